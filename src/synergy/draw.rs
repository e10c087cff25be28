//! Pictures of the synergies: each of the first components drawn as hand postures at a
//! few amplitudes, like Fig. 2b of the paper.
//!
//! Component k at amplitude `a` (in standard deviations) is the posture
//! `P^-1(a sqrt(lambda_k) e_k)` (the mean posture moved `a` standard deviations along
//! component k), made feasible with [`project_feasible`]. Postures are drawn as stick
//! figures from the forward kinematics of a [`Robot`] in the palm frame, in two views
//! side by side: the palm-side view (looking at the palm along +y: x to the right, z up)
//! and the side view (looking along -x: y to the right, z up). The SVG is plain text
//! written here, with one `<g id="Ck">` group per component row.

use crate::robot::joints::FINGERS;
use crate::robot::Robot;
use crate::synergy::map::project_feasible;
use crate::synergy::pca::SynergyModel;
use crate::synergy::N_FINGER_JOINTS;
use nalgebra::Point3;
use std::fmt::Write as _;

const D: usize = N_FINGER_JOINTS;

/// The amplitudes (standard deviations) of the figure's columns.
pub const SIGMA_STEPS: [f64; 5] = [-2.0, -1.0, 0.0, 1.0, 2.0];

/// How many components the figure shows at most (Fig. 2b shows three).
pub const FIGURE_COMPONENTS: usize = 3;

/// Error while drawing synergies.
#[derive(Debug, thiserror::Error)]
pub enum DrawError {
    /// The robot model lacks a hand link the stick figure needs.
    #[error("robot '{robot}' has no hand link '{link}' (needed for the stick figure)")]
    MissingLink {
        /// The robot's name.
        robot: String,
        /// The missing link (without side prefix).
        link: &'static str,
    },
}

/// The feasible posture of component `k` (0-based) at `sigmas` standard deviations
/// (`sqrt(eigenvalue_k)`) from the mean.
///
/// # Panics
/// If `k >= model.n_components()`.
pub fn synergy_posture(
    model: &SynergyModel,
    k: usize,
    sigmas: f64,
    limits: &[(f64, f64); D],
) -> [f64; D] {
    let mut eps = [0.0; D];
    eps[k] = sigmas * model.eigenvalues()[k].sqrt();
    let mut t = model.reconstruct(&eps[..model.n_components()]);
    project_feasible(&mut t, limits);
    t
}

/// For component `k`, the range (min, max) each joint spans over the postures at
/// [`SIGMA_STEPS`] (so from -2 to +2 standard deviations, after feasibility).
pub fn joint_ranges(model: &SynergyModel, k: usize, limits: &[(f64, f64); D]) -> [(f64, f64); D] {
    let mut out = [(f64::INFINITY, f64::NEG_INFINITY); D];
    for s in SIGMA_STEPS {
        let t = synergy_posture(model, k, s, limits);
        for (o, v) in out.iter_mut().zip(t) {
            o.0 = o.0.min(v);
            o.1 = o.1.max(v);
        }
    }
    out
}

/// A hand posture as points in the palm frame (metres).
#[derive(Debug, Clone, PartialEq)]
pub struct Skeleton {
    /// Outline of the palm: base of the FF side, the four knuckles, the LF metacarpal
    /// joint, base of the LF side.
    pub palm: Vec<Point3<f64>>,
    /// One polyline per finger in [`FINGERS`] order, from the knuckle (or the LF
    /// metacarpal, the thumb base) to the tip.
    pub chains: [Vec<Point3<f64>>; 5],
}

const CHAINS: [&[&str]; 5] = [
    &["ffknuckle", "ffmiddle", "ffdistal", "fftip"],
    &["mfknuckle", "mfmiddle", "mfdistal", "mftip"],
    &["rfknuckle", "rfmiddle", "rfdistal", "rftip"],
    &["lfmetacarpal", "lfknuckle", "lfmiddle", "lfdistal", "lftip"],
    &["thbase", "thhub", "thdistal", "thtip"],
];

/// The stick figure of finger posture `fingers` (wrist joints at zero) from `robot`'s
/// forward kinematics.
pub fn skeleton(robot: &Robot, fingers: &[f64; D]) -> Result<Skeleton, DrawError> {
    let mut hand = [0.0; 24];
    hand[2..].copy_from_slice(fingers);
    let poses = robot.hand_fk_palm(&hand);
    let at = |link: &'static str| -> Result<Point3<f64>, DrawError> {
        robot
            .hand_link(link)
            .and_then(|i| poses.get(i))
            .map(|p| Point3::from(p.translation.vector))
            .ok_or_else(|| DrawError::MissingLink {
                robot: robot.name.clone(),
                link,
            })
    };
    let mut chains: [Vec<Point3<f64>>; 5] = Default::default();
    for (chain, names) in chains.iter_mut().zip(CHAINS) {
        for n in names {
            chain.push(at(n)?);
        }
    }
    let ff = at("ffknuckle")?;
    let lfm = at("lfmetacarpal")?;
    let palm = vec![
        Point3::new(ff.x, 0.0, 0.0),
        ff,
        at("mfknuckle")?,
        at("rfknuckle")?,
        at("lfknuckle")?,
        lfm,
        Point3::new(lfm.x, 0.0, 0.0),
    ];
    Ok(Skeleton { palm, chains })
}

const COLOURS: [&str; 5] = ["#d62728", "#ff7f0e", "#2ca02c", "#1f77b4", "#9467bd"];
const SCALE: f64 = 650.0; // pixels per metre
const PAD: f64 = 6.0;

/// Screen coordinates of a palm-frame point in view `v` (0: palm side, 1: side).
fn view(p: &Point3<f64>, v: usize) -> (f64, f64) {
    if v == 0 {
        (p.x, -p.z)
    } else {
        (p.y, -p.z)
    }
}

/// The figure of the first (up to three) synergies of `model` as SVG text: one row per
/// component, one column per amplitude of [`SIGMA_STEPS`], each cell a palm-side and a
/// side view of the hand of `robot`.
pub fn synergies_svg(
    robot: &Robot,
    model: &SynergyModel,
    limits: &[(f64, f64); D],
) -> Result<String, DrawError> {
    let rows = model.n_components().min(FIGURE_COMPONENTS);
    let mut figures = Vec::with_capacity(rows);
    for k in 0..rows {
        let mut row = Vec::with_capacity(SIGMA_STEPS.len());
        for s in SIGMA_STEPS {
            row.push(skeleton(robot, &synergy_posture(model, k, s, limits))?);
        }
        figures.push(row);
    }

    // Common bounds of each view over all postures, so every cell has the same scale.
    let mut lo = [(f64::INFINITY, f64::INFINITY); 2];
    let mut hi = [(f64::NEG_INFINITY, f64::NEG_INFINITY); 2];
    for sk in figures.iter().flatten() {
        for p in sk.chains.iter().flatten().chain(&sk.palm) {
            for v in 0..2 {
                let (x, y) = view(p, v);
                lo[v] = (lo[v].0.min(x), lo[v].1.min(y));
                hi[v] = (hi[v].0.max(x), hi[v].1.max(y));
            }
        }
    }
    let w = [0, 1].map(|v| (hi[v].0 - lo[v].0) * SCALE + 2.0 * PAD);
    let h = (0..2)
        .map(|v| (hi[v].1 - lo[v].1) * SCALE + 2.0 * PAD)
        .fold(0.0, f64::max);
    let (left, top, gap_x, gap_y) = (110.0, 62.0, 16.0, 22.0);
    let cell_w = w[0] + w[1];
    let width = left + SIGMA_STEPS.len() as f64 * (cell_w + gap_x) + 10.0;
    let height = top + rows as f64 * (h + gap_y) + 30.0;

    let mut s = String::new();
    let _ = writeln!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{width:.0}" height="{height:.0}" viewBox="0 0 {width:.1} {height:.1}" font-family="sans-serif" font-size="12">"#
    );
    let _ = writeln!(s, r#"<rect width="100%" height="100%" fill="white"/>"#);
    let title = format!(
        "Hand synergies C1-C{rows} ({} samples{}): mean posture \u{b1} k \u{3c3} along each component",
        model.n_samples(),
        if model.source().is_empty() {
            String::new()
        } else {
            format!(", {}", model.source())
        }
    );
    let _ = writeln!(
        s,
        r#"<text x="10" y="20" font-size="14" font-weight="bold">{}</text>"#,
        xml_escape(&title)
    );
    for (c, a) in SIGMA_STEPS.iter().enumerate() {
        let x = left + c as f64 * (cell_w + gap_x) + cell_w / 2.0;
        let label = if *a == 0.0 {
            "mean".to_string()
        } else {
            format!("{a:+}\u{3c3}")
        };
        let _ = writeln!(
            s,
            r#"<text x="{x:.1}" y="42" text-anchor="middle" font-weight="bold">{label}</text>"#
        );
        for (v, name) in ["palm side", "side"].iter().enumerate() {
            let xv = left
                + c as f64 * (cell_w + gap_x)
                + if v == 0 {
                    w[0] / 2.0
                } else {
                    w[0] + w[1] / 2.0
                };
            let _ = writeln!(
                s,
                r##"<text x="{xv:.1}" y="56" text-anchor="middle" font-size="9" fill="#666">{name}</text>"##
            );
        }
    }
    for (k, row) in figures.iter().enumerate() {
        let y0 = top + k as f64 * (h + gap_y);
        let _ = writeln!(s, r#"<g id="C{}">"#, k + 1);
        let _ = writeln!(
            s,
            r#"<text x="10" y="{:.1}" font-size="16" font-weight="bold">C{}</text>"#,
            y0 + h / 2.0 - 8.0,
            k + 1
        );
        let _ = writeln!(
            s,
            r#"<text x="10" y="{:.1}" font-size="10">λ = {:.3e}</text>"#,
            y0 + h / 2.0 + 8.0,
            model.eigenvalues()[k]
        );
        let _ = writeln!(
            s,
            r#"<text x="10" y="{:.1}" font-size="10">{:.1} % of variance</text>"#,
            y0 + h / 2.0 + 22.0,
            100.0 * model.explained_variance_ratio()[k]
        );
        for (c, sk) in row.iter().enumerate() {
            let x0 = left + c as f64 * (cell_w + gap_x);
            for v in 0..2 {
                let ox = x0 + if v == 0 { 0.0 } else { w[0] };
                let map = |p: &Point3<f64>| {
                    let (x, y) = view(p, v);
                    (
                        ox + PAD + (x - lo[v].0) * SCALE,
                        y0 + PAD + (y - lo[v].1) * SCALE,
                    )
                };
                let _ = writeln!(
                    s,
                    r##"<rect x="{ox:.1}" y="{y0:.1}" width="{:.1}" height="{h:.1}" fill="none" stroke="#ddd"/>"##,
                    w[v]
                );
                let _ = writeln!(
                    s,
                    r##"<polygon points="{}" fill="#e8e8e8" stroke="#888" stroke-width="1"/>"##,
                    points(sk.palm.iter().map(map))
                );
                for (f, chain) in sk.chains.iter().enumerate() {
                    let _ = writeln!(
                        s,
                        r#"<polyline class="{}" points="{}" fill="none" stroke="{}" stroke-width="2.5" stroke-linecap="round" stroke-linejoin="round"/>"#,
                        FINGERS[f],
                        points(chain.iter().map(map)),
                        COLOURS[f]
                    );
                    for p in &chain[..chain.len() - 1] {
                        let (x, y) = map(p);
                        let _ = writeln!(
                            s,
                            r##"<circle cx="{x:.1}" cy="{y:.1}" r="1.8" fill="#333"/>"##
                        );
                    }
                }
            }
        }
        let _ = writeln!(s, "</g>");
    }
    let ly = height - 12.0;
    for (f, name) in FINGERS.iter().enumerate() {
        let x = 10.0 + f as f64 * 60.0;
        let _ = writeln!(
            s,
            r#"<line x1="{x:.1}" y1="{:.1}" x2="{:.1}" y2="{:.1}" stroke="{}" stroke-width="3"/><text x="{:.1}" y="{ly:.1}">{name}</text>"#,
            ly - 4.0,
            x + 18.0,
            ly - 4.0,
            COLOURS[f],
            x + 22.0
        );
    }
    s.push_str("</svg>\n");
    Ok(s)
}

fn points(it: impl Iterator<Item = (f64, f64)>) -> String {
    let mut s = String::new();
    for (x, y) in it {
        let _ = write!(s, "{x:.1},{y:.1} ");
    }
    s.trim_end().to_string()
}

fn xml_escape(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            c => out.push(c),
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::robot::Side;
    use crate::synergy::finger_limits;
    use crate::synergy::pca::tests::{base_posture, directions, known_rows};
    use approx::assert_relative_eq;

    fn model() -> SynergyModel {
        SynergyModel::fit(&known_rows(), 3).unwrap()
    }

    #[test]
    fn postures_move_sigma_along_the_component() {
        // lambda_1 = 0.06 (see pca tests), so +1 sigma moves sqrt(0.06) along u.
        let m = model();
        let limits = finger_limits(Side::Left);
        let (u, _) = directions();
        let t = synergy_posture(&m, 0, 1.0, &limits);
        for j in 0..22 {
            assert_relative_eq!(
                t[j],
                base_posture()[j] + 0.06f64.sqrt() * u[j],
                epsilon = 1e-12
            );
        }
        assert_eq!(synergy_posture(&m, 0, 0.0, &limits), *m.mean());
        let r = joint_ranges(&m, 0, &limits);
        // FFJ3 = 0.5 + a sqrt(0.06) * 3/sqrt(26) for a in -2..2.
        let amp = 2.0 * 0.06f64.sqrt() * 3.0 / 26f64.sqrt();
        assert_relative_eq!(r[1].0, 0.5 - amp, epsilon = 1e-12);
        assert_relative_eq!(r[1].1, 0.5 + amp, epsilon = 1e-12);
        assert_eq!(r[0], (0.0, 0.0)); // FFJ4 does not move in C1
    }

    #[test]
    fn skeleton_of_the_flat_hand_matches_the_joint_table() {
        let robot = Robot::builtin(Side::Left);
        let sk = skeleton(&robot, &[0.0; 22]).unwrap();
        // Left hand: FF knuckle at x = -0.033, z = 0.095; the finger is straight along z:
        // tip at 0.095 + 0.045 + 0.025 + 0.026 = 0.191.
        let ff = &sk.chains[0];
        assert_relative_eq!(ff[0].x, -0.033, epsilon = 1e-9);
        assert_relative_eq!(ff[0].z, 0.095, epsilon = 1e-9);
        assert_relative_eq!(ff[3].z, 0.191, epsilon = 1e-9);
        assert_relative_eq!(ff[3].x, -0.033, epsilon = 1e-9);
        assert_eq!(sk.palm.len(), 7);
        assert_eq!(sk.chains[3].len(), 5);
    }

    #[test]
    fn flexing_ffj3_moves_the_ff_tip_to_the_palm_side() {
        let robot = Robot::builtin(Side::Left);
        let mut q = [0.0; 22];
        q[1] = std::f64::consts::FRAC_PI_2; // FFJ3 at 90 degrees
        let sk = skeleton(&robot, &q).unwrap();
        let tip = sk.chains[0][3];
        // The finger points along -y (the palm faces -y) at the knuckle's height.
        assert_relative_eq!(tip.z, 0.095, epsilon = 1e-6);
        assert_relative_eq!(tip.y, -0.096, epsilon = 1e-6);
    }

    #[test]
    fn svg_has_one_group_per_row_and_every_cell() {
        let robot = Robot::builtin(Side::Left);
        let svg = synergies_svg(
            &robot,
            &model().with_source("a<b"),
            &finger_limits(Side::Left),
        )
        .unwrap();
        assert!(svg.starts_with("<svg"));
        assert!(svg.trim_end().ends_with("</svg>"));
        for k in 1..=3 {
            assert!(svg.contains(&format!("<g id=\"C{k}\">")), "C{k}");
        }
        // 3 rows x 5 amplitudes x 2 views x 5 fingers polylines.
        assert_eq!(svg.matches("<polyline").count(), 150);
        assert!(svg.contains("a&lt;b"));
        assert!(!svg.contains("NaN"));
    }
}
