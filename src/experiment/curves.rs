//! Learning curves across seeds: smoothing, interpolation onto a common grid of
//! transitions, and mean / min / max / std per grid point (the paper's Fig. 5 shows a mean
//! curve with a band over 5 seeds).

use crate::train::plot::BandCurve;
use crate::train::MetricsRow;

/// The success-rate curve of one run: `(transitions, success)` per update that finished
/// episodes, smoothed by a trailing mean over `window` such points (1: no smoothing).
pub fn success_curve(rows: &[MetricsRow], window: usize) -> Vec<(f64, f64)> {
    let raw: Vec<(f64, f64)> = rows
        .iter()
        .filter_map(|r| r.stats.success_rate.map(|s| (r.global_step as f64, s)))
        .collect();
    let w = window.max(1);
    (0..raw.len())
        .map(|i| {
            let lo = (i + 1).saturating_sub(w);
            let tail = &raw[lo..=i];
            (
                raw[i].0,
                tail.iter().map(|p| p.1).sum::<f64>() / tail.len() as f64,
            )
        })
        .collect()
}

/// `curve` (x ascending) linearly interpolated at `x`, held constant beyond its ends;
/// `None` for an empty curve.
pub fn interpolate(curve: &[(f64, f64)], x: f64) -> Option<f64> {
    let first = curve.first()?;
    let last = curve.last()?;
    if x <= first.0 {
        return Some(first.1);
    }
    if x >= last.0 {
        return Some(last.1);
    }
    let k = curve.partition_point(|p| p.0 <= x);
    let (a, b) = (curve[k - 1], curve[k]);
    if b.0 - a.0 <= 0.0 {
        return Some(b.1);
    }
    Some(a.1 + (x - a.0) / (b.0 - a.0) * (b.1 - a.1))
}

/// Mean and sample standard deviation (n - 1; 0 for a single value); `None` when empty.
pub fn mean_std(v: &[f64]) -> Option<(f64, f64)> {
    if v.is_empty() {
        return None;
    }
    let n = v.len() as f64;
    let mean = v.iter().sum::<f64>() / n;
    if v.len() == 1 {
        return Some((mean, 0.0));
    }
    let var = v.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>() / (n - 1.0);
    Some((mean, var.sqrt()))
}

/// How the band around the mean is drawn.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Deserialize, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Band {
    /// From the lowest to the highest seed.
    MinMax,
    /// Mean plus or minus one sample standard deviation.
    Std,
}

/// Aggregates the curves of several seeds: the grid is the x values of all curves up to
/// the shortest curve's end (every seed has data there), and each seed is interpolated at
/// each grid point. Curves without points are ignored; `None` when none is left.
pub fn aggregate(label: &str, curves: &[Vec<(f64, f64)>], band: Band) -> Option<BandCurve> {
    let curves: Vec<&Vec<(f64, f64)>> = curves.iter().filter(|c| !c.is_empty()).collect();
    let end = curves
        .iter()
        .filter_map(|c| c.last().map(|p| p.0))
        .fold(f64::INFINITY, f64::min);
    if curves.is_empty() || !end.is_finite() {
        return None;
    }
    let mut grid: Vec<f64> = curves
        .iter()
        .flat_map(|c| c.iter().map(|p| p.0))
        .filter(|x| *x <= end)
        .collect();
    grid.sort_by(f64::total_cmp);
    grid.dedup();
    let points = grid
        .into_iter()
        .filter_map(|x| {
            let ys: Vec<f64> = curves.iter().filter_map(|c| interpolate(c, x)).collect();
            let (mean, std) = mean_std(&ys)?;
            let (lo, hi) = match band {
                Band::MinMax => (
                    ys.iter().copied().fold(f64::INFINITY, f64::min),
                    ys.iter().copied().fold(f64::NEG_INFINITY, f64::max),
                ),
                Band::Std => (mean - std, mean + std),
            };
            Some((x, mean, lo, hi))
        })
        .collect();
    Some(BandCurve {
        label: label.to_string(),
        points,
    })
}

/// The final training success of one run: the mean success rate of the last `window`
/// updates that finished episodes; `None` without any.
pub fn final_success(rows: &[MetricsRow], window: usize) -> Option<f64> {
    let v: Vec<f64> = rows.iter().filter_map(|r| r.stats.success_rate).collect();
    let tail = &v[v.len().saturating_sub(window.max(1))..];
    mean_std(tail).map(|m| m.0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ppo::UpdateStats;

    fn row(step: u64, s: Option<f64>) -> MetricsRow {
        MetricsRow {
            update: step,
            global_step: step,
            episodes: step,
            stats: UpdateStats {
                success_rate: s,
                ..UpdateStats::default()
            },
            curriculum_level: None,
            transitions_per_s: 1.0,
            wall_s: 1.0,
            physics_failures: 0,
        }
    }

    #[test]
    fn smoothing_is_a_trailing_mean_over_rows_with_success() {
        let rows = [
            row(10, Some(0.0)),
            row(20, None),
            row(30, Some(1.0)),
            row(40, Some(0.5)),
        ];
        assert_eq!(
            success_curve(&rows, 2),
            vec![(10.0, 0.0), (30.0, 0.5), (40.0, 0.75)]
        );
        assert_eq!(success_curve(&rows, 1)[2], (40.0, 0.5));
        assert_eq!(final_success(&rows, 2), Some(0.75));
        assert_eq!(final_success(&rows, 100), Some(0.5));
        assert_eq!(final_success(&[row(1, None)], 3), None);
    }

    #[test]
    fn interpolation_is_linear_and_clamped() {
        let c = [(0.0, 0.0), (10.0, 1.0), (20.0, 0.0)];
        assert_eq!(interpolate(&c, 5.0), Some(0.5));
        assert_eq!(interpolate(&c, 15.0), Some(0.5));
        assert_eq!(interpolate(&c, 10.0), Some(1.0));
        assert_eq!(interpolate(&c, -3.0), Some(0.0));
        assert_eq!(interpolate(&c, 99.0), Some(0.0));
        assert_eq!(interpolate(&[], 1.0), None);
    }

    #[test]
    fn mean_and_sample_std() {
        // 1, 2, 3, 4: mean 2.5, sample variance (2.25 + 0.25 + 0.25 + 2.25) / 3 = 5/3.
        let (m, s) = mean_std(&[1.0, 2.0, 3.0, 4.0]).unwrap();
        assert_eq!(m, 2.5);
        assert!((s - (5.0f64 / 3.0).sqrt()).abs() < 1e-12);
        assert_eq!(mean_std(&[7.0]), Some((7.0, 0.0)));
        assert_eq!(mean_std(&[]), None);
    }

    #[test]
    fn aggregation_on_the_common_grid() {
        // Seed A: 0 at 0, 1 at 10, 1 at 20. Seed B: 0.5 at 5, 0.5 at 15 (ends at 15).
        let a = vec![(0.0, 0.0), (10.0, 1.0), (20.0, 1.0)];
        let b = vec![(5.0, 0.5), (15.0, 0.5)];
        let c = aggregate("v", &[a.clone(), b.clone(), vec![]], Band::MinMax).unwrap();
        let xs: Vec<f64> = c.points.iter().map(|p| p.0).collect();
        assert_eq!(xs, [0.0, 5.0, 10.0, 15.0]);
        // At 5: A = 0.5, B = 0.5. At 10: A = 1, B = 0.5 -> mean 0.75, band 0.5..1.
        assert_eq!(c.points[1], (5.0, 0.5, 0.5, 0.5));
        assert_eq!(c.points[2], (10.0, 0.75, 0.5, 1.0));
        let s = aggregate("v", &[a, b], Band::Std).unwrap();
        // std of {1, 0.5} = sqrt(0.125).
        let half = 0.125f64.sqrt();
        assert!((s.points[2].2 - (0.75 - half)).abs() < 1e-12);
        assert!((s.points[2].3 - (0.75 + half)).abs() < 1e-12);
        assert!(aggregate("v", &[vec![]], Band::MinMax).is_none());
    }
}
