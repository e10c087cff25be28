//! [`SimHandArm`]: the simulator behind the [`HandArm`] interface, with a model of the
//! real hand's raw signals so that calibration, drift compensation and the safety layer
//! are exercised end to end.
//!
//! # Raw-sensor model
//! For backend time `t` (s), fingertip `k` and actuator `j` (all noise Gaussian, drawn from
//! one `ChaCha8Rng` seeded by [`RawModelConfig::seed`] in [`RawModel`], a fixed number of draws per
//! reading so that runs with the same seed see the same noise):
//! - tactile: `raw_k = tactile_offset[k] + tactile_gain[k] * F_k + N(0, tactile_noise)`,
//!   where `F_k` is the normal force (N) between the object and the distal phalanx
//!   ([`HandSim::tip_forces`]). With the hand still, the readings scatter around the
//!   offset (the calibration's lower range); pressed, they rise by the gain times the force
//!   (the upper range).
//! - tendons: `raw_j = tendon_scale * e_j + tendon_offset + tendon_drift_rate * t +
//!   w_j(t) + N(0, tendon_noise)`, where `e_j` is the actuator effort (N m, the PD law the
//!   motors apply, [`HandSim::sensors`]) and `w_j` a random walk with standard deviation
//!   `tendon_drift_walk * sqrt(dt)` per reading interval `dt`. The default scale of 1000
//!   units per N m puts the real robot's thresholds (-200, -100, 0, 100, 200) at
//!   (-0.2, -0.1, 0, 0.1, 0.2) N m, the same torques as the simulator's own thresholds.
//! - joint angles: the simulated angles plus `N(0, joint_noise)`.
//!
//! # Pressing a fingertip
//! Calibration needs the maximum reading while each fingertip is pressed. Pushing each
//! fingertip against a probe in the physics would need a probe body the simulator does not
//! have, so a press is modelled as a KNOWN force added to that fingertip's contact force in
//! the raw model: [`SimHandArm::read_pressed`] returns one reading with `F_k + force`.
//!
//! # Clock, arm and lift
//! - The clock is simulated time ([`RawModelConfig::clock_start_s`] plus the physics time
//!   since construction): [`HandArm::wait`] steps the physics, nothing sleeps.
//! - [`SimHandArm::inject_sensor_dropout`] makes every reading from a given time on repeat
//!   the last fresh one, stamp included (the sensor data stops), for the watchdog.
//! - The UR10e is not simulated (the simulator carries the hand on a vertical lift).
//!   [`ArmMotion::Joints`] places the hand where the arm's forward kinematics puts the
//!   flange (the hand's forearm frame is the flange frame): the world is reset with the
//!   hand there in its current posture and the object back at rest. The simulator only
//!   places hands palm down, so a pose whose palm normal is more than 1 mrad from the
//!   vertical is refused. Where the hand would overlap the object it is raised in 5 mm
//!   steps (at most 10 cm), as a guarded approach that stops at first contact would.
//! - [`ArmMotion::Lift`] runs the simulator's lift ([`HandSim::lift_and_judge`]: its
//!   configured height, ramp and hold); a lift of another height is refused. The judgement
//!   (object held) is reported by [`HandArm::lift_outcome`].

use crate::hardware::{check_duration, ArmMotion, HandArm, HwError, RawSensors};
use crate::perception::pointcloud::CloudError;
use crate::robot::joints::{N_JOINTS, N_TACTILE};
use crate::robot::{Posture, Robot};
use crate::sim::settle::Unsettled;
use crate::sim::{HandSim, LiftOutcome, ObjectSpec, Scene, SimConfig};
use nalgebra::{Isometry3, Point3};

pub use super::raw_model::{RawModel, RawModelConfig};
use super::simulated::{guarded_placement, top_down_placement};

pub use super::simulated::{SimBackendConfig, GUARD_MAX_M, GUARD_STEP_M, MAX_PALM_TILT_RAD};
pub use crate::perception::camera::{camera_cloud, CameraConfig};

/// The simulated hand-arm system (see the module docs).
pub struct SimHandArm {
    sim: HandSim,
    cfg: SimBackendConfig,
    /// The raw-sensor model (noise generator and tendon walk).
    raw: RawModel,
    clock_base: f64,
    dropout_at: Option<f64>,
    last_fresh: Option<RawSensors>,
    extra_force: [f64; N_TACTILE],
    stops: Vec<f64>,
    lift: Option<LiftOutcome>,
    guard_raise: f64,
    /// The object's pose kept through arm moves ([`SimHandArm::settle_for_retry`]); until
    /// then every placement puts it at rest at `cfg.object_xy`, `cfg.object_yaw`.
    kept_object: Option<Isometry3<f64>>,
}

fn sim_err(e: crate::sim::SimError) -> HwError {
    HwError::InvalidCommand {
        field: "simulator".into(),
        detail: e.to_string(),
    }
}

impl SimHandArm {
    /// A simulated hand (`robot`'s Shadow hand) with `object` at rest on the table and the
    /// hand open, its grasp point `home_clearance` above the object's top.
    pub fn new(
        robot: &Robot,
        object: ObjectSpec,
        sim_cfg: SimConfig,
        cfg: SimBackendConfig,
    ) -> Result<SimHandArm, HwError> {
        cfg.validate()?;
        let raw = RawModel::new(cfg.raw.clone())?;
        let top = 2.0 * object.rest_height();
        let sim = HandSim::new(robot, object, sim_cfg).map_err(sim_err)?;
        let clock = cfg.raw.clock_start_s;
        let mut arm = SimHandArm {
            sim,
            raw,
            clock_base: clock,
            dropout_at: None,
            last_fresh: None,
            extra_force: [0.0; N_TACTILE],
            stops: Vec::new(),
            lift: None,
            guard_raise: 0.0,
            kept_object: None,
            cfg,
        };
        let [x, y] = arm.cfg.object_xy;
        let scene = Scene {
            start: Posture::Open.angles(),
            object_xy: [x, y],
            object_yaw: arm.cfg.object_yaw,
            grasp_point: [x, y, top + arm.cfg.home_clearance],
            hand_yaw: 0.0,
        };
        arm.place(scene)?;
        Ok(arm)
    }

    /// Prepares a second attempt after a failed one, as `grasp eval --attempts` does
    /// ([`crate::env::grasp::GraspEnv::prepare_retry`]): opens the hand where the attempt
    /// left it and lets the object settle on the table ([`HandSim::settle_object`]). From
    /// then on, moving the arm keeps the object where it lies instead of placing it at its
    /// configured start. An error says why there is no retry.
    pub fn settle_for_retry(&mut self) -> Result<(), HwError> {
        match self.sim.settle_object(&Posture::Open.angles()) {
            Ok(()) => {}
            Err(Unsettled::PhysicsFailure) => {
                return Err(HwError::Disconnected(format!(
                    "the simulated physics failed while the object settled: {:?}",
                    self.sim.failure()
                )))
            }
            Err(e) => {
                return Err(HwError::InvalidCommand {
                    field: "retry".into(),
                    detail: e.to_string(),
                })
            }
        }
        self.kept_object = self.sim.object_pose();
        Ok(())
    }

    /// The simulator (read-only).
    pub fn sim(&self) -> &HandSim {
        &self.sim
    }

    /// The backend configuration.
    pub fn config(&self) -> &SimBackendConfig {
        &self.cfg
    }

    /// From backend time `at_s` on, every reading repeats the last fresh one (stamp
    /// included): the sensor data stops.
    pub fn inject_sensor_dropout(&mut self, at_s: f64) {
        self.dropout_at = Some(at_s);
    }

    /// Backend times at which [`HandArm::stop`] was called.
    pub fn stop_times(&self) -> &[f64] {
        &self.stops
    }

    /// The simulator's judgement of the last lift.
    pub fn last_lift(&self) -> Option<&LiftOutcome> {
        self.lift.as_ref()
    }

    /// How far the last [`ArmMotion::Joints`] placement was raised to clear the object (m).
    pub fn guard_raise(&self) -> f64 {
        self.guard_raise
    }

    /// The point cloud the depth cameras of `cam` see of the object in its current pose
    /// (world frame, m), with noise drawn from `seed` (see [`camera_cloud`]).
    pub fn camera_cloud(
        &self,
        cam: &CameraConfig,
        seed: u64,
    ) -> Result<Vec<Point3<f64>>, CloudError> {
        camera_cloud(&self.sim, cam, seed)
    }

    /// One reading while fingertip `finger` (0..5: FF, MF, RF, LF, TH) is pressed with
    /// `force_n` newtons (a known force added to its contact force in the raw model).
    pub fn read_pressed(&mut self, finger: usize, force_n: f64) -> Result<RawSensors, HwError> {
        super::raw_model::check_press(finger, force_n)?;
        self.extra_force[finger] = force_n;
        let r = self.read();
        self.extra_force = [0.0; N_TACTILE];
        r
    }

    /// Resets the world with `scene`, raising the hand in [`GUARD_STEP_M`] steps while it
    /// overlaps the object.
    fn place(&mut self, mut scene: Scene) -> Result<(), HwError> {
        self.clock_base += self.sim.time();
        let raised = guarded_placement(|raise| {
            if raise {
                scene.grasp_point[2] += GUARD_STEP_M;
            }
            match &self.kept_object {
                Some(pose) => self.sim.reset_with_object_pose(&scene, pose),
                None => self.sim.reset(&scene),
            }
            .map_err(sim_err)?;
            Ok(self.sim.hand_overlaps_object())
        })?;
        self.guard_raise = raised;
        self.lift = None;
        Ok(())
    }

    /// The scene that puts the hand where the arm at `q` puts the flange.
    fn scene_for_arm(&self, q: &[f64; 6]) -> Result<Scene, HwError> {
        let hand_q = self.sim.targets();
        let (p, hand_yaw) = top_down_placement(self.sim.robot(), &self.cfg.arm_base, &hand_q, q)?;
        Ok(Scene {
            start: hand_q,
            object_xy: self.cfg.object_xy,
            object_yaw: self.cfg.object_yaw,
            grasp_point: [p.x, p.y, p.z],
            hand_yaw,
        })
    }

    fn fresh_reading(&mut self) -> RawSensors {
        let t = self.clock_base + self.sim.time();
        let s = self.sim.sensors();
        let tip = self.sim.tip_forces();
        let force: [f64; N_TACTILE] = std::array::from_fn(|k| tip[k] + self.extra_force[k]);
        self.raw.reading(t, &s.q, &force, &s.effort)
    }
}

impl HandArm for SimHandArm {
    fn read(&mut self) -> Result<RawSensors, HwError> {
        if let Some(at) = self.dropout_at {
            let now = self.now();
            if now >= at {
                return self.last_fresh.ok_or(HwError::Timeout {
                    what: "sensor data (none before the dropout)".into(),
                    waited_s: now - at,
                });
            }
        }
        let r = self.fresh_reading();
        self.last_fresh = Some(r);
        Ok(r)
    }

    fn command_hand(&mut self, targets: &[f64; N_JOINTS]) -> Result<(), HwError> {
        self.sim.set_targets(targets).map_err(sim_err)
    }

    fn move_arm(&mut self, motion: &ArmMotion) -> Result<(), HwError> {
        motion.validate()?;
        match *motion {
            ArmMotion::Joints(q) => {
                let scene = self.scene_for_arm(&q)?;
                self.place(scene)
            }
            ArmMotion::Lift { height_m, .. } => {
                let h = self.sim.config().lift.height;
                if (height_m - h).abs() > 1e-6 {
                    return Err(HwError::InvalidCommand {
                        field: "lift height_m".into(),
                        detail: format!(
                            "the simulator lifts by its configured lift.height {h} m, not {height_m} m"
                        ),
                    });
                }
                let out = self.sim.lift_and_judge();
                let failure = out.failure.clone();
                self.lift = Some(out);
                match failure {
                    Some(f) => Err(HwError::Disconnected(format!(
                        "the simulated physics failed during the lift: {f:?}"
                    ))),
                    None => Ok(()),
                }
            }
        }
    }

    fn stop(&mut self) -> Result<(), HwError> {
        self.stops.push(self.now());
        let (q, _) = self.sim.joint_state();
        self.sim.set_targets(&q).map_err(sim_err)
    }

    fn now(&self) -> f64 {
        self.clock_base + self.sim.time()
    }

    fn wait(&mut self, seconds: f64) -> Result<(), HwError> {
        check_duration(seconds)?;
        let dt = self.sim.config().dt;
        let end = self.sim.time() + seconds;
        while self.sim.time() + 0.5 * dt <= end {
            if !self.sim.step_physics() {
                return Err(HwError::Disconnected(format!(
                    "the simulated physics failed: {:?}",
                    self.sim.failure()
                )));
            }
        }
        Ok(())
    }

    fn lift_outcome(&self) -> Option<bool> {
        self.lift.as_ref().map(|l| l.success)
    }
}

impl super::simulated::SimulatedArm for SimHandArm {
    const NAME: &'static str = "sim";

    fn build(
        robot: &Robot,
        object: ObjectSpec,
        sim_cfg: SimConfig,
        cfg: SimBackendConfig,
    ) -> Result<Self, HwError> {
        SimHandArm::new(robot, object, sim_cfg, cfg)
    }

    fn camera_cloud(&self, cam: &CameraConfig, seed: u64) -> Result<Vec<Point3<f64>>, CloudError> {
        SimHandArm::camera_cloud(self, cam, seed)
    }

    fn read_pressed(&mut self, finger: usize, force_n: f64) -> Result<RawSensors, HwError> {
        SimHandArm::read_pressed(self, finger, force_n)
    }

    fn settle_for_retry(&mut self) -> Result<(), HwError> {
        SimHandArm::settle_for_retry(self)
    }

    fn physics_failure(&self) -> Option<String> {
        self.sim.failure().map(|f| format!("{f:?}"))
    }

    fn failure_report(&self) -> Option<crate::sim::FailureReport> {
        self.sim.failure_report()
    }

    fn lift_report(&self) -> Option<LiftOutcome> {
        self.lift.clone()
    }

    fn deepest_contact(&self) -> Option<(f64, String)> {
        self.sim
            .deepest_contact()
            .map(|c| (c.depth, c.with.clone()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::robot::grasp_map::{root_pose_for, TwoFingerGrasp};
    use crate::robot::{ur10e, Side};
    use nalgebra::Vector3;

    fn arm(cfg: SimBackendConfig) -> SimHandArm {
        let robot = Robot::builtin(Side::Left);
        SimHandArm::new(&robot, ObjectSpec::default_box(), SimConfig::default(), cfg).unwrap()
    }

    #[test]
    fn raw_model_still_readings_sit_at_the_offsets() {
        let mut a = arm(SimBackendConfig::default());
        let r = a.read().unwrap();
        let raw = RawModelConfig::default();
        for k in 0..5 {
            // No contact: offset + noise (sigma 0.3, 6 sigma bound).
            assert!(
                (r.tactile_raw[k] - raw.tactile_offset[k]).abs() < 1.8,
                "{k}"
            );
        }
        // A press of 10 N adds gain * 10.
        let p = a.read_pressed(2, 10.0).unwrap();
        assert!((p.tactile_raw[2] - (305.0 + 1050.0)).abs() < 1.8);
        assert!((p.tactile_raw[0] - 312.0).abs() < 1.8);
        assert!(a.read_pressed(5, 1.0).is_err());
        assert!(a.read_pressed(0, f64::NAN).is_err());
    }

    #[test]
    fn wait_steps_the_clock_and_dropout_freezes_stamps() {
        let mut a = arm(SimBackendConfig::default());
        assert_eq!(a.now(), 0.0);
        a.wait(0.1).unwrap();
        assert!((a.now() - 0.1).abs() < 1e-9, "{}", a.now());
        assert!((a.read().unwrap().stamp - 0.1).abs() < 1e-9);
        a.inject_sensor_dropout(0.15);
        a.wait(0.1).unwrap();
        let r = a.read().unwrap();
        // The last fresh reading was at 0.1 s.
        assert!((r.stamp - 0.1).abs() < 1e-9);
        assert!(a.wait(-1.0).is_err());
    }

    #[test]
    fn linear_drift_shifts_every_tendon_by_rate_times_time() {
        let mut cfg = SimBackendConfig::default();
        cfg.raw.tendon_drift_walk = 0.0;
        let mut a = arm(cfg.clone());
        cfg.raw.clock_start_s = 100.0;
        let mut b = arm(cfg);
        let (ra, rb) = (a.read().unwrap(), b.read().unwrap());
        for j in 0..20 {
            // Same seed, same noise: the difference is the drift 2 units/s * 100 s.
            assert!((rb.tendon_raw[j] - ra.tendon_raw[j] - 200.0).abs() < 1e-6);
        }
        assert!((rb.stamp - 100.0).abs() < 1e-12);
    }

    #[test]
    fn arm_joints_place_the_hand_and_tilted_poses_are_refused() {
        let mut a = arm(SimBackendConfig::default());
        let robot = Robot::builtin(Side::Left);
        let q_hand = a.sim().targets();
        let g = TwoFingerGrasp::top_down(Point3::new(0.0, 0.0, 0.2), 0.4);
        let root = root_pose_for(&robot, &q_hand, &g).unwrap();
        let base = a.config().arm_base.pose();
        let q = ur10e::ik(&(base.inverse() * root), &ur10e::HOME).unwrap();
        let s = a.scene_for_arm(&q).unwrap();
        assert!((s.grasp_point[2] - 0.2).abs() < 1e-6, "{:?}", s.grasp_point);
        assert!(s.grasp_point[0].abs() < 1e-6 && s.grasp_point[1].abs() < 1e-6);
        assert!((s.hand_yaw - 0.4).abs() < 1e-6, "{}", s.hand_yaw);
        a.move_arm(&ArmMotion::Joints(q)).unwrap();
        assert_eq!(a.guard_raise(), 0.0);
        let tilted = TwoFingerGrasp {
            center: Point3::new(0.0, 0.0, 0.2),
            approach: Vector3::new(0.3, 0.0, -1.0),
            closing: Vector3::y(),
        };
        let root = root_pose_for(&robot, &q_hand, &tilted).unwrap();
        let q = ur10e::ik(&(base.inverse() * root), &ur10e::HOME).unwrap();
        let e = a.move_arm(&ArmMotion::Joints(q)).unwrap_err().to_string();
        assert!(e.contains("palm down"), "{e}");
        // A lift of another height than the simulator's is refused.
        let e = a
            .move_arm(&ArmMotion::Lift {
                height_m: 0.3,
                duration_s: 2.0,
            })
            .unwrap_err()
            .to_string();
        assert!(e.contains("lift.height"), "{e}");
    }

    #[test]
    fn cameras_see_the_box_surface_from_both_sides() {
        let a = arm(SimBackendConfig::default());
        let cam = CameraConfig {
            noise_sigma: 0.0,
            ..CameraConfig::default()
        };
        let c = a.camera_cloud(&cam, 0).unwrap();
        assert!(c.len() > 500, "{}", c.len());
        // Every hit lies on the 5 x 5 x 8 cm box resting at the origin ...
        let on_face = |p: &Point3<f64>| {
            let d = [
                (p.x.abs() - 0.025).abs(),
                (p.y.abs() - 0.025).abs(),
                (p.z - 0.04).abs() - 0.04,
            ];
            p.x.abs() <= 0.0251
                && p.y.abs() <= 0.0251
                && (0.0..=0.0801).contains(&p.z)
                && (d[0] < 1e-4 || d[1] < 1e-4 || d[2].abs() < 1e-4)
        };
        assert!(c.iter().all(on_face));
        // ... and each of the four side faces is seen (one camera on each side), the
        // bottom (on the table) is not.
        assert!(c.iter().any(|p| p.x > 0.0249) && c.iter().any(|p| p.x < -0.0249));
        assert!(c.iter().any(|p| p.y > 0.0249) && c.iter().any(|p| p.y < -0.0249));
        assert!(!c
            .iter()
            .any(|p| p.z < 1e-4 && p.x.abs() < 0.024 && p.y.abs() < 0.024));
        // Two views from +-x see the -y face only where it meets the others.
        let two = CameraConfig {
            positions: vec![[0.35, 0.0, 0.35], [-0.35, 0.0, 0.35]],
            ..cam.clone()
        };
        assert!(!a
            .camera_cloud(&two, 0)
            .unwrap()
            .iter()
            .any(|p| p.y < -0.0249 && p.z < 0.079 && p.x.abs() < 0.024));
        assert!(a
            .camera_cloud(
                &CameraConfig {
                    positions: vec![[0.0, 0.0, 0.01]],
                    ..cam
                },
                0
            )
            .is_err());
    }
}
