//! The scripted close-and-lift of `grasp sim` (the paper's baseline 1, Sec. V-D): the hand
//! closes along a human-like trajectory from the start posture to a power-grasp posture;
//! each joint tracks it until it reaches its target or its torque limit (its actuator's
//! torque level reaches the top or bottom level), then the hand lifts and the grasp is
//! judged.

use super::sensors::Sensors;
use super::world::{HandSim, LiftOutcome};
use crate::robot::joints::{hand_index, COUPLED_FINGERS, HAND_JOINTS};
use serde::Serialize;

/// The closed power-grasp posture the script closes toward (24 angles, paper order):
/// fingers flexed (J3 1.3 rad, J0 = J1 + J2 = 2.2 rad), thumb opposed and flexed.
pub fn power_grasp() -> [f64; 24] {
    let mut q = [0.0; 24];
    let mut set = |n: &str, v: f64| {
        if let Some(i) = hand_index(n) {
            q[i] = v;
        }
    };
    for f in COUPLED_FINGERS {
        set(&format!("{f}J3"), 1.3);
        set(&format!("{f}J2"), 1.1);
        set(&format!("{f}J1"), 1.1);
    }
    set("LFJ5", 0.3);
    set("THJ5", 0.6);
    set("THJ4", 1.2);
    set("THJ3", 0.2);
    set("THJ2", 0.5);
    set("THJ1", 1.2);
    q
}

/// Index of the actuator (0..20) that drives each of the 24 hand joints.
pub fn actuator_of_joint() -> [usize; 24] {
    let mut out = [0; 24];
    let mut a = 0;
    let mut i = 0;
    while i < 24 {
        let name = HAND_JOINTS[i];
        out[i] = a;
        if COUPLED_FINGERS.contains(&&name[..2]) && name.ends_with("J2") {
            out[i + 1] = a;
            i += 2;
        } else {
            i += 1;
        }
        a += 1;
    }
    out
}

/// One control step of the script.
#[derive(Debug, Clone, Serialize)]
pub struct ScriptStep {
    /// Control step index.
    pub step: usize,
    /// Phase: `close` or `hold`.
    pub phase: &'static str,
    /// Targets sent (rad, paper order).
    pub targets: Vec<f64>,
    /// Sensor readings at the end of the step.
    pub sensors: Sensors,
    /// Object centre height (m).
    pub object_z: f64,
}

/// What the script did.
#[derive(Debug, Clone, Serialize)]
pub struct ScriptResult {
    /// Per control step.
    pub steps: Vec<ScriptStep>,
    /// The lift outcome, when lifted.
    pub lift: Option<LiftOutcome>,
    /// Physics steps in all.
    pub physics_steps: u64,
    /// Simulated seconds.
    pub sim_time: f64,
}

/// Options of the script.
#[derive(Debug, Clone, Copy)]
pub struct ScriptOptions {
    /// Close the hand (else the targets stay at the start posture).
    pub close: bool,
    /// Lift and judge at the end.
    pub lift: bool,
    /// Control steps of the closing trajectory.
    pub close_steps: usize,
    /// Control steps holding the final targets before the lift.
    pub hold_steps: usize,
}

impl Default for ScriptOptions {
    fn default() -> Self {
        ScriptOptions {
            close: true,
            lift: true,
            close_steps: 5,
            hold_steps: 2,
        }
    }
}

/// Runs the script from the sim's current state (call [`HandSim::reset`] first).
pub fn close_and_lift(sim: &mut HandSim, opts: ScriptOptions, closed: &[f64; 24]) -> ScriptResult {
    let start = sim.targets();
    let act = actuator_of_joint();
    let top = sim.config().sensors.torque_thresholds.len() as u8;
    let mut targets = start;
    let mut stopped = [false; 24];
    let mut steps = Vec::new();
    let n = opts.close_steps.max(1);
    for k in 0..opts.close_steps + opts.hold_steps {
        let phase = if k < opts.close_steps {
            "close"
        } else {
            "hold"
        };
        if opts.close && k < opts.close_steps {
            // Smooth (cubic) progress along the straight line in joint space; wrist held.
            let s = (k + 1) as f64 / n as f64;
            let s = s * s * (3.0 - 2.0 * s);
            for j in 2..24 {
                if !stopped[j] {
                    targets[j] = start[j] + (closed[j] - start[j]) * s;
                }
            }
        }
        // Targets are finite by construction.
        let _ = sim.set_targets(&targets);
        let ok = sim.step_control();
        let sensors = sim.sensors();
        for j in 2..24 {
            let lvl = sensors.torque_level[act[j]];
            if lvl == 0 || lvl == top {
                stopped[j] = true;
            }
        }
        steps.push(ScriptStep {
            step: k,
            phase,
            targets: sim.targets().to_vec(),
            sensors,
            object_z: sim.object_position().z,
        });
        if !ok {
            break;
        }
    }
    let lift = opts.lift.then(|| sim.lift_and_judge());
    ScriptResult {
        steps,
        lift,
        physics_steps: sim.physics_steps(),
        sim_time: sim.time(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn actuator_map_matches_the_actuator_list() {
        let a = actuator_of_joint();
        let specs = crate::robot::joints::actuators();
        for (j, &k) in a.iter().enumerate() {
            assert!(
                specs[k].joints.contains(&HAND_JOINTS[j]),
                "{}",
                HAND_JOINTS[j]
            );
        }
        assert_eq!(a[23], 19);
    }
}
