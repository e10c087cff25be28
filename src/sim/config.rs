//! [`SimConfig`]: every number of the simulator, with defaults, TOML loading and range
//! validation whose errors name the offending field.
//!
//! Units: metres, kilograms, seconds, radians, newtons and newton metres. Motor gains are
//! those of rapier's `MotorModel::ForceBased`: stiffness in N m/rad (N/m for the lift),
//! damping in N m s/rad (N s/m for the lift).

use crate::util::config::{parse_toml, ConfigError};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// The default config file, also embedded as the built-in defaults.
pub const DEFAULT_SIM_TOML: &str = include_str!("../../configs/sim.toml");

/// Error of an invalid simulator configuration.
#[derive(Debug, thiserror::Error)]
pub enum SimConfigError {
    /// The TOML could not be read or parsed.
    #[error(transparent)]
    Load(#[from] ConfigError),
    /// A field is out of its allowed range.
    #[error(
        "sim config: field '{field}' = {}: {message}",
        crate::util::num::short(*.value)
    )]
    Range {
        /// Dotted field name, e.g. `motors.fingers.kp`.
        field: String,
        /// The value found.
        value: f64,
        /// The allowed range.
        message: String,
    },
}

/// Smallest physics step accepted (s): 10 kHz, 40x finer than the default.
pub const MIN_DT: f64 = 1e-4;
/// Longest control period accepted (s): ten times the default.
pub const MAX_CONTROL_PERIOD: f64 = 2.0;
/// Longest lift ramp and hold accepted (s).
pub const MAX_LIFT_TIME: f64 = 10.0;

/// Stiffness, damping of a group of position motors.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Gains {
    /// Stiffness kp (N m/rad, or N/m for the lift).
    pub kp: f64,
    /// Damping kd (N m s/rad, or N s/m for the lift).
    pub kd: f64,
}

/// Motor gains per joint group.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MotorGains {
    /// FF, MF, RF, LF joints (J5..J1).
    pub fingers: Gains,
    /// TH joints.
    pub thumb: Gains,
    /// WRJ2 and WRJ1.
    pub wrist: Gains,
    /// The prismatic lift joint standing in for the UR10e.
    pub lift: Gains,
    /// Largest force the lift motor may apply (N).
    pub lift_max_force: f64,
}

impl MotorGains {
    /// The gains of the hand joint named `name` (any side prefix): the wrist's for WR
    /// joints, the thumb's for TH joints, the fingers' otherwise.
    pub fn for_joint(&self, name: &str) -> Gains {
        let name = crate::robot::joints::canonical_name(name);
        if name.starts_with("WR") {
            self.wrist
        } else if name.starts_with("TH") {
            self.thumb
        } else {
            self.fingers
        }
    }
}

/// Contact friction coefficients (combined with the MIN rule).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Friction {
    /// Hand colliders (rubber pads).
    pub hand: f64,
    /// The table top.
    pub table: f64,
}

/// Sensor models.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SensorConfig {
    /// Normal force (N) above which a fingertip reports contact.
    pub tactile_threshold: f64,
    /// Sim torque units per N m (the paper's thresholds are in these units).
    pub torque_scale: f64,
    /// Increasing thresholds mapping a torque reading to levels 0..=len.
    pub torque_thresholds: Vec<f64>,
}

/// The lift that ends an episode.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LiftConfig {
    /// How far the hand is raised (m).
    pub height: f64,
    /// Duration of the smooth ramp (s).
    pub ramp_time: f64,
    /// Hold time after the ramp before judging (s).
    pub hold_time: f64,
    /// The object's lowest point must be this high above the table top for success (m).
    pub success_height: f64,
    /// End the lift early once its outcome is decided: every hand collider is above the
    /// object's highest point (the hand only rises, so it cannot carry the object any
    /// more). Judged as at the end: a failure.
    #[serde(default = "default_true")]
    pub stop_when_dropped: bool,
}

/// How the joints' PD position control is simulated.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum DriveModel {
    /// An implicit joint spring and damper folded into the multibody's mass matrix (as
    /// MuJoCo does with actuators): no solver row. The spring's rest point is moved before
    /// every physics step so that the PD effort it applies, `kp (target - q) - kd qdot`, is
    /// clamped to the joint's effort limit.
    #[default]
    Spring,
    /// rapier's force-based position motor: one solver row per joint, each of which costs
    /// a dense solve against the hand multibody's 25 x 25 mass matrix in every step.
    MotorRow,
}

impl<'de> Deserialize<'de> for DriveModel {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        named(
            d,
            &[
                ("spring", DriveModel::Spring),
                ("motor_row", DriveModel::MotorRow),
            ],
        )
    }
}

/// How the hand multibody's Coriolis and gyroscopic terms are integrated.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum CoriolisModel {
    /// rapier's semi-implicit treatment: the terms' velocity derivative joins the matrix
    /// of the free acceleration, a second, unsymmetric matrix built and factored every
    /// step (with an energy check that falls back to the explicit terms).
    #[default]
    Implicit,
    /// As explicit forces (MuJoCo's Euler integrator): the free acceleration is solved
    /// with the mass matrix the constraint rows already factor (patch round 5,
    /// vendor/README.md).
    Explicit,
}

impl<'de> Deserialize<'de> for CoriolisModel {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        named(
            d,
            &[
                ("implicit", CoriolisModel::Implicit),
                ("explicit", CoriolisModel::Explicit),
            ],
        )
    }
}

/// Which joint limits become solver rows.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum LimitRows {
    /// Only the limits of joints within `limit_margin + |qdot| dt` of a bound (rapier emits
    /// a row for every enabled limit, even one far from its bound, where it does nothing).
    #[default]
    Near,
    /// Every limit in every step (rapier's behaviour).
    Always,
}

impl<'de> Deserialize<'de> for LimitRows {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        named(
            d,
            &[("near", LimitRows::Near), ("always", LimitRows::Always)],
        )
    }
}

/// Deserialises a unit enum from its snake_case name; any other value, a number
/// included, is an error listing the valid names (`coriolis = 1`).
fn named<'de, D, T>(d: D, names: &'static [(&'static str, T)]) -> Result<T, D::Error>
where
    D: serde::Deserializer<'de>,
    T: Copy + 'static,
{
    struct Names<T: 'static>(&'static [(&'static str, T)]);
    impl<'de, T: Copy + 'static> serde::de::Visitor<'de> for Names<T> {
        type Value = T;
        fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
            let list: Vec<String> = self.0.iter().map(|(n, _)| format!("\"{n}\"")).collect();
            write!(f, "one of {}", list.join(", "))
        }
        fn visit_str<E: serde::de::Error>(self, v: &str) -> Result<T, E> {
            self.0
                .iter()
                .find(|(n, _)| *n == v)
                .map(|(_, t)| *t)
                .ok_or_else(|| E::invalid_value(serde::de::Unexpected::Str(v), &self))
        }
    }
    d.deserialize_any(Names(names))
}

fn default_prediction_distance() -> f64 {
    0.02
}

fn default_limit_margin() -> f64 {
    0.05
}

fn default_true() -> bool {
    true
}

/// The softness of rapier's contact constraints: each contact acts as a spring-damper of
/// this natural frequency and damping ratio scaled by the pair's effective mass, so under a
/// steady push `F` it settles at a penetration of about `F / (m_eff (2 pi f)^2)`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ContactConfig {
    /// Natural frequency (Hz) of contacts between two moving bodies (hand and object);
    /// rapier's default is 30.
    #[serde(default = "default_contact_frequency")]
    pub natural_frequency: f64,
    /// Damping ratio of those contacts; rapier's default is 10.
    #[serde(default = "default_contact_damping")]
    pub damping_ratio: f64,
    /// Natural frequency (Hz) of contacts with a fixed body (the table); rapier's
    /// default is 60.
    #[serde(default = "default_static_contact_frequency")]
    pub static_natural_frequency: f64,
    /// Damping ratio of contacts with a fixed body; rapier's default is 10.
    #[serde(default = "default_contact_damping")]
    pub static_damping_ratio: f64,
    /// Check every contact manifold that parry's GJK/EPA returns against the shapes'
    /// geometry and compute a wrong one again, and compute the fingertips' (balls')
    /// contacts with convex hulls exactly ([`crate::sim::contact`]); off (parry's contacts
    /// as they are) when absent.
    #[serde(default)]
    pub check_normals: bool,
    /// A library object meets the table with the convex hull of its parts, in one
    /// manifold of at most four points (spanning where it touches, then where it may
    /// touch next), instead of part by part ([`crate::sim::contact`]); off when absent.
    #[serde(default)]
    pub table_hull: bool,
    /// With `table_hull`: how many times faster than other contacts with the table the
    /// solver corrects the hull's penetration into it (rapier's per-manifold stiffness),
    /// so that its few points hold the object as firmly as the parts' many did; 1 when
    /// absent.
    #[serde(default = "default_table_hull_stiffness")]
    pub table_hull_stiffness: f64,
    /// rapier's contact recycling (m): a colliding pair whose relative pose drifted less
    /// than this since its last contact computation keeps its contact points and normal
    /// frozen instead of computing them again; 0 turns recycling off. rapier's default,
    /// 0.05, is kept when the field is absent (see configs/sim.toml).
    #[serde(default = "default_recycle_distance")]
    pub recycle_distance: f64,
}

fn default_pgs_iterations() -> usize {
    1
}

fn default_table_hull_stiffness() -> f64 {
    1.0
}

fn default_recycle_distance() -> f64 {
    0.05
}

fn default_contact_frequency() -> f64 {
    30.0
}

fn default_static_contact_frequency() -> f64 {
    60.0
}

fn default_contact_damping() -> f64 {
    10.0
}

impl Default for ContactConfig {
    /// rapier's defaults.
    fn default() -> Self {
        ContactConfig {
            natural_frequency: default_contact_frequency(),
            damping_ratio: default_contact_damping(),
            static_natural_frequency: default_static_contact_frequency(),
            static_damping_ratio: default_contact_damping(),
            check_normals: false,
            table_hull: false,
            table_hull_stiffness: default_table_hull_stiffness(),
            recycle_distance: default_recycle_distance(),
        }
    }
}

/// Limits that end an episode with a physics failure.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FailureConfig {
    /// Largest body speed (m/s).
    pub max_speed: f64,
    /// Largest distance of the object from its start position (m).
    pub max_object_travel: f64,
    /// Deepest allowed penetration of any contact with the object (m).
    pub max_penetration: f64,
}

/// All numbers of the simulator.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SimConfig {
    /// Physics time step (s).
    pub dt: f64,
    /// Solver substeps per physics step (rapier's `num_solver_iterations`).
    pub substeps: usize,
    /// Projected Gauss-Seidel iterations per substep (rapier's
    /// `num_internal_pgs_iterations`); rapier's default, 1, when absent.
    #[serde(default = "default_pgs_iterations")]
    pub pgs_iterations: usize,
    /// rapier's `max_ccd_substeps`: 0 turns continuous collision detection off (default).
    /// Rapier otherwise sweeps every fast body against the table each step, and for a
    /// compound object it recomputes each convex part's mass properties in every sweep.
    /// Off, the scripted grasps gave identical outcomes 2.5x faster (see configs/sim.toml).
    #[serde(default)]
    pub ccd_substeps: usize,
    /// rapier's `contact_clustering`: merge the contact points of a compound's many
    /// manifolds into a few per pair. On (rapier's default), the chosen points change from
    /// step to step and flat-based convex objects creep across the table (see
    /// configs/sim.toml).
    #[serde(default)]
    pub contact_clustering: bool,
    /// Angular damping of the object (1/s): a stand-in for rolling resistance, which rapier
    /// lacks. Without it, rounded objects rock on their facets forever (see
    /// configs/sim.toml).
    #[serde(default)]
    pub object_angular_damping: f64,
    /// How the joints' PD control is simulated (see configs/sim.toml).
    #[serde(default)]
    pub drive: DriveModel,
    /// How the Coriolis and gyroscopic terms are integrated (see configs/sim.toml);
    /// rapier's semi-implicit treatment when absent.
    #[serde(default)]
    pub coriolis: CoriolisModel,
    /// Which joint limits become solver rows (see configs/sim.toml).
    #[serde(default)]
    pub limit_rows: LimitRows,
    /// Distance to a joint bound (rad, m for the lift) within which its limit row is
    /// emitted with `limit_rows = "near"`; the distance covered in one step at the joint's
    /// current speed is added.
    #[serde(default = "default_limit_margin")]
    pub limit_margin: f64,
    /// rapier's contact prediction distance (m, its `normalized_prediction_distance` at a
    /// length unit of 1 m): pairs closer than this get contact points, and solver rows,
    /// before they touch. rapier's default, 0.02, is kept when the field is absent (see
    /// configs/sim.toml for the measured trade).
    #[serde(default = "default_prediction_distance")]
    pub prediction_distance: f64,
    /// The softness of contacts (rapier's defaults when the section is absent; see
    /// configs/sim.toml).
    #[serde(default)]
    pub contacts: ContactConfig,
    /// Seconds one control action lasts.
    pub control_period: f64,
    /// Gravity along world z (m/s^2, negative: down).
    pub gravity: f64,
    /// Motor gains.
    pub motors: MotorGains,
    /// Friction coefficients.
    pub friction: Friction,
    /// Sensor models.
    pub sensors: SensorConfig,
    /// The lift.
    pub lift: LiftConfig,
    /// Failure detection.
    pub failure: FailureConfig,
}

impl Default for SimConfig {
    fn default() -> Self {
        // The embedded file is part of the build and covered by a unit test.
        parse_toml(Path::new("configs/sim.toml"), DEFAULT_SIM_TOML)
            .unwrap_or_else(|e| panic!("embedded configs/sim.toml is invalid: {e}"))
    }
}

/// A range error of `field`.
fn bad(field: &str, value: f64, message: &str) -> SimConfigError {
    SimConfigError::Range {
        field: field.into(),
        value,
        message: message.into(),
    }
}

/// `v` must be finite and positive.
fn pos(f: &str, v: f64) -> Result<(), SimConfigError> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(bad(f, v, "must be a finite number > 0"))
    }
}

/// `v` must be finite and not negative.
fn nonneg(f: &str, v: f64) -> Result<(), SimConfigError> {
    if v.is_finite() && v >= 0.0 {
        Ok(())
    } else {
        Err(bad(f, v, "must be a finite number >= 0"))
    }
}

/// A friction coefficient: in [0, 1].
fn fric(f: &str, v: f64) -> Result<(), SimConfigError> {
    if v.is_finite() && (0.0..=1.0).contains(&v) {
        Ok(())
    } else {
        Err(bad(f, v, "friction must be in [0, 1]"))
    }
}

/// The shipped simulator config, from the repository root: it holds the built-in
/// defaults.
pub const DEFAULT_PATH: &str = "configs/sim.toml";

impl SimConfig {
    /// The simulator config of an optional file, by one rule for every command, training
    /// and the checkpoints' saved configs: the file when one is named, else the built-in
    /// defaults. The shipped file ([`DEFAULT_PATH`]) named but absent from the working
    /// folder (a command run outside the repository) is the built-in defaults it holds;
    /// any other file named must exist and be valid.
    pub fn load_or_default(path: Option<&Path>) -> Result<SimConfig, SimConfigError> {
        match path {
            Some(p) if p.exists() || p != Path::new(DEFAULT_PATH) => SimConfig::load(p),
            _ => Ok(SimConfig::default()),
        }
    }

    /// [`SimConfig::load_or_default`] for a `--sim-config`-style flag: the error says
    /// `loading the simulator config PATH` before its cause.
    pub fn load_flag(path: Option<&Path>) -> Result<SimConfig, crate::util::step::StepError> {
        use crate::util::step::StepContext;
        SimConfig::load_or_default(path).step(|| {
            format!(
                "loading the simulator config {}",
                path.map_or_else(String::new, |p| p.display().to_string())
            )
        })
    }

    /// Loads and validates a TOML file.
    pub fn load(path: &Path) -> Result<SimConfig, SimConfigError> {
        let c: SimConfig = crate::util::config::load_toml(path)?;
        c.validate()?;
        Ok(c)
    }

    /// Parses and validates TOML text (`path` names it in errors).
    pub fn parse(path: &Path, text: &str) -> Result<SimConfig, SimConfigError> {
        let c: SimConfig = parse_toml(path, text)?;
        c.validate()?;
        Ok(c)
    }

    /// Number of physics steps in one control period (at least 1).
    pub fn steps_per_control(&self) -> usize {
        ((self.control_period / self.dt).round() as usize).max(1)
    }

    /// Checks every number's range; the error names the first bad field.
    pub fn validate(&self) -> Result<(), SimConfigError> {
        self.check_solver()?;
        self.check_contacts()?;
        self.check_control_and_gravity()?;
        self.check_drives_and_sensors()?;
        self.check_lift()?;
        self.check_failure()?;
        Ok(())
    }

    /// The integrator and solver: time step, iterations, damping, margins.
    fn check_solver(&self) -> Result<(), SimConfigError> {
        pos("dt", self.dt)?;
        // Bounded below too: a tiny step passes `> 0` but never finishes an episode.
        if !(MIN_DT..=0.05).contains(&self.dt) {
            return Err(bad("dt", self.dt, "must be in [1e-4, 0.05] s"));
        }
        for (field, n) in [
            ("substeps", self.substeps),
            ("pgs_iterations", self.pgs_iterations),
        ] {
            if !(1..=64).contains(&n) {
                return Err(bad(field, n as f64, "must be in 1..=64"));
            }
        }
        if self.ccd_substeps > 16 {
            return Err(bad(
                "ccd_substeps",
                self.ccd_substeps as f64,
                "must be in 0..=16",
            ));
        }
        nonneg("object_angular_damping", self.object_angular_damping)?;
        if self.object_angular_damping > 10.0 {
            return Err(bad(
                "object_angular_damping",
                self.object_angular_damping,
                "must be at most 10 1/s",
            ));
        }
        pos("limit_margin", self.limit_margin)?;
        if self.limit_margin > 1.0 {
            return Err(bad(
                "limit_margin",
                self.limit_margin,
                "must be at most 1 rad",
            ));
        }
        pos("prediction_distance", self.prediction_distance)?;
        if self.prediction_distance > 0.1 {
            return Err(bad(
                "prediction_distance",
                self.prediction_distance,
                "must be at most 0.1 m",
            ));
        }
        Ok(())
    }

    /// The contact model: stiffness, damping, the table hull, recycling.
    fn check_contacts(&self) -> Result<(), SimConfigError> {
        let c = &self.contacts;
        for (field, v) in [
            ("contacts.natural_frequency", c.natural_frequency),
            (
                "contacts.static_natural_frequency",
                c.static_natural_frequency,
            ),
        ] {
            pos(field, v)?;
            if v > 1000.0 {
                return Err(bad(field, v, "must be at most 1000 Hz"));
            }
        }
        for (field, v) in [
            ("contacts.damping_ratio", c.damping_ratio),
            ("contacts.static_damping_ratio", c.static_damping_ratio),
        ] {
            pos(field, v)?;
            if v > 100.0 {
                return Err(bad(field, v, "must be at most 100"));
            }
        }
        if !(1.0..=8.0).contains(&c.table_hull_stiffness) {
            return Err(bad(
                "contacts.table_hull_stiffness",
                c.table_hull_stiffness,
                "must be in [1, 8]",
            ));
        }
        nonneg("contacts.recycle_distance", c.recycle_distance)?;
        if c.recycle_distance > 0.1 {
            return Err(bad(
                "contacts.recycle_distance",
                c.recycle_distance,
                "must be at most 0.1 m",
            ));
        }
        Ok(())
    }

    /// The control period and gravity (which must pull down).
    fn check_control_and_gravity(&self) -> Result<(), SimConfigError> {
        pos("control_period", self.control_period)?;
        if self.control_period < self.dt {
            return Err(bad(
                "control_period",
                self.control_period,
                "must be at least dt",
            ));
        }
        if self.control_period > MAX_CONTROL_PERIOD {
            return Err(bad(
                "control_period",
                self.control_period,
                "must be at most 2 s",
            ));
        }
        if !self.gravity.is_finite() || self.gravity.abs() > 100.0 {
            return Err(bad("gravity", self.gravity, "must be finite, |g| <= 100"));
        }
        // Cross-field checks: settings each valid alone that together make every episode
        // fail or succeed regardless of the grasp.
        if self.gravity >= 0.0 {
            return Err(bad(
                "gravity",
                self.gravity,
                "must be negative (m/s^2 along z, which points up; Earth's is -9.81): with \
                 none or upward gravity an object floats and every lift is judged a success",
            ));
        }
        Ok(())
    }

    /// The drives, friction and sensors.
    fn check_drives_and_sensors(&self) -> Result<(), SimConfigError> {
        for (name, g) in [
            ("fingers", self.motors.fingers),
            ("thumb", self.motors.thumb),
            ("wrist", self.motors.wrist),
            ("lift", self.motors.lift),
        ] {
            pos(&format!("motors.{name}.kp"), g.kp)?;
            nonneg(&format!("motors.{name}.kd"), g.kd)?;
        }
        pos("motors.lift_max_force", self.motors.lift_max_force)?;
        fric("friction.hand", self.friction.hand)?;
        fric("friction.table", self.friction.table)?;
        nonneg("sensors.tactile_threshold", self.sensors.tactile_threshold)?;
        pos("sensors.torque_scale", self.sensors.torque_scale)?;
        let th = &self.sensors.torque_thresholds;
        if th.is_empty() || th.len() > 16 {
            return Err(bad(
                "sensors.torque_thresholds",
                th.len() as f64,
                "needs 1 to 16 thresholds",
            ));
        }
        for (k, v) in th.iter().enumerate() {
            if !v.is_finite() {
                return Err(bad(
                    &format!("sensors.torque_thresholds[{k}]"),
                    *v,
                    "must be finite",
                ));
            }
            if k > 0 && *v <= th[k - 1] {
                return Err(bad(
                    &format!("sensors.torque_thresholds[{k}]"),
                    *v,
                    "thresholds must increase",
                ));
            }
        }
        Ok(())
    }

    /// The lift test: heights and times.
    fn check_lift(&self) -> Result<(), SimConfigError> {
        pos("lift.height", self.lift.height)?;
        if self.lift.height > 1.0 {
            return Err(bad("lift.height", self.lift.height, "must be at most 1 m"));
        }
        pos("lift.ramp_time", self.lift.ramp_time)?;
        if self.lift.ramp_time > MAX_LIFT_TIME {
            return Err(bad(
                "lift.ramp_time",
                self.lift.ramp_time,
                "must be at most 10 s",
            ));
        }
        nonneg("lift.hold_time", self.lift.hold_time)?;
        if self.lift.hold_time > MAX_LIFT_TIME {
            return Err(bad(
                "lift.hold_time",
                self.lift.hold_time,
                "must be at most 10 s",
            ));
        }
        nonneg("lift.success_height", self.lift.success_height)?;
        if self.lift.success_height >= self.lift.height {
            return Err(bad(
                "lift.success_height",
                self.lift.success_height,
                &format!(
                    "must be below lift.height {} m: the object rises at most as far as the \
                     hand, so every lift would fail",
                    crate::util::num::short(self.lift.height)
                ),
            ));
        }
        Ok(())
    }

    /// The physics-failure thresholds, and contacts stiff enough to rest on within them.
    fn check_failure(&self) -> Result<(), SimConfigError> {
        pos("failure.max_speed", self.failure.max_speed)?;
        pos("failure.max_object_travel", self.failure.max_object_travel)?;
        pos("failure.max_penetration", self.failure.max_penetration)?;
        for (field, f) in [
            (
                "contacts.natural_frequency",
                self.contacts.natural_frequency,
            ),
            (
                "contacts.static_natural_frequency",
                self.contacts.static_natural_frequency,
            ),
        ] {
            // A body resting on such a contact settles about g / (2 pi f)^2 deep.
            let sag = self.gravity.abs() / (2.0 * std::f64::consts::PI * f).powi(2);
            if f.is_finite() && f > 0.0 && sag >= self.failure.max_penetration {
                let min = (self.gravity.abs() / self.failure.max_penetration).sqrt()
                    / (2.0 * std::f64::consts::PI);
                return Err(bad(
                    field,
                    f,
                    &format!(
                        "too soft: a body resting on such a contact sinks about {} m, beyond \
                         failure.max_penetration {} m, so every episode would end in a \
                         physics failure; use more than {:.1} Hz (rapier's default is 30)",
                        if sag < 1e3 {
                            format!("{sag:.3}")
                        } else {
                            format!("{sag:.2e}")
                        },
                        crate::util::num::short(self.failure.max_penetration),
                        min
                    ),
                ));
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests;
