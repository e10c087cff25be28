//! Observations of the grasping MDP (Sec. IV-B).
//!
//! One frame is `o_k = < a_{k-1}, phi, tau, theta >`:
//! - `a_{k-1}`: the previous continuous action (`n` synergy increments and 2 wrist
//!   increments, in the policy's normalised units, i.e. clipped to [-1, 1]); it is the
//!   agent's own memory, present in every modality;
//! - `phi`: the 5 binary fingertip contacts (FF, MF, RF, LF, TH), in M2 and M3;
//! - `tau`: the 20 actuator torque levels 0..5, in M3, SCALED to [0, 1] as `level / 5`
//!   (one number per actuator keeps the levels' order and the input small; a one-hot code
//!   would be 120 numbers per frame);
//! - `theta`: the 24 joint angles (rad), in every modality.
//!
//! The policy sees `O_t = < o_{t-h+1}, ..., o_t >` with `h = 3`, oldest first, zero-padded
//! at the start of an episode.

use serde::{Deserialize, Serialize};

/// Sensing modalities of the paper.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum Modality {
    /// Joint angles only.
    M1,
    /// Joint angles and fingertip tactile contacts.
    M2,
    /// Joint angles, tactile contacts and joint torque levels.
    M3,
    /// Beyond the paper: M3 plus the object's geometry relative to the hand, for each
    /// distal phalanx (FF, MF, RF, LF, TH) and the palm the vector to the nearest object
    /// surface point in the palm frame ([`surface_vectors`]). In simulation it comes from
    /// the object's mesh.
    M3G,
}

impl std::str::FromStr for Modality {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s.to_ascii_uppercase().as_str() {
            "M1" => Ok(Modality::M1),
            "M2" => Ok(Modality::M2),
            "M3" => Ok(Modality::M3),
            "M3G" => Ok(Modality::M3G),
            other => Err(format!(
                "unknown modality '{other}': expected M1, M2, M3 or M3G"
            )),
        }
    }
}

// The counts are the robot's ([`crate::robot::joints`]).
pub use crate::robot::joints::{N_JOINTS, N_TACTILE};
/// Number of torque levels in a frame: one per actuator.
pub const N_TORQUE: usize = crate::robot::joints::N_ACTUATORS;
/// Number of surface-vector values of M3G (6 points x 3).
pub const N_SURFACE: usize = 18;
/// Number of torque levels.
pub const N_LEVELS: usize = 6;

/// What a segment of one frame holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum SegmentKind {
    /// `a_{k-1}`: the previous continuous action, clipped to [-1, 1].
    PrevAction,
    /// `phi`: the fingertip contacts, 0 or 1.
    Tactile,
    /// `tau`: the actuator torque levels, scaled to [0, 1].
    TorqueLevels,
    /// M3G's surface vectors ([`surface_vectors`]).
    Surface,
    /// `theta`: the joint angles (rad).
    JointAngles,
}

impl SegmentKind {
    /// The segment's name: `prev_action`, `tactile`, `torque_levels`, `surface` or
    /// `joint_angles`.
    pub fn name(self) -> &'static str {
        match self {
            SegmentKind::PrevAction => "prev_action",
            SegmentKind::Tactile => "tactile",
            SegmentKind::TorqueLevels => "torque_levels",
            SegmentKind::Surface => "surface",
            SegmentKind::JointAngles => "joint_angles",
        }
    }
}

/// A slice of the observation vector: what it holds and where.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct Segment {
    /// What the values are (serialised as its name).
    #[serde(rename = "name")]
    pub kind: SegmentKind,
    /// Offset inside one frame.
    pub offset: usize,
    /// Number of values.
    pub len: usize,
}

/// Longest observation history `h` accepted from a config: the paper uses 3; the policy's
/// first layer grows with `h` (100000 frames asked for a 2.9 GB matrix).
pub const MAX_HISTORY: usize = 64;

/// The layout of the stacked observation, so a policy can be built for any modality and
/// PCA size.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct ObsLayout {
    /// Sensing modality.
    pub modality: Modality,
    /// Number of synergy components `n`.
    pub n_components: usize,
    /// History length `h`.
    pub history: usize,
    /// The segments of one frame, in order.
    pub segments: Vec<Segment>,
    /// Values after the stacked frames that only an asymmetric critic reads
    /// ([`CRITIC_STATE_LEN`] with `[env] critic_state = true`, else 0). The actor never
    /// reads them: on the robot they are zeros.
    pub critic_state: usize,
}

/// Length of the privileged simulator state an asymmetric critic reads
/// ([`critic_state`]).
pub const CRITIC_STATE_LEN: usize = 46;

impl ObsLayout {
    /// The layout for a modality, PCA size and history length.
    pub fn new(modality: Modality, n_components: usize, history: usize) -> Self {
        Self::with_action_len(modality, n_components, n_components + 2, history)
    }

    /// The layout whose previous-action segment holds `action_len` values (the action's
    /// continuous components: `n + 2`, or `n + 3` with the grip of
    /// [`crate::env::action::ActionConfig::grip_scale`]).
    pub fn with_action_len(
        modality: Modality,
        n_components: usize,
        action_len: usize,
        history: usize,
    ) -> Self {
        let mut segments = Vec::new();
        let mut off = 0;
        let mut push = |kind, len| {
            segments.push(Segment {
                kind,
                offset: off,
                len,
            });
            off += len;
        };
        push(SegmentKind::PrevAction, action_len);
        if modality != Modality::M1 {
            push(SegmentKind::Tactile, N_TACTILE);
        }
        if matches!(modality, Modality::M3 | Modality::M3G) {
            push(SegmentKind::TorqueLevels, N_TORQUE);
        }
        if modality == Modality::M3G {
            push(SegmentKind::Surface, N_SURFACE);
        }
        push(SegmentKind::JointAngles, N_JOINTS);
        ObsLayout {
            modality,
            n_components,
            history,
            segments,
            critic_state: 0,
        }
    }

    /// The layout with (`on`) or without the critic's privileged state appended.
    pub fn with_critic_state(mut self, on: bool) -> Self {
        self.critic_state = if on { CRITIC_STATE_LEN } else { 0 };
        self
    }

    /// Length of the part the actor reads: the stacked frames.
    pub fn actor_len(&self) -> usize {
        self.frame_len() * self.history
    }

    /// Size of one frame.
    pub fn frame_len(&self) -> usize {
        self.segments.iter().map(|s| s.len).sum()
    }

    /// Size of the observation given to the policy: the stacked frames, then the
    /// critic's privileged state when there is one.
    pub fn len(&self) -> usize {
        self.actor_len() + self.critic_state
    }

    /// Whether the observation is empty (never, for a valid layout).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Builds one frame: the previous action `prev_action` (missing values are zeros),
    /// then what the layout's modality reads of `sensed`.
    pub fn frame(&self, prev_action: &[f32], sensed: &Sensing) -> Vec<f32> {
        let mut out = Vec::with_capacity(self.frame_len());
        for s in &self.segments {
            match s.kind {
                SegmentKind::PrevAction => {
                    out.extend((0..s.len).map(|k| prev_action.get(k).copied().unwrap_or(0.0)))
                }
                SegmentKind::Tactile => {
                    out.extend(sensed.tactile.iter().map(|&t| if t { 1.0 } else { 0.0 }))
                }
                SegmentKind::TorqueLevels => out.extend(
                    sensed
                        .torque_levels
                        .iter()
                        .map(|&l| f32::from(l.min(5)) / 5.0),
                ),
                SegmentKind::JointAngles => {
                    out.extend(sensed.joint_angles.iter().map(|&a| a as f32))
                }
                SegmentKind::Surface => out.extend(sensed.surface.iter().map(|&v| v as f32)),
            }
        }
        out
    }
}

/// What the hand senses at one control step, in whichever world it acts: the simulator
/// fills it in [`crate::env::grasp::GraspEnv`], the robot pipeline from the calibrated
/// sensors (`crate::run::pipeline`). Every modality's frame is built from it
/// ([`ObsLayout::frame`]): a new modality is one [`SegmentKind`], one field here and one
/// producer per world.
#[derive(Debug, Clone, PartialEq)]
pub struct Sensing {
    /// `phi`: the fingertip contacts (FF, MF, RF, LF, TH).
    pub tactile: [bool; N_TACTILE],
    /// `tau`: the actuators' torque levels 0..5.
    pub torque_levels: [u8; N_TORQUE],
    /// `theta`: the joint angles (rad, paper order).
    pub joint_angles: [f64; N_JOINTS],
    /// M3G's surface vectors ([`surface_vectors`]); zeros where the modality does not
    /// read them.
    pub surface: [f64; N_SURFACE],
}

/// The privileged simulator state of an asymmetric critic, [`CRITIC_STATE_LEN`] values,
/// all in the palm frame: the object's position (3, m), orientation (the first two
/// columns of its rotation matrix, 6), linear (3, m/s) and angular velocity (3, rad/s);
/// for FF, MF, RF, LF, TH distal and the palm the vector from the collider's centre to the
/// nearest object surface point (6 x 3, m) and its length (6); the distal phalanges'
/// normal forces on the object (5, N); the object's mass (kg) and friction coefficient.
pub fn critic_state(
    geom: &crate::sim::CriticGeometry,
    tip_forces: &[f64; 5],
    mass: f64,
    friction: f64,
) -> Vec<f32> {
    let inv = geom.palm.inverse();
    let rel = inv * geom.object;
    let r = rel.rotation.to_rotation_matrix();
    let to_palm = |v: &nalgebra::Vector3<f64>| inv.rotation * v;
    let mut out: Vec<f64> = Vec::with_capacity(CRITIC_STATE_LEN);
    out.extend(rel.translation.vector.iter());
    out.extend(r.matrix().column(0).iter());
    out.extend(r.matrix().column(1).iter());
    out.extend(to_palm(&geom.object_linvel).iter());
    out.extend(to_palm(&geom.object_angvel).iter());
    out.extend(surface_vectors(geom));
    out.extend(geom.nearest.iter().map(|(c, p)| (p - c).norm()));
    out.extend(tip_forces.iter());
    out.push(mass);
    out.push(friction);
    debug_assert_eq!(out.len(), CRITIC_STATE_LEN);
    out.into_iter().map(|x| x as f32).collect()
}

/// M3G's surface vectors: for FF, MF, RF, LF, TH distal and the palm, the vector from the
/// collider's centre to the nearest object surface point, in the palm frame (m).
pub fn surface_vectors(geom: &crate::sim::CriticGeometry) -> [f64; N_SURFACE] {
    let rot = geom.palm.rotation.inverse();
    let mut out = [0.0; N_SURFACE];
    for (k, (c, p)) in geom.nearest.iter().enumerate() {
        let v = rot * (p - c);
        out[3 * k..3 * k + 3].copy_from_slice(v.as_slice());
    }
    out
}

/// The stack of the last `h` frames, oldest first, zero-padded at the episode start.
#[derive(Debug, Clone, PartialEq)]
pub struct FrameStack {
    frame_len: usize,
    history: usize,
    frames: std::collections::VecDeque<Vec<f32>>,
}

impl FrameStack {
    /// An empty (all-zero) stack.
    pub fn new(layout: &ObsLayout) -> Self {
        let mut s = FrameStack {
            frame_len: layout.frame_len(),
            history: layout.history,
            frames: Default::default(),
        };
        s.clear();
        s
    }

    /// Resets to all zeros (episode start).
    pub fn clear(&mut self) {
        self.frames = (0..self.history)
            .map(|_| vec![0.0; self.frame_len])
            .collect();
    }

    /// Pushes the newest frame, dropping the oldest.
    pub fn push(&mut self, frame: Vec<f32>) {
        debug_assert_eq!(frame.len(), self.frame_len);
        self.frames.pop_front();
        self.frames.push_back(frame);
    }

    /// The stacked observation `O_t`.
    pub fn stacked(&self) -> Vec<f32> {
        self.frames.iter().flatten().copied().collect()
    }
}

/// The torque levels live in [`crate::util::levels`]; re-exported for callers of
/// `env::obs::torque_level`.
pub use crate::util::levels::torque_level;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn critic_state_is_in_the_palm_frame_hand_computed() {
        use nalgebra::{Isometry3, Point3, Vector3};
        // The palm turned 90 degrees about z at (1, 0, 0); the object at (1, 2, 0) with
        // the world's orientation, moving at +x 0.5 m/s. In the palm frame (x' = y,
        // y' = -x) the object sits at (2, 0, 0) and moves along -y' at 0.5 m/s.
        let palm = Isometry3::new(
            Vector3::new(1.0, 0.0, 0.0),
            Vector3::z() * std::f64::consts::FRAC_PI_2,
        );
        let object = Isometry3::translation(1.0, 2.0, 0.0);
        let mut nearest = [(Point3::origin(), Point3::origin()); 6];
        nearest[0] = (Point3::new(0.0, 0.0, 0.0), Point3::new(0.0, 0.0, 0.03));
        let geom = crate::sim::CriticGeometry {
            palm,
            object,
            object_linvel: Vector3::new(0.5, 0.0, 0.0),
            object_angvel: Vector3::zeros(),
            nearest,
        };
        let s = critic_state(&geom, &[1.0, 0.0, 0.0, 0.0, 2.0], 0.2, 0.8);
        assert_eq!(s.len(), CRITIC_STATE_LEN);
        let close = |a: &[f32], b: &[f32]| a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-6);
        assert!(close(&s[0..3], &[2.0, 0.0, 0.0]), "{:?}", &s[0..3]);
        // Object x axis in the palm frame: world x = -y'.
        assert!(close(&s[3..6], &[0.0, -1.0, 0.0]), "{:?}", &s[3..6]);
        assert!(close(&s[9..12], &[0.0, -0.5, 0.0]), "{:?}", &s[9..12]);
        // FF's vector: 3 cm along z (z' = z), its length 0.03.
        assert!(close(&s[15..18], &[0.0, 0.0, 0.03]));
        assert!((s[33] - 0.03).abs() < 1e-6);
        assert!(close(&s[39..46], &[1.0, 0.0, 0.0, 0.0, 2.0, 0.2, 0.8]));
        let l = ObsLayout::new(Modality::M3, 5, 3).with_critic_state(true);
        assert_eq!((l.actor_len(), l.len()), (168, 168 + CRITIC_STATE_LEN));
        // The grip's extra action value widens the frame, not the synergy count.
        let g = ObsLayout::with_action_len(Modality::M3, 5, 8, 3);
        assert_eq!((g.n_components, g.frame_len()), (5, 57));
    }

    #[test]
    fn sizes_per_modality_hand_computed() {
        // M3G: M3 + 18 surface values.
        assert_eq!(ObsLayout::new(Modality::M3G, 5, 3).frame_len(), 74);
        // PCA5: prev action 5 + 2 = 7; M1 7 + 24 = 31; M2 + 5 = 36; M3 + 20 = 56.
        assert_eq!(ObsLayout::new(Modality::M1, 5, 3).frame_len(), 31);
        assert_eq!(ObsLayout::new(Modality::M2, 5, 3).frame_len(), 36);
        assert_eq!(ObsLayout::new(Modality::M3, 5, 3).frame_len(), 56);
        assert_eq!(ObsLayout::new(Modality::M3, 5, 3).len(), 168);
        assert_eq!(ObsLayout::new(Modality::M3, 10, 3).len(), 3 * 61);
    }

    #[test]
    fn frame_content_and_order() {
        let l = ObsLayout::new(Modality::M3, 3, 3);
        let mut tact = [false; 5];
        tact[4] = true;
        let mut lev = [3u8; 20];
        lev[0] = 5;
        let mut ang = [0.0; 24];
        ang[23] = 1.5;
        let mut sensed = Sensing {
            tactile: tact,
            torque_levels: lev,
            joint_angles: ang,
            surface: [0.0; N_SURFACE],
        };
        let f = l.frame(&[0.5, -1.0, 0.25, 0.0, 1.0], &sensed);
        assert_eq!(f.len(), 5 + 5 + 20 + 24);
        assert_eq!(&f[..5], &[0.5, -1.0, 0.25, 0.0, 1.0]);
        assert_eq!(&f[5..10], &[0.0, 0.0, 0.0, 0.0, 1.0]);
        assert_eq!(f[10], 1.0);
        assert_eq!(f[11], 0.6);
        assert_eq!(f[53], 1.5);
        let m1 = ObsLayout::new(Modality::M1, 3, 3);
        assert_eq!(m1.frame(&[0.0; 5], &sensed).len(), 29);
        // M3G: M3's values, then the 18 surface values before the joint angles.
        let g = ObsLayout::new(Modality::M3G, 3, 3);
        sensed.surface[0] = 0.02;
        sensed.surface[17] = -0.05;
        let f = g.frame(&[0.5, -1.0, 0.25, 0.0, 1.0], &sensed);
        assert_eq!(f.len(), 5 + 5 + 20 + 18 + 24);
        assert_eq!((f[30], f[47], f[71]), (0.02, -0.05, 1.5));
        assert_eq!(g.frame_len(), 72);
    }

    #[test]
    fn segments_serialise_with_their_names_in_order() {
        let g = ObsLayout::new(Modality::M3G, 5, 3);
        let v = serde_json::to_value(&g.segments).unwrap();
        let names: Vec<&str> = g.segments.iter().map(|s| s.kind.name()).collect();
        assert_eq!(
            names,
            [
                "prev_action",
                "tactile",
                "torque_levels",
                "surface",
                "joint_angles"
            ]
        );
        for (s, j) in g.segments.iter().zip(v.as_array().unwrap()) {
            assert_eq!(j["name"], s.kind.name());
            assert_eq!(j["offset"], s.offset);
            assert_eq!(j["len"], s.len);
        }
        assert_eq!(v[3]["offset"], 7 + 5 + 20);
    }

    #[test]
    fn stack_is_zero_padded_and_oldest_first() {
        let l = ObsLayout::new(Modality::M1, 3, 3);
        let mut s = FrameStack::new(&l);
        assert!(s.stacked().iter().all(|&v| v == 0.0));
        s.push(vec![1.0; 29]);
        s.push(vec![2.0; 29]);
        let o = s.stacked();
        assert_eq!(o.len(), 87);
        assert_eq!(o[0], 0.0);
        assert_eq!(o[29], 1.0);
        assert_eq!(o[58], 2.0);
        s.push(vec![3.0; 29]);
        assert_eq!(s.stacked()[0], 1.0);
        s.clear();
        assert!(s.stacked().iter().all(|&v| v == 0.0));
    }
}
