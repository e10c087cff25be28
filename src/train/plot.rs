//! The learning-curve plots, SVG drawn with plotters: one run's success rate (with the
//! curriculum level) and episode return against environment transitions
//! ([`learning_curve_svg`]), and the paper's Fig.-5 style comparison of variants, each a
//! mean curve over seeds with a shaded band ([`band_plot_svg`]).

use super::metrics::MetricsRow;
use super::TrainError;
use plotters::prelude::*;
use std::path::Path;

/// (min, max) of `v`, widened when empty or flat.
fn range(v: impl Iterator<Item = f64>) -> (f64, f64) {
    let (lo, hi) = v.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
        (a.min(x), b.max(x))
    });
    if !lo.is_finite() || !hi.is_finite() {
        return (0.0, 1.0);
    }
    if hi - lo < 1e-9 {
        return (lo - 0.5, hi + 0.5);
    }
    let pad = 0.05 * (hi - lo);
    (lo - pad, hi + pad)
}

/// One line of a panel: label, colour, points.
type Series<'a> = (&'a str, RGBColor, Vec<(f64, f64)>);

type DrawResult = Result<(), Box<dyn std::error::Error>>;

fn panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, plotters::coord::Shift>,
    title: &str,
    y_desc: &str,
    x_max: f64,
    y: (f64, f64),
    series: &[Series<'_>],
) -> DrawResult
where
    DB::ErrorType: 'static,
{
    let mut chart = ChartBuilder::on(area)
        .caption(title, ("sans-serif", 18))
        .margin(12)
        .x_label_area_size(36)
        .y_label_area_size(56)
        .build_cartesian_2d(0f64..x_max, y.0..y.1)?;
    chart
        .configure_mesh()
        .x_desc("transitions")
        .y_desc(y_desc)
        .draw()?;
    for (label, color, pts) in series {
        let c = *color;
        chart
            .draw_series(LineSeries::new(pts.iter().copied(), c.stroke_width(2)))?
            .label(*label)
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], c));
    }
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .draw()?;
    Ok(())
}

/// Renders the curve of `rows` as SVG text. With success rates (the grasp environment) the
/// image has two panels, success/curriculum on top and return below; otherwise only the
/// return panel.
pub fn learning_curve_svg(title: &str, rows: &[MetricsRow]) -> Result<String, String> {
    let pts = |f: fn(&MetricsRow) -> Option<f64>| -> Vec<(f64, f64)> {
        rows.iter()
            .filter_map(|r| f(r).map(|v| (r.global_step as f64, v)))
            .collect()
    };
    let success = pts(|r| r.stats.success_rate);
    let curriculum = pts(|r| r.curriculum_level);
    let ret = pts(|r| r.stats.episode_return);
    let x_max = rows.last().map_or(1.0, |r| r.global_step.max(1) as f64);
    let has_success = !success.is_empty();
    let height = if has_success { 720 } else { 380 };
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (900, height)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| e.to_string())?;
        let ret_area = if has_success {
            let (top, bottom) = root.split_vertically(height / 2);
            let mut s = vec![("success rate", RGBColor(31, 119, 180), success)];
            if !curriculum.is_empty() {
                s.push(("curriculum r_s", RGBColor(255, 127, 14), curriculum));
            }
            panel(
                &top,
                &format!("{title}: success"),
                "rate",
                x_max,
                (0.0, 1.0),
                &s,
            )
            .map_err(|e| e.to_string())?;
            bottom
        } else {
            root.clone()
        };
        let y = range(ret.iter().map(|p| p.1));
        panel(
            &ret_area,
            &format!("{title}: episode return"),
            "return",
            x_max,
            y,
            &[("mean return", RGBColor(44, 160, 44), ret)],
        )
        .map_err(|e| e.to_string())?;
        root.present().map_err(|e| e.to_string())?;
    }
    Ok(svg)
}

/// Draws the curve of `rows` to `path` (written atomically).
pub fn write_learning_curve(
    path: &Path,
    title: &str,
    rows: &[MetricsRow],
) -> Result<(), TrainError> {
    let svg = learning_curve_svg(title, rows).map_err(|message| TrainError::Plot {
        path: path.to_path_buf(),
        message,
    })?;
    crate::util::fsx::write_atomic(path, svg.as_bytes())?;
    Ok(())
}

/// One variant of a band plot: a mean curve with a band (min-max or +-std across seeds).
#[derive(Debug, Clone, PartialEq)]
pub struct BandCurve {
    /// Legend label.
    pub label: String,
    /// Points `(x, mean, low, high)`, x ascending.
    pub points: Vec<(f64, f64, f64, f64)>,
}

/// Colours of the variants (and of the agents in [`crate::eval::plot`]), in order
/// (matplotlib's tab10).
pub const PALETTE: [RGBColor; 10] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
    RGBColor(188, 189, 34),
    RGBColor(23, 190, 207),
];

/// Renders curves in the style of the paper's Fig. 5 as SVG text: `y_desc` (e.g. the
/// success rate, in [0, 1]) against transitions, one colour per variant, the band shaded
/// under the mean line.
pub fn band_plot_svg(title: &str, y_desc: &str, curves: &[BandCurve]) -> Result<String, String> {
    let x_max = curves
        .iter()
        .flat_map(|c| c.points.iter().map(|p| p.0))
        .fold(1.0f64, f64::max);
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (900, 520)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| e.to_string())?;
        let draw = || -> DrawResult {
            let mut chart = ChartBuilder::on(&root)
                .caption(title, ("sans-serif", 20))
                .margin(14)
                .x_label_area_size(40)
                .y_label_area_size(56)
                .build_cartesian_2d(0f64..x_max, 0f64..1f64)?;
            chart
                .configure_mesh()
                .x_desc("transitions")
                .y_desc(y_desc)
                .draw()?;
            for (k, c) in curves.iter().enumerate() {
                let colour = PALETTE[k % PALETTE.len()];
                if c.points.len() >= 2 {
                    let mut outline: Vec<(f64, f64)> = c
                        .points
                        .iter()
                        .map(|p| (p.0, p.3.clamp(0.0, 1.0)))
                        .collect();
                    outline.extend(c.points.iter().rev().map(|p| (p.0, p.2.clamp(0.0, 1.0))));
                    chart.draw_series(std::iter::once(Polygon::new(
                        outline,
                        colour.mix(0.18).filled(),
                    )))?;
                }
                chart
                    .draw_series(LineSeries::new(
                        c.points.iter().map(|p| (p.0, p.1)),
                        colour.stroke_width(2),
                    ))?
                    .label(c.label.as_str())
                    .legend(move |(x, y)| {
                        PathElement::new(vec![(x, y), (x + 18, y)], colour.stroke_width(2))
                    });
            }
            chart
                .configure_series_labels()
                .position(SeriesLabelPosition::LowerRight)
                .background_style(WHITE.mix(0.85))
                .border_style(BLACK)
                .draw()?;
            Ok(())
        };
        draw().map_err(|e| e.to_string())?;
        root.present().map_err(|e| e.to_string())?;
    }
    Ok(svg)
}

/// Draws [`band_plot_svg`] to `path` (written atomically).
pub fn write_band_plot(
    path: &Path,
    title: &str,
    y_desc: &str,
    curves: &[BandCurve],
) -> Result<(), TrainError> {
    let svg = band_plot_svg(title, y_desc, curves).map_err(|message| TrainError::Plot {
        path: path.to_path_buf(),
        message,
    })?;
    crate::util::fsx::write_atomic(path, svg.as_bytes())?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ppo::UpdateStats;

    fn row(update: u64, success: Option<f64>, ret: f64) -> MetricsRow {
        MetricsRow {
            update,
            global_step: update * 100,
            episodes: update,
            stats: UpdateStats {
                success_rate: success,
                episode_return: Some(ret),
                episode_length: Some(ret),
                ..UpdateStats::default()
            },
            curriculum_level: success,
            transitions_per_s: 1.0,
            wall_s: 1.0,
            physics_failures: 0,
        }
    }

    #[test]
    fn svg_has_one_or_two_panels() {
        let rows: Vec<_> = (1..5).map(|u| row(u, None, u as f64)).collect();
        let svg = learning_curve_svg("cp", &rows).unwrap();
        assert!(svg.starts_with("<svg") && svg.contains("cp: episode return"));
        assert!(!svg.contains("cp: success"));
        let rows: Vec<_> = (1..5).map(|u| row(u, Some(0.25), 1.0)).collect();
        let svg = learning_curve_svg("g", &rows).unwrap();
        assert!(svg.contains("g: success") && svg.contains("curriculum r_s"));
        assert!(learning_curve_svg("empty", &[]).is_ok());
    }

    #[test]
    fn band_plot_draws_a_band_and_a_line_per_variant() {
        let curve = |label: &str, y: f64| BandCurve {
            label: label.into(),
            points: (0..5)
                .map(|k| (1000.0 * k as f64, y, y - 0.1, y + 0.1))
                .collect(),
        };
        let svg = band_plot_svg(
            "Fig. 5a",
            "success rate",
            &[curve("GRU-M1PCA5", 0.3), curve("GRU-M3PCA5", 0.6)],
        )
        .unwrap();
        assert!(svg.starts_with("<svg") && svg.contains("Fig. 5a"));
        assert!(svg.contains("GRU-M1PCA5") && svg.contains("GRU-M3PCA5"));
        // Two filled bands (polygons) with the palette's first two colours.
        assert_eq!(svg.matches("<polygon").count(), 2, "{svg}");
        assert!(svg.contains("#1F77B4") || svg.contains("#1f77b4"));
        // A single point draws no band, and no curves at all is fine.
        let one = BandCurve {
            label: "x".into(),
            points: vec![(1.0, 0.5, 0.5, 0.5)],
        };
        assert!(!band_plot_svg("t", "y", &[one])
            .unwrap()
            .contains("<polygon"));
        assert!(band_plot_svg("t", "y", &[]).is_ok());
    }

    #[test]
    fn range_pads_and_handles_degenerate_input() {
        assert_eq!(range([].into_iter()), (0.0, 1.0));
        assert_eq!(range([2.0].into_iter()), (1.5, 2.5));
        let (lo, hi) = range([0.0, 10.0].into_iter());
        assert!((lo + 0.5).abs() < 1e-12 && (hi - 10.5).abs() < 1e-12);
    }
}
