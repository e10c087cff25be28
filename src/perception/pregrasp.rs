//! Planned top-down hand placements: the pre-grasp of `grasp run` as an episode start.
//!
//! By default an episode places the hand top-down over the object's centre, its grasp
//! point `grasp_depth` below the object's top (see [`crate::sim::Scene::top_down`]). A
//! [`PregraspPlanner`] replaces that with a planned grasp: after the object is placed (at
//! rest, in its episode pose), the planner sees the simulator and returns a grasp point and
//! a hand yaw, as `grasp run` plans one on a robot's depth cloud. The environment then
//! places the hand there, raised clear of the object where it would overlap it, exactly as
//! the default placement is.
//!
//! [`AntipodalPregrasp`] is `grasp run`'s choice for a cloud: the simulated depth cameras
//! see the object where it rests ([`super::camera::camera_cloud`]), the antipodal sampler
//! scores two-finger grasps on the cloud, and the best candidate within `max_tilt_rad` of
//! straight down, made exactly top-down ([`snap_top_down`]), places the hand: its centre is
//! the grasp point (the TH/LF fingertip midpoint) and its closing direction the hand's
//! thumb-to-little-finger line (less the UR10e's reachability check: every evaluation
//! object lies within the arm's reach). `grasp eval --pregrasp antipodal` starts every
//! episode from it, and a training config's `[env.placement]` from a share of them.

use super::camera::{camera_cloud, CameraConfig};
use super::pointcloud::{grasp_candidates, principal_axis_grasp, AntipodalConfig};
use crate::robot::grasp_map::TwoFingerGrasp;
use crate::sim::HandSim;
use nalgebra::Vector3;

/// A planned top-down hand placement.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlannedGrasp {
    /// Grasp point (the TH/LF fingertip midpoint) in the world (m).
    pub grasp_point: [f64; 3],
    /// Direction of the thumb-to-little-finger line about world z (rad).
    pub hand_yaw: f64,
}

impl PlannedGrasp {
    /// Whether every number is finite.
    pub fn is_finite(&self) -> bool {
        self.grasp_point.iter().all(|v| v.is_finite()) && self.hand_yaw.is_finite()
    }

    /// Whether `other` is the same grasp for a retry's purpose: grasp points within
    /// [`SAME_GRASP_M`] and closing lines within [`SAME_GRASP_RAD`] of each other (a line:
    /// the hand turned by half a turn closes along the same one).
    pub fn same_as(&self, other: &PlannedGrasp) -> bool {
        let d2: f64 = (0..3)
            .map(|k| (self.grasp_point[k] - other.grasp_point[k]).powi(2))
            .sum();
        let turn = (self.hand_yaw - other.hand_yaw).rem_euclid(std::f64::consts::PI);
        d2.sqrt() < SAME_GRASP_M && turn.min(std::f64::consts::PI - turn) < SAME_GRASP_RAD
    }
}

/// Grasp points closer than this (m) are one grasp ([`PlannedGrasp::same_as`]).
pub const SAME_GRASP_M: f64 = 0.01;

/// Closing lines closer than this (rad) are one grasp ([`PlannedGrasp::same_as`]).
pub const SAME_GRASP_RAD: f64 = 0.35;

/// Plans the hand's start for an episode from the simulator with the object placed.
pub trait PregraspPlanner: Send {
    /// The placement for the episode of `seed` (the same seed gives the same plan, so
    /// every agent starts a trial from the same pose), or `None` when the planner finds
    /// none (the episode then starts from the default placement). A retry passes the
    /// grasps its trial already tried in `avoid`: none of them is planned again
    /// ([`PlannedGrasp::same_as`]), the next best is.
    fn plan(&mut self, sim: &HandSim, seed: u64, avoid: &[PlannedGrasp]) -> Option<PlannedGrasp>;
}

/// Largest tilt of a candidate's approach from straight down that a top-down grasp
/// accepts (rad): `grasp run`'s default too.
pub const DEFAULT_MAX_TILT_RAD: f64 = 0.35;

/// Candidates tried, best score first, before a plan gives up: `grasp run`'s default too.
pub const DEFAULT_MAX_CANDIDATES: usize = 30;

/// Makes a candidate exactly top-down (approach -z, horizontal closing direction) if it is
/// within `max_tilt` of it.
pub fn snap_top_down(g: &TwoFingerGrasp, max_tilt: f64) -> Option<TwoFingerGrasp> {
    let a = g.approach.try_normalize(1e-9)?;
    if a.angle(&-Vector3::z()) > max_tilt {
        return None;
    }
    let closing = Vector3::new(g.closing.x, g.closing.y, 0.0).try_normalize(1e-6)?;
    Some(TwoFingerGrasp {
        center: g.center,
        approach: -Vector3::z(),
        closing,
    })
}

/// Antipodal pre-grasps on the simulated depth cloud.
#[derive(Debug, Clone, PartialEq)]
pub struct AntipodalPregrasp {
    /// The depth cameras.
    pub cameras: CameraConfig,
    /// The sampler (its seed is replaced by the episode's).
    pub antipodal: AntipodalConfig,
    /// Largest tilt of a candidate's approach from straight down (rad).
    pub max_tilt_rad: f64,
    /// Most candidates tried, best score first.
    pub max_candidates: usize,
}

impl Default for AntipodalPregrasp {
    /// `grasp run --backend sim`'s settings: four camera views, the default sampler, top-down
    /// within 0.35 rad, the best 30 candidates.
    fn default() -> Self {
        AntipodalPregrasp {
            cameras: CameraConfig::default(),
            antipodal: AntipodalConfig::default(),
            max_tilt_rad: DEFAULT_MAX_TILT_RAD,
            max_candidates: DEFAULT_MAX_CANDIDATES,
        }
    }
}

impl AntipodalPregrasp {
    /// Up to `top` distinct placements for the episode of `seed`, best score first: the
    /// sampler's candidates on the depth cloud within `max_tilt_rad` of straight down, none
    /// the same as another ([`PlannedGrasp::same_as`]) or as a grasp in `avoid`, else the
    /// grasp across the cloud's narrowest horizontal extent. The first is
    /// [`PregraspPlanner::plan`]'s; the others are what a ranker chooses among
    /// (`grasp eval --rank-top`).
    pub fn candidates(
        &self,
        sim: &HandSim,
        seed: u64,
        avoid: &[PlannedGrasp],
        top: usize,
    ) -> Vec<PlannedGrasp> {
        let Ok(cloud) = camera_cloud(sim, &self.cameras, seed) else {
            return Vec::new();
        };
        let cfg = AntipodalConfig {
            seed,
            ..self.antipodal
        };
        // No usable antipodal pair (or too few points for the normals): across the
        // cloud's narrowest horizontal extent instead.
        let candidates = grasp_candidates(&cloud, &cfg).unwrap_or_default();
        let planned = |g: TwoFingerGrasp| PlannedGrasp {
            grasp_point: g.center.into(),
            hand_yaw: g.closing.y.atan2(g.closing.x),
        };
        let mut out: Vec<PlannedGrasp> = Vec::new();
        for p in candidates
            .iter()
            .take(self.max_candidates)
            .filter_map(|c| snap_top_down(&c.grasp, self.max_tilt_rad).map(planned))
        {
            if out.len() >= top.max(1) {
                break;
            }
            if !avoid.iter().chain(&out).any(|a| a.same_as(&p)) {
                out.push(p);
            }
        }
        if out.is_empty() {
            out.extend(
                principal_axis_grasp(&cloud)
                    .map(planned)
                    .filter(|p| !avoid.iter().any(|a| a.same_as(p))),
            );
        }
        out
    }
}

impl PregraspPlanner for AntipodalPregrasp {
    fn plan(&mut self, sim: &HandSim, seed: u64, avoid: &[PlannedGrasp]) -> Option<PlannedGrasp> {
        self.candidates(sim, seed, avoid, 1).first().copied()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::robot::{Posture, Robot, Side};
    use crate::sim::{ObjectSpec, Scene, SimConfig};

    #[test]
    fn a_plan_with_nan_is_not_finite() {
        let ok = PlannedGrasp {
            grasp_point: [0.0, 0.1, 0.05],
            hand_yaw: 0.3,
        };
        assert!(ok.is_finite());
        assert!(!PlannedGrasp {
            hand_yaw: f64::NAN,
            ..ok
        }
        .is_finite());
        assert!(!PlannedGrasp {
            grasp_point: [0.0, f64::INFINITY, 0.0],
            ..ok
        }
        .is_finite());
    }

    #[test]
    fn a_long_box_is_grasped_across_its_narrow_width_near_its_centre() {
        // A 16 x 5 x 6 cm box (long along x) at rest at the origin, yawed by 0.4 rad: the
        // only antipodal pairs within the 11 cm opening are across its 5 cm width, so the
        // planned closing line lies within the friction cone (mu 0.5: 26.6 degrees) of the
        // box's y axis, (-sin 0.4, cos 0.4), up to sign, and the grasp point lies on the
        // box's footprint, below its 6 cm top.
        let robot = Robot::builtin(Side::Left);
        let obj = ObjectSpec::cuboid([0.08, 0.025, 0.03], 0.3, 0.8);
        let mut sim = HandSim::new(&robot, obj.clone(), SimConfig::default()).unwrap();
        let mut scene = Scene::above(&obj, Posture::Open.angles(), 0.2, 0.0);
        scene.object_yaw = 0.4;
        sim.reset(&scene).unwrap();
        let mut planner = AntipodalPregrasp::default();
        let a = planner.plan(&sim, 7, &[]).expect("a plan on a box");
        let b = planner.plan(&sim, 7, &[]).expect("a plan on a box");
        assert_eq!(a, b, "the same seed gives the same plan");
        let (s, c) = (0.4f64.sin(), 0.4f64.cos());
        let across = (a.hand_yaw.cos() * -s + a.hand_yaw.sin() * c).abs();
        assert!(
            across > (0.5f64).atan().cos(),
            "yaw {} against the box's y axis",
            a.hand_yaw
        );
        let [x, y, z] = a.grasp_point;
        // In the box's frame: |x'| within its half length, |y'| near the middle.
        let (xb, yb) = (c * x + s * y, -s * x + c * y);
        assert!(xb.abs() < 0.08 && yb.abs() < 0.015, "({xb}, {yb})");
        assert!(z > 0.0 && z < 0.06, "{z}");
        // A retry avoiding this grasp gets another one: elsewhere along the box or
        // across it at another angle.
        let c = planner.plan(&sim, 7, &[a]).expect("a second plan");
        assert!(!c.same_as(&a), "{c:?} against {a:?}");
        let d = planner.plan(&sim, 7, &[a, c]).expect("a third plan");
        assert!(!d.same_as(&a) && !d.same_as(&c));
        // The top candidates a ranker chooses among: the plan first, then others, no two
        // the same grasp, none that the trial tried.
        let top = planner.candidates(&sim, 7, &[], 5);
        assert_eq!(top.len(), 5);
        assert_eq!(top[0], a);
        for (i, p) in top.iter().enumerate() {
            assert!(top[..i].iter().all(|q| !q.same_as(p)), "{i}: {p:?}");
        }
        let untried = planner.candidates(&sim, 7, &[a], 3);
        assert_eq!(untried[0], c);
        assert!(untried.iter().all(|p| !p.same_as(&a)));
    }

    #[test]
    fn same_grasp_hand_computed() {
        let g = PlannedGrasp {
            grasp_point: [0.0, 0.0, 0.05],
            hand_yaw: 0.1,
        };
        let at = |dx: f64, yaw: f64| PlannedGrasp {
            grasp_point: [dx, 0.0, 0.05],
            hand_yaw: yaw,
        };
        // 9 mm away, 0.3 rad turned: the same; 11 mm or 0.4 rad: another grasp.
        assert!(g.same_as(&at(0.009, 0.4)));
        assert!(!g.same_as(&at(0.011, 0.1)));
        assert!(!g.same_as(&at(0.0, 0.5)));
        // Half a turn closes along the same line (thumb and fingers swapped): the same;
        // a quarter turn is across it.
        assert!(g.same_as(&at(0.0, 0.1 + std::f64::consts::PI)));
        assert!(g.same_as(&at(0.0, 0.1 - std::f64::consts::PI + 0.2)));
        assert!(!g.same_as(&at(0.0, 0.1 + std::f64::consts::FRAC_PI_2)));
    }

    #[test]
    fn the_spatula_is_planned_across_its_handle() {
        // The built-in spatula (27 x 7 x 2.4 cm, lying along its x axis), yawed by 0.3 rad.
        // With the default four views the sampler finds pairs across its handle; with two
        // views from +-x it finds none (they see the handle's sides at grazing angles and
        // the edges of its 8 mm blade hardly at all), and the plan closes across the
        // cloud's narrow horizontal axis instead. Either way the hand closes within 0.25
        // rad of the object's y axis, over the object, below its top.
        let robot = Robot::builtin(Side::Left);
        let ctx = crate::objects::BuildContext::uncached();
        let spatula = crate::objects::load_objects("spatula", &ctx)
            .unwrap()
            .remove(0);
        let obj = ObjectSpec::simulable(&spatula).unwrap();
        let mut sim = HandSim::new(&robot, obj.clone(), SimConfig::default()).unwrap();
        let mut scene = Scene::above(&obj, Posture::Open.angles(), 0.2, 0.0);
        scene.object_yaw = 0.3;
        sim.reset(&scene).unwrap();
        let two_views = CameraConfig {
            positions: vec![[0.35, 0.0, 0.35], [-0.35, 0.0, 0.35]],
            ..CameraConfig::default()
        };
        let cfg = AntipodalConfig {
            seed: 5,
            ..AntipodalConfig::default()
        };
        let top_down_pairs = |cameras: &CameraConfig| {
            let cloud = camera_cloud(&sim, cameras, 5).unwrap();
            grasp_candidates(&cloud, &cfg)
                .unwrap()
                .iter()
                .filter(|c| snap_top_down(&c.grasp, DEFAULT_MAX_TILT_RAD).is_some())
                .count()
        };
        assert!(top_down_pairs(&CameraConfig::default()) > 0);
        assert_eq!(top_down_pairs(&two_views), 0);
        for cameras in [CameraConfig::default(), two_views] {
            let mut planner = AntipodalPregrasp {
                cameras,
                ..AntipodalPregrasp::default()
            };
            let g = planner.plan(&sim, 5, &[]).expect("a plan on the spatula");
            let across = (g.hand_yaw - 0.3 - std::f64::consts::FRAC_PI_2).sin().abs();
            assert!(across < 0.25f64.sin(), "hand yaw {}", g.hand_yaw);
            let [x, y, z] = g.grasp_point;
            assert!(x.hypot(y) < 0.1, "({x}, {y})");
            assert!(z > 0.0 && z < 0.024, "{z}");
        }
    }

    #[test]
    fn snap_top_down_hand_computed() {
        // Approach tilted by atan(0.1) ~ 0.0997 rad: kept, made exactly vertical; the
        // closing direction (3, 4, 1) loses its vertical part -> (0.6, 0.8, 0).
        let g = TwoFingerGrasp {
            center: nalgebra::Point3::new(0.1, 0.2, 0.3),
            approach: Vector3::new(0.1, 0.0, -1.0),
            closing: Vector3::new(3.0, 4.0, 1.0),
        };
        let s = snap_top_down(&g, 0.1).unwrap();
        assert_eq!(s.approach, -Vector3::z());
        assert!((s.closing - Vector3::new(0.6, 0.8, 0.0)).norm() < 1e-12);
        assert_eq!(s.center, g.center);
        assert!(snap_top_down(&g, 0.09).is_none());
        let vertical = TwoFingerGrasp {
            closing: Vector3::z(),
            ..g
        };
        assert!(snap_top_down(&vertical, 0.2).is_none());
    }
}
