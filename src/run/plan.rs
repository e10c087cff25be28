//! Planning a grasp attempt ([`plan_grasp`]): a two-finger grasp is given (a grasp file,
//! see [`load_grasp_file`], or the command line) or sampled on a point cloud with the
//! antipodal sampler ([`grasp_candidates`]); it is mapped to the hand ([`root_pose_for`]:
//! C-shape preshape, grasp point between the thumb and little-finger tips, x = -palm
//! normal, y along thumb-little finger), and the UR10e IK is solved for the pre-grasp pose
//! (the grasp pose moved back along the approach by `pregrasp_offset_m`) and the grasp
//! pose. A given grasp the arm cannot reach is an error; cloud candidates are tried best
//! first until one is reachable. [`super::pipeline`] runs the attempt the plan starts.

use super::pipeline::PipelineConfig;
use super::RunError;
use crate::perception::pointcloud::{grasp_candidates, principal_axis_grasp};
use crate::perception::pregrasp::{snap_top_down, PlannedGrasp};
use crate::robot::grasp_map::{root_pose_for, TwoFingerGrasp};
use crate::robot::joints::N_JOINTS;
use crate::robot::{ur10e, Robot};
use nalgebra::{Isometry3, Point3, Translation3, Vector3};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// A two-finger grasp as written in a grasp file (TOML or JSON, world frame, metres):
/// `center = [x, y, z]`, `closing = [x, y, z]` (the direction joining the fingers) and
/// optionally `approach = [x, y, z]` (default straight down, `[0, 0, -1]`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GraspFile {
    /// Grasp centre (m).
    pub center: [f64; 3],
    /// Approach direction.
    #[serde(default = "down")]
    pub approach: [f64; 3],
    /// Closing direction.
    pub closing: [f64; 3],
}

fn down() -> [f64; 3] {
    [0.0, 0.0, -1.0]
}

impl GraspFile {
    /// The grasp, checked: finite, non-degenerate directions.
    pub fn grasp(&self) -> Result<TwoFingerGrasp, RunError> {
        let g = TwoFingerGrasp {
            center: Point3::from(self.center),
            approach: Vector3::from(self.approach),
            closing: Vector3::from(self.closing),
        };
        g.frame().map_err(|e| RunError::BadGrasp(e.to_string()))?;
        Ok(g)
    }
}

/// Reads a grasp file: JSON when the name ends in `.json`, TOML otherwise. Errors name
/// the file and the field (with line and column).
pub fn load_grasp_file(path: &Path) -> Result<TwoFingerGrasp, RunError> {
    let err = |detail: String| RunError::GraspFile {
        path: path.to_path_buf(),
        detail,
    };
    let text = crate::util::fsx::read_to_string_bounded(path, crate::util::fsx::limits::CONFIG)
        .map_err(|e| err(format!("cannot read: {e}")))?;
    let is_json = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("json"));
    let f: GraspFile = if is_json {
        serde_json::from_str(&text).map_err(|e| err(e.to_string()))?
    } else {
        crate::util::config::parse_toml(path, &text).map_err(|e| err(e.to_string()))?
    };
    f.grasp().map_err(|e| err(e.to_string()))
}

/// Where the grasp comes from.
#[derive(Debug, Clone, PartialEq)]
pub enum GraspSource {
    /// A given two-finger grasp.
    Given(TwoFingerGrasp),
    /// A point cloud of the object (world frame, m) to sample candidates on.
    Cloud(Vec<Point3<f64>>),
}

/// A planned grasp: the two-finger grasp, the hand preshape and the arm configurations.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct GraspPlan {
    /// Grasp centre (m, world).
    pub center: [f64; 3],
    /// Approach direction (unit).
    pub approach: [f64; 3],
    /// Closing direction (unit).
    pub closing: [f64; 3],
    /// The candidate's score (cloud grasps only).
    pub score: Option<f64>,
    /// Candidates found on the cloud (0 for a given grasp).
    pub candidates: usize,
    /// Candidates skipped before this one (not top-down, unreachable).
    pub skipped: usize,
    /// Whether no antipodal candidate was usable and the grasp closes across the cloud's
    /// narrowest horizontal extent instead ([`principal_axis_grasp`]).
    pub fallback: bool,
    /// The hand preshape (24 angles, paper order).
    pub preshape: [f64; N_JOINTS],
    /// UR10e joints at the pre-grasp pose.
    pub pregrasp_q: [f64; 6],
    /// UR10e joints at the grasp pose.
    pub grasp_q: [f64; 6],
}

impl GraspPlan {
    /// The two-finger grasp of the plan.
    pub fn grasp(&self) -> TwoFingerGrasp {
        TwoFingerGrasp {
            center: Point3::from(self.center),
            approach: Vector3::from(self.approach),
            closing: Vector3::from(self.closing),
        }
    }
}

/// Arm configurations for `grasp` with the hand in `preshape`: (pre-grasp, grasp).
fn solve_arm(
    robot: &Robot,
    preshape: &[f64; 24],
    grasp: &TwoFingerGrasp,
    cfg: &PipelineConfig,
) -> Result<([f64; 6], [f64; 6]), RunError> {
    let root =
        root_pose_for(robot, preshape, grasp).map_err(|e| RunError::BadGrasp(e.to_string()))?;
    let base_inv = cfg.arm_base.pose().inverse();
    let back = -grasp.approach.normalize() * cfg.pregrasp_offset_m;
    check_above_table(robot, preshape, grasp, &back)?;
    let pre = Isometry3::from_parts(
        Translation3::from(root.translation.vector + back),
        root.rotation,
    );
    let c = grasp.center;
    let ik_err = |stage, source| RunError::Ik {
        stage,
        x: c.x,
        y: c.y,
        z: c.z,
        source,
    };
    let q_pre = ur10e::ik(&(base_inv * pre), &ur10e::HOME).map_err(|e| ik_err("pre-grasp", e))?;
    let q_grasp = ur10e::ik(&(base_inv * root), &q_pre).map_err(|e| ik_err("grasp", e))?;
    Ok((q_pre, q_grasp))
}

/// How far below the table top (z = 0 in the world frame of grasps and clouds) the palm
/// may be planned (m).
pub const TABLE_MARGIN_M: f64 = 0.02;

/// How far below the table top a fingertip of the preshape may be planned (m): over a
/// flat object the open fingers reach past it and are stopped by the table as they close
/// (the spatula's plan puts one 3.7 cm below the top and lifts it); deeper, the hand
/// itself would go into the table.
pub const FINGERTIP_TABLE_MARGIN_M: f64 = 0.06;

/// Refuses a grasp whose hand would go into the table, before any command: the grasp
/// centre below the table top, the palm more than [`TABLE_MARGIN_M`] or a fingertip (in
/// the preshape) more than [`FINGERTIP_TABLE_MARGIN_M`] below it at the pre-grasp pose
/// or the grasp pose (the approach between them is a straight line, so its ends bound
/// it).
fn check_above_table(
    robot: &Robot,
    preshape: &[f64; 24],
    grasp: &TwoFingerGrasp,
    back: &Vector3<f64>,
) -> Result<(), RunError> {
    use crate::util::num::short;
    let at = |p: &Point3<f64>| format!("({}, {}, {}) m", short(p.x), short(p.y), short(p.z));
    check_center(grasp)?;
    let palm = crate::robot::grasp_map::palm_pose_for(robot, preshape, grasp)
        .map_err(|e| RunError::BadGrasp(e.to_string()))?;
    let tips = robot.fingertips_palm(preshape);
    for (stage, shift) in [("grasp", Vector3::zeros()), ("pre-grasp", *back)] {
        let points = std::iter::once(("the palm", palm * Point3::origin(), TABLE_MARGIN_M)).chain(
            tips.iter()
                .map(|t| ("a fingertip", palm * t, FINGERTIP_TABLE_MARGIN_M)),
        );
        for (what, p, margin) in points {
            let p = p + shift;
            if p.z < -margin {
                return Err(RunError::BadGrasp(format!(
                    "at the {stage} pose {what} would be at {}, {} m below the table top \
                     (z = 0): the hand would be driven into the table",
                    at(&p),
                    short((-p.z * 1000.0).round() / 1000.0)
                )));
            }
        }
    }
    Ok(())
}

/// Refuses a grasp centre below the table top (z = 0 in the world frame).
fn check_center(grasp: &TwoFingerGrasp) -> Result<(), RunError> {
    use crate::util::num::short;
    let c = grasp.center;
    if c.z < 0.0 {
        return Err(RunError::BadGrasp(format!(
            "the grasp centre ({}, {}, {}) m is below the table top (z = 0): the hand would \
             be driven into the table",
            short(c.x),
            short(c.y),
            short(c.z)
        )));
    }
    Ok(())
}

/// The checks of a grasp source that need no robot, run before anything moves: a given
/// grasp's centre above the table top, a cloud that can show an object
/// ([`check_cloud`]). Planning checks the hand's poses against the table as well.
pub fn check_source(source: &GraspSource) -> Result<(), RunError> {
    match source {
        GraspSource::Given(g) => check_center(g),
        GraspSource::Cloud(points) => check_cloud(points),
    }
}

/// The smallest extent of a cloud an object can have (m): the library's smallest side.
pub const MIN_CLOUD_EXTENT_M: f64 = crate::objects::mesh::MIN_EXTENT_M;

/// Refuses a cloud no object can have made, before any candidate is planned on it: one
/// whose points all lie below the table top, one less than [`MIN_CLOUD_EXTENT_M`] across
/// (3,000 copies of one point, a cloud in kilometres read as metres), or one whose points
/// lie on a line (its second principal spread under a millimetre): planning "across the
/// narrow axis" of such a cloud reported successes on nothing.
pub fn check_cloud(points: &[Point3<f64>]) -> Result<(), RunError> {
    use crate::util::num::short;
    let bad = |m: String| Err(RunError::NoGrasp(format!("the cloud {m}")));
    if points.is_empty() {
        return bad("has no points".into());
    }
    let top = points.iter().map(|p| p.z).fold(f64::NEG_INFINITY, f64::max);
    if top < 0.0 {
        return bad(format!(
            "lies wholly below the table top (z = 0; its highest point is at z = {} m): \
             clouds are in the world frame, the table top at z = 0",
            short(top)
        ));
    }
    let (lo, hi) = points.iter().fold(
        (
            Vector3::repeat(f64::INFINITY),
            Vector3::repeat(f64::NEG_INFINITY),
        ),
        |(lo, hi), p| (lo.inf(&p.coords), hi.sup(&p.coords)),
    );
    let span = (hi - lo).max();
    if span < MIN_CLOUD_EXTENT_M {
        return bad(format!(
            "spans only {} m across its {} points (an object is at least {} m across): it \
             shows no object",
            short(span),
            points.len(),
            short(MIN_CLOUD_EXTENT_M)
        ));
    }
    let n = points.len() as f64;
    let mean = points.iter().fold(Vector3::zeros(), |a, p| a + p.coords) / n;
    let cov = points.iter().fold(nalgebra::Matrix3::zeros(), |a, p| {
        let d = p.coords - mean;
        a + d * d.transpose()
    }) / n;
    let mut ev: Vec<f64> = cov.symmetric_eigenvalues().iter().copied().collect();
    ev.sort_by(|a, b| b.total_cmp(a));
    let second = ev[1].max(0.0).sqrt();
    if second < 1e-3 {
        return bad(format!(
            "lies on a line (its points spread {} m across it): it shows no object to \
             close the hand on",
            short(second)
        ));
    }
    Ok(())
}

/// Plans the grasp (see the module docs) with the hand in `preshape` (see
/// [`PipelineConfig::preshape_angles`]).
pub fn plan_grasp(
    robot: &Robot,
    source: &GraspSource,
    preshape: &[f64; N_JOINTS],
    cfg: &PipelineConfig,
) -> Result<GraspPlan, RunError> {
    plan_grasp_avoiding(robot, source, preshape, cfg, &[])
}

/// Whether cloud grasp `g` is one of `tried` (a retry plans another): the same grasp
/// point and closing line as [`PlannedGrasp::same_as`] judges them.
fn already_tried(g: &TwoFingerGrasp, tried: &[GraspPlan]) -> bool {
    let planned = |center: Point3<f64>, closing: Vector3<f64>| PlannedGrasp {
        grasp_point: center.into(),
        hand_yaw: closing.y.atan2(closing.x),
    };
    let p = planned(g.center, g.closing);
    tried
        .iter()
        .any(|t| planned(Point3::from(t.center), Vector3::from(t.closing)).same_as(&p))
}

/// [`plan_grasp`] for a retry: on a cloud, the best reachable candidate that is none of
/// the grasps already `tried` (a given grasp is planned as it is).
pub fn plan_grasp_avoiding(
    robot: &Robot,
    source: &GraspSource,
    preshape: &[f64; N_JOINTS],
    cfg: &PipelineConfig,
    tried: &[GraspPlan],
) -> Result<GraspPlan, RunError> {
    cfg.validate()?;
    let preshape = *preshape;
    let make = |g: &TwoFingerGrasp, score, candidates, skipped, q: ([f64; 6], [f64; 6])| {
        let a = g.approach.normalize();
        let c = (g.closing - a * a.dot(&g.closing)).normalize();
        GraspPlan {
            center: g.center.into(),
            approach: a.into(),
            closing: c.into(),
            score,
            candidates,
            skipped,
            fallback: score.is_none() && matches!(source, GraspSource::Cloud(_)),
            preshape,
            pregrasp_q: q.0,
            grasp_q: q.1,
        }
    };
    match source {
        GraspSource::Given(g) => {
            g.frame().map_err(|e| RunError::BadGrasp(e.to_string()))?;
            let g = if cfg.top_down_only {
                snap_top_down(g, cfg.max_tilt_rad).ok_or_else(|| {
                    RunError::BadGrasp(format!(
                        "this backend grasps top-down only: the approach must be within {:.2} rad of straight down and the closing direction not vertical",
                        cfg.max_tilt_rad
                    ))
                })?
            } else {
                *g
            };
            let q = solve_arm(robot, &preshape, &g, cfg)?;
            Ok(make(&g, None, 0, 0, q))
        }
        GraspSource::Cloud(points) => {
            check_cloud(points)?;
            let cands = grasp_candidates(points, &cfg.antipodal)?;
            let mut skipped = 0;
            let mut first_err = None;
            for c in cands.iter().take(cfg.max_candidates) {
                let g = if cfg.top_down_only {
                    match snap_top_down(&c.grasp, cfg.max_tilt_rad) {
                        Some(g) => g,
                        None => {
                            skipped += 1;
                            continue;
                        }
                    }
                } else {
                    c.grasp
                };
                if already_tried(&g, tried) {
                    skipped += 1;
                    continue;
                }
                match solve_arm(robot, &preshape, &g, cfg) {
                    Ok(q) => return Ok(make(&g, Some(c.score), cands.len(), skipped, q)),
                    Err(e) => {
                        skipped += 1;
                        first_err.get_or_insert(e.to_string());
                    }
                }
            }
            // No usable candidate: across the cloud's narrowest horizontal extent, as the
            // pre-grasp planner of evaluation and training does.
            if let Some(g) = principal_axis_grasp(points).filter(|g| !already_tried(g, tried)) {
                match solve_arm(robot, &preshape, &g, cfg) {
                    Ok(q) => return Ok(make(&g, None, cands.len(), skipped, q)),
                    Err(e) => {
                        first_err.get_or_insert(e.to_string());
                    }
                }
            }
            if cands.is_empty() {
                // A hand-sized object spans centimetres: a cloud metres across is most
                // likely in another unit.
                let (lo, hi) = points.iter().fold(
                    (
                        Vector3::repeat(f64::INFINITY),
                        Vector3::repeat(f64::NEG_INFINITY),
                    ),
                    |(lo, hi), p| (lo.inf(&p.coords), hi.sup(&p.coords)),
                );
                let span = (hi - lo).max();
                let hint = if span > 2.0 {
                    format!(
                        "; the cloud spans {} m: its coordinates must be in metres (a \
                         cloud in millimetres is 1000 times too large)",
                        crate::util::num::short((span * 1000.0).round() / 1000.0)
                    )
                } else {
                    String::new()
                };
                return Err(RunError::NoGrasp(format!(
                    "the antipodal sampler found no two-finger grasp on the {} points of the cloud, and the grasp across its narrow axis is not usable{}{hint}",
                    points.len(),
                    first_err.map(|e| format!(" ({e})")).unwrap_or_default()
                )));
            }
            Err(RunError::NoGrasp(format!(
                "{} candidates, none of the best {} usable, nor the grasp across the cloud's narrow axis{}{}",
                cands.len(),
                cfg.max_candidates.min(cands.len()),
                if cfg.top_down_only {
                    " (top-down only)"
                } else {
                    ""
                },
                first_err.map(|e| format!(": {e}")).unwrap_or_default()
            )))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::env::grasp::EnvConfig;
    use crate::robot::Side;

    #[test]
    fn planning_reaches_a_top_down_grasp_and_refuses_an_unreachable_one() {
        let robot = Robot::builtin(Side::Left);
        let cfg = PipelineConfig::default();
        let pre = cfg.preshape_angles(&EnvConfig::default()).unwrap();
        let g = TwoFingerGrasp::top_down(Point3::new(0.0, 0.0, 0.05), 0.0);
        let plan = plan_grasp(&robot, &GraspSource::Given(g), &pre, &cfg).unwrap();
        // The pre-grasp flange is 10 cm above the grasp flange (approach straight down).
        let base = cfg.arm_base.pose();
        let f_pre = base * ur10e::fk(&plan.pregrasp_q);
        let f_grasp = base * ur10e::fk(&plan.grasp_q);
        let d = f_pre.translation.vector - f_grasp.translation.vector;
        assert!((d - Vector3::new(0.0, 0.0, 0.10)).norm() < 1e-6, "{d}");
        // The grasp flange realises the grasp: the TH/LF tip midpoint at the centre.
        let root = root_pose_for(&robot, &pre, &g).unwrap();
        assert!((f_grasp.translation.vector - root.translation.vector).norm() < 1e-6);
        let far = TwoFingerGrasp::top_down(Point3::new(3.0, 0.0, 0.05), 0.0);
        let e = plan_grasp(&robot, &GraspSource::Given(far), &pre, &cfg).unwrap_err();
        assert!(
            matches!(
                e,
                RunError::Ik {
                    stage: "pre-grasp",
                    ..
                }
            ),
            "{e}"
        );
        assert!(e.to_string().contains("(3.000, 0.000, 0.050)"), "{e}");
    }

    #[test]
    fn grasps_into_the_table_and_clouds_of_nothing_are_refused() {
        let robot = Robot::builtin(Side::Left);
        let cfg = PipelineConfig::default();
        let pre = cfg.preshape_angles(&EnvConfig::default()).unwrap();
        let plan_at = |z: f64| {
            let g = TwoFingerGrasp::top_down(Point3::new(0.0, 0.0, z), 0.0);
            plan_grasp(&robot, &GraspSource::Given(g), &pre, &cfg)
        };
        plan_at(0.03).unwrap();
        let e = plan_at(-0.5).unwrap_err().to_string();
        assert!(e.contains("below the table top"), "{e}");
        // Approached from below: the palm comes up through the table.
        let up = TwoFingerGrasp {
            center: Point3::new(0.0, 0.0, 0.05),
            approach: Vector3::new(0.0, 0.0, 1.0),
            closing: Vector3::new(1.0, 0.0, 0.0),
        };
        let e = plan_grasp(&robot, &GraspSource::Given(up), &pre, &cfg)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("the palm would be at") && e.contains("below the table top"),
            "{e}"
        );
        let same = vec![Point3::new(0.0, 0.0, 0.03); 3000];
        let e = check_cloud(&same).unwrap_err().to_string();
        assert!(e.contains("spans only 0 m"), "{e}");
        let line: Vec<_> = (0..100)
            .map(|i| Point3::new(0.001 * i as f64, 0.0, 0.03))
            .collect();
        let e = check_cloud(&line).unwrap_err().to_string();
        assert!(e.contains("lies on a line"), "{e}");
        let below: Vec<_> = (0..100)
            .map(|i| Point3::new(0.001 * (i % 10) as f64, 0.001 * (i / 10) as f64, -0.5))
            .collect();
        let e = check_cloud(&below).unwrap_err().to_string();
        assert!(e.contains("wholly below the table top"), "{e}");
    }
}
