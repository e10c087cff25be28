//! The Shadow hand's joint vocabulary: names, the paper's order, coupling and the
//! published kinematic facts (`shared/ROBOT.md`) from which the project's URDF files are
//! written.
//!
//! Names here carry no side prefix (`FFJ3`); URDF joint names carry `rh_` or `lh_`.
//! All lengths are metres, angles radians, efforts N m.

// The limits are the published, rounded values (1.5708, 0.5236, ...), kept as written.
#![allow(clippy::approx_constant)]

use std::f64::consts::{FRAC_PI_2, FRAC_PI_4};

/// Which hand: the paper uses the LEFT hand; the right hand is the published reference.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Side {
    /// The left hand (`lh_` prefix), the mirror image of the right hand.
    Left,
    /// The right hand (`rh_` prefix).
    Right,
}

impl Side {
    /// The ROS joint/link prefix: `lh_` or `rh_`.
    pub fn prefix(self) -> &'static str {
        match self {
            Side::Left => "lh_",
            Side::Right => "rh_",
        }
    }

    /// Lower-case name, `left` or `right`.
    pub fn name(self) -> &'static str {
        match self {
            Side::Left => "left",
            Side::Right => "right",
        }
    }
}

impl std::str::FromStr for Side {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s.to_ascii_lowercase().as_str() {
            "left" | "l" | "lh" => Ok(Side::Left),
            "right" | "r" | "rh" => Ok(Side::Right),
            other => Err(format!(
                "unknown hand side '{other}': expected 'left' or 'right'"
            )),
        }
    }
}

/// The 2 wrist joints, in the paper's order.
pub const WRIST_JOINTS: [&str; 2] = ["WRJ2", "WRJ1"];

/// The 22 finger joints in the synergy order: FF(4), MF(4), RF(4), LF(5), TH(5).
pub const FINGER_JOINTS: [&str; 22] = [
    "FFJ4", "FFJ3", "FFJ2", "FFJ1", "MFJ4", "MFJ3", "MFJ2", "MFJ1", "RFJ4", "RFJ3", "RFJ2", "RFJ1",
    "LFJ5", "LFJ4", "LFJ3", "LFJ2", "LFJ1", "THJ5", "THJ4", "THJ3", "THJ2", "THJ1",
];

/// All 24 hand joints in the paper's order: WRJ2, WRJ1, then [`FINGER_JOINTS`].
pub const HAND_JOINTS: [&str; 24] = [
    "WRJ2", "WRJ1", "FFJ4", "FFJ3", "FFJ2", "FFJ1", "MFJ4", "MFJ3", "MFJ2", "MFJ1", "RFJ4", "RFJ3",
    "RFJ2", "RFJ1", "LFJ5", "LFJ4", "LFJ3", "LFJ2", "LFJ1", "THJ5", "THJ4", "THJ3", "THJ2", "THJ1",
];

/// Number of hand joint angles ([`HAND_JOINTS`]): what the hand reports and the policy
/// reads as `theta`.
pub const N_JOINTS: usize = HAND_JOINTS.len();
/// Number of fingertip tactile sensors, one per finger of [`FINGERS`].
pub const N_TACTILE: usize = FINGERS.len();
/// Number of actuators ([`actuators`]): one tendon-force channel and one torque level each.
pub const N_ACTUATORS: usize = 20;

/// The key closing joints of eq. 5 (mask M = 1).
pub const KEY_CLOSING_JOINTS: [&str; 5] = ["FFJ3", "MFJ3", "RFJ3", "LFJ3", "THJ5"];

/// The fingers in the tactile order used by observations: FF, MF, RF, LF, TH.
pub const FINGERS: [&str; 5] = ["FF", "MF", "RF", "LF", "TH"];

/// Fingertip link names (without side prefix), in [`FINGERS`] order.
pub const FINGERTIP_LINKS: [&str; 5] = ["fftip", "mftip", "rftip", "lftip", "thtip"];

/// The four fingers whose J1 and J2 are driven by one actuator (J0 = J1 + J2).
pub const COUPLED_FINGERS: [&str; 4] = ["FF", "MF", "RF", "LF"];

/// One actuator of the hand. Coupled actuators drive `J0 = J1 + J2` of one finger.
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize)]
pub struct ActuatorSpec {
    /// Actuator name, e.g. `FFJ0` for the coupled pair or `FFJ3`.
    pub name: String,
    /// The joints it drives (one, or two for a coupled J0).
    pub joints: Vec<&'static str>,
}

/// The 20 actuators in the paper's order: WRJ2, WRJ1, FFJ4, FFJ3, FFJ0, MF.., RF..,
/// LFJ5, LFJ4, LFJ3, LFJ0, THJ5..THJ1.
pub fn actuators() -> Vec<ActuatorSpec> {
    let mut out = Vec::with_capacity(20);
    let mut i = 0;
    while i < HAND_JOINTS.len() {
        let j = HAND_JOINTS[i];
        let finger = &j[..2];
        if COUPLED_FINGERS.contains(&finger) && j.ends_with("J2") {
            out.push(ActuatorSpec {
                name: format!("{finger}J0"),
                joints: vec![HAND_JOINTS[i], HAND_JOINTS[i + 1]],
            });
            i += 2;
        } else {
            out.push(ActuatorSpec {
                name: j.to_string(),
                joints: vec![j],
            });
            i += 1;
        }
    }
    out
}

/// The 20 actuator values from 24 per-joint values (paper orders, see [`actuators`]): a
/// coupled finger's J1 and J2 values are summed into its J0 actuator. Used for joint
/// efforts in the simulator and for tendon readings from the real hand.
pub fn actuator_sums(e: &[f64; 24]) -> [f64; 20] {
    let mut out = [0.0; 20];
    let (mut i, mut a) = (0, 0);
    while i < HAND_JOINTS.len() && a < out.len() {
        let name = HAND_JOINTS[i];
        if COUPLED_FINGERS.contains(&&name[..2]) && name.ends_with("J2") {
            out[a] = e[i] + e[i + 1];
            i += 2;
        } else {
            out[a] = e[i];
            i += 1;
        }
        a += 1;
    }
    out
}

/// Position of a finger joint name (no prefix) in [`FINGER_JOINTS`].
pub fn finger_index(name: &str) -> Option<usize> {
    FINGER_JOINTS.iter().position(|j| *j == name)
}

/// Position of a hand joint name (no prefix) in [`HAND_JOINTS`].
pub fn hand_index(name: &str) -> Option<usize> {
    HAND_JOINTS.iter().position(|j| *j == name)
}

/// Strips an `rh_`/`lh_` prefix and upper-cases the rest: `lh_ffj3` -> `FFJ3`.
pub fn canonical_name(name: &str) -> String {
    let lower = name.to_ascii_lowercase();
    let base = lower
        .strip_prefix("rh_")
        .or_else(|| lower.strip_prefix("lh_"))
        .unwrap_or(&lower);
    base.to_ascii_uppercase()
}

/// A published joint fact for the RIGHT hand (palm-frame conventions of ROBOT.md).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct JointFact {
    /// Joint name without prefix (`FFJ3`) or a fixed tip joint (`FFtip`).
    pub name: &'static str,
    /// Parent link (without prefix).
    pub parent: &'static str,
    /// Child link (without prefix).
    pub child: &'static str,
    /// Origin translation in the parent frame.
    pub xyz: [f64; 3],
    /// Origin rotation (roll, pitch, yaw) in the parent frame.
    pub rpy: [f64; 3],
    /// Rotation axis in the child frame; `None` for fixed joints.
    pub axis: Option<[f64; 3]>,
    /// Lower limit.
    pub lower: f64,
    /// Upper limit.
    pub upper: f64,
    /// Effort limit.
    pub effort: f64,
}

#[allow(clippy::too_many_arguments)]
const fn rev(
    name: &'static str,
    parent: &'static str,
    child: &'static str,
    xyz: [f64; 3],
    rpy: [f64; 3],
    axis: [f64; 3],
    lower: f64,
    upper: f64,
    effort: f64,
) -> JointFact {
    JointFact {
        name,
        parent,
        child,
        xyz,
        rpy,
        axis: Some(axis),
        lower,
        upper,
        effort,
    }
}

const fn tip(name: &'static str, parent: &'static str, child: &'static str, z: f64) -> JointFact {
    JointFact {
        name,
        parent,
        child,
        xyz: [0.0, 0.0, z],
        rpy: [0.0; 3],
        axis: None,
        lower: 0.0,
        upper: 0.0,
        effort: 0.0,
    }
}

const Z3: [f64; 3] = [0.0; 3];
const J3_LO: f64 = -0.2618;
const J4: f64 = 0.3491;
const HALF_PI: f64 = 1.5708;

macro_rules! finger {
    ($F:literal, $f:literal, $knuckle:expr, $axis4:expr) => {
        [
            rev(
                concat!($F, "J4"),
                "knuckle_parent",
                concat!($f, "knuckle"),
                $knuckle,
                Z3,
                $axis4,
                -J4,
                J4,
                2.0,
            ),
            rev(
                concat!($F, "J3"),
                concat!($f, "knuckle"),
                concat!($f, "proximal"),
                Z3,
                Z3,
                [1.0, 0.0, 0.0],
                J3_LO,
                HALF_PI,
                2.0,
            ),
            rev(
                concat!($F, "J2"),
                concat!($f, "proximal"),
                concat!($f, "middle"),
                [0.0, 0.0, 0.045],
                Z3,
                [1.0, 0.0, 0.0],
                0.0,
                HALF_PI,
                2.0,
            ),
            rev(
                concat!($F, "J1"),
                concat!($f, "middle"),
                concat!($f, "distal"),
                [0.0, 0.0, 0.025],
                Z3,
                [1.0, 0.0, 0.0],
                0.0,
                HALF_PI,
                2.0,
            ),
            tip(
                concat!($f, "tip"),
                concat!($f, "distal"),
                concat!($f, "tip"),
                0.026,
            ),
        ]
    };
}

/// The published joint facts of the RIGHT hand, parents before children. Link names are
/// lower-case without prefix (`palm`, `ffknuckle`, `fftip`, ...). The `*_knuckle_parent`
/// placeholder parent of the finger macro is resolved to `palm` or `lfmetacarpal`.
pub fn right_hand_facts() -> Vec<JointFact> {
    let mut v = vec![
        rev(
            "WRJ2",
            "forearm",
            "wrist",
            [0.0, -0.010, 0.213],
            Z3,
            [0.0, 1.0, 0.0],
            -0.5236,
            0.1745,
            10.0,
        ),
        rev(
            "WRJ1",
            "wrist",
            "palm",
            [0.0, 0.0, 0.034],
            Z3,
            [1.0, 0.0, 0.0],
            -0.6981,
            0.4887,
            30.0,
        ),
    ];
    fn push_finger(v: &mut Vec<JointFact>, facts: [JointFact; 5], parent: &'static str) {
        for mut f in facts {
            if f.parent == "knuckle_parent" {
                f.parent = parent;
            }
            v.push(f);
        }
    }
    push_finger(
        &mut v,
        finger!("FF", "ff", [0.033, 0.0, 0.095], [0.0, -1.0, 0.0]),
        "palm",
    );
    push_finger(
        &mut v,
        finger!("MF", "mf", [0.011, 0.0, 0.099], [0.0, -1.0, 0.0]),
        "palm",
    );
    push_finger(
        &mut v,
        finger!("RF", "rf", [-0.011, 0.0, 0.095], [0.0, 1.0, 0.0]),
        "palm",
    );
    let lf5 = rev(
        "LFJ5",
        "palm",
        "lfmetacarpal",
        [-0.033, 0.0, 0.02071],
        Z3,
        [0.573576, 0.0, 0.819152],
        0.0,
        0.7854,
        2.0,
    );
    v.push(lf5);
    push_finger(
        &mut v,
        finger!("LF", "lf", [0.0, 0.0, 0.06579], [0.0, 1.0, 0.0]),
        "lfmetacarpal",
    );
    v.extend([
        rev(
            "THJ5",
            "palm",
            "thbase",
            [0.034, -0.0085, 0.029],
            [0.0, FRAC_PI_4, 0.0],
            [0.0, 0.0, -1.0],
            -1.0472,
            1.0472,
            5.0,
        ),
        rev(
            "THJ4",
            "thbase",
            "thproximal",
            Z3,
            Z3,
            [1.0, 0.0, 0.0],
            0.0,
            1.2217,
            3.0,
        ),
        rev(
            "THJ3",
            "thproximal",
            "thhub",
            [0.0, 0.0, 0.038],
            Z3,
            [1.0, 0.0, 0.0],
            -0.2094,
            0.2094,
            2.0,
        ),
        rev(
            "THJ2",
            "thhub",
            "thmiddle",
            Z3,
            Z3,
            [0.0, -1.0, 0.0],
            -0.6981,
            0.6981,
            2.0,
        ),
        rev(
            "THJ1",
            "thmiddle",
            "thdistal",
            [0.0, 0.0, 0.032],
            [0.0, 0.0, -FRAC_PI_2],
            [1.0, 0.0, 0.0],
            -0.2618,
            HALF_PI,
            1.0,
        ),
        tip("thtip", "thdistal", "thtip", 0.0275),
    ]);
    v
}

/// The joint facts of `side`. The left hand is the exact mirror image of the right hand
/// through the palm's y-z plane (x -> -x): every origin is mirrored, fixed rotations
/// become `M R M` (for the thumb base, pitch +pi/4 -> -pi/4; for THJ1, yaw -pi/2 -> +pi/2),
/// and every axis `a` becomes `(a_x, -a_y, -a_z)` so that the same joint angle gives the
/// mirrored posture. For the joints ROBOT.md lists (WRJ2, the J4 joints, THJ5, LFJ5) this is
/// exactly its recipe; it also mirrors the thumb's fixed rotations, without which the left
/// thumb would not be the mirror of the right one. Limits are unchanged.
pub fn hand_facts(side: Side) -> Vec<JointFact> {
    let mut facts = right_hand_facts();
    if side == Side::Left {
        for f in &mut facts {
            f.xyz[0] = -f.xyz[0];
            // M Rz(y) Ry(p) Rx(r) M = Rz(-y) Ry(-p) Rx(r) for M = diag(-1, 1, 1).
            f.rpy = [f.rpy[0], -f.rpy[1], -f.rpy[2]];
            if let Some(a) = f.axis.as_mut() {
                a[1] = -a[1];
                a[2] = -a[2];
                for c in a.iter_mut() {
                    if *c == 0.0 {
                        *c = 0.0; // normalise -0.0 for clean URDF output
                    }
                }
            }
            if f.xyz[0] == 0.0 {
                f.xyz[0] = 0.0;
            }
        }
    }
    facts
}

/// Hand targets as the motors take them: the coupled fingers' J1 and J2 each get half of
/// their J0 = J1 + J2, then every target is clamped to its joint's `limits` (24 angles,
/// paper order). Both simulated engines apply this before their PD laws.
pub fn couple_and_clamp(t: &[f64; 24], limits: &[(f64, f64); 24]) -> [f64; 24] {
    let mut out = *t;
    for f in COUPLED_FINGERS {
        if let (Some(j2), Some(j1)) = (hand_index(&format!("{f}J2")), hand_index(&format!("{f}J1")))
        {
            let j0 = out[j2] + out[j1];
            out[j2] = j0 / 2.0;
            out[j1] = j0 / 2.0;
        }
    }
    for (v, (lo, hi)) in out.iter_mut().zip(limits) {
        *v = v.clamp(*lo, *hi);
    }
    out
}

#[cfg(test)]
mod tests {

    #[test]
    fn couple_and_clamp_splits_j0_and_clamps_hand_computed() {
        let mut limits = [(-1.0, 1.0); 24];
        let ff3 = hand_index("FFJ3").unwrap();
        limits[ff3] = (0.0, 0.5);
        let mut t = [0.0; 24];
        let (ff2, ff1) = (hand_index("FFJ2").unwrap(), hand_index("FFJ1").unwrap());
        // J0 = 0.9 + 0.1 = 1.0: each gets 0.5.
        t[ff2] = 0.9;
        t[ff1] = 0.1;
        // 0.8 is above FFJ3's upper limit 0.5; -3 below the others' -1.
        t[ff3] = 0.8;
        let th1 = hand_index("THJ1").unwrap();
        t[th1] = -3.0;
        let out = couple_and_clamp(&t, &limits);
        assert_eq!((out[ff2], out[ff1]), (0.5, 0.5));
        assert_eq!(out[ff3], 0.5);
        assert_eq!(out[th1], -1.0);
        // The thumb is not coupled: THJ2 keeps its own target.
        let th2 = hand_index("THJ2").unwrap();
        t[th2] = 0.3;
        assert_eq!(couple_and_clamp(&t, &limits)[th2], 0.3);
    }

    use super::*;

    #[test]
    fn coupled_efforts_are_summed() {
        let mut e = [0.0; 24];
        for (k, v) in e.iter_mut().enumerate() {
            *v = k as f64;
        }
        let a = actuator_sums(&e);
        // WRJ2, WRJ1, FFJ4, FFJ3, FFJ0 = FFJ2 + FFJ1 = 4 + 5.
        assert_eq!(&a[..5], &[0.0, 1.0, 2.0, 3.0, 9.0]);
        // LFJ5, LFJ4, LFJ3, LFJ0 = 17 + 18, then the thumb 19..23.
        assert_eq!(
            &a[11..],
            &[14.0, 15.0, 16.0, 35.0, 19.0, 20.0, 21.0, 22.0, 23.0]
        );
    }

    #[test]
    fn twenty_actuators_with_four_coupled_pairs() {
        let a = actuators();
        assert_eq!(a.len(), 20);
        let coupled: Vec<_> = a.iter().filter(|a| a.joints.len() == 2).collect();
        assert_eq!(coupled.len(), 4);
        assert_eq!(coupled[0].name, "FFJ0");
        assert_eq!(coupled[0].joints, vec!["FFJ2", "FFJ1"]);
        assert_eq!(a[0].name, "WRJ2");
        assert_eq!(a[19].name, "THJ1");
    }

    #[test]
    fn orders_are_consistent() {
        assert_eq!(&HAND_JOINTS[2..], &FINGER_JOINTS[..]);
        for k in KEY_CLOSING_JOINTS {
            assert!(finger_index(k).is_some());
        }
        assert_eq!(canonical_name("lh_ffj3"), "FFJ3");
        assert_eq!(canonical_name("rh_WRJ1"), "WRJ1");
    }

    #[test]
    fn facts_cover_all_joints_and_tips() {
        let f = right_hand_facts();
        for j in HAND_JOINTS {
            assert_eq!(f.iter().filter(|x| x.name == j).count(), 1, "{j}");
        }
        for t in FINGERTIP_LINKS {
            assert!(f.iter().any(|x| x.child == t), "{t}");
        }
        assert_eq!(f.len(), 24 + 5);
    }

    #[test]
    fn left_axes_follow_robot_md() {
        let l = hand_facts(Side::Left);
        let get = |n: &str| l.iter().find(|f| f.name == n).unwrap();
        assert_eq!(get("WRJ2").axis, Some([0.0, -1.0, 0.0]));
        assert_eq!(get("FFJ4").axis, Some([0.0, 1.0, 0.0]));
        assert_eq!(get("THJ5").axis, Some([0.0, 0.0, 1.0]));
        assert_eq!(get("LFJ5").axis, Some([0.573576, 0.0, -0.819152]));
        assert_eq!(get("FFJ4").xyz, [-0.033, 0.0, 0.095]);
        assert_eq!(get("FFJ3").axis, Some([1.0, 0.0, 0.0]));
    }

    #[test]
    fn side_parses() {
        assert_eq!("LEFT".parse::<Side>().unwrap(), Side::Left);
        assert!("middle".parse::<Side>().unwrap_err().contains("middle"));
    }
}
