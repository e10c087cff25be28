//! `grasp calibrate`: the tactile calibration of Sec. V-C, saved for `grasp run`.

use anyhow::{bail, Context, Result};
use clap::Args;
use grasp::run::calibrate::CalibrationReport;
use std::path::PathBuf;

use super::Global;
use super::{calibrate_sim, sim_backend, sim_config, sim_object, Backend};

/// Calibrate the fingertip sensors: lower range = mean of 10 still readings, upper range
/// = maximum while each fingertip is pressed, contact above 0.3 % of the range.
#[derive(Debug, Args)]
#[command(after_help = "Examples:
  grasp calibrate --backend sim --out tactile.json
  grasp calibrate --backend ros --ros-url ws://robot:9090 --press-seconds 4 --out tactile.json --json

The sim backend models a press as a known force (--press-force) added to the fingertip's
contact force in its raw-sensor model. On the robot, press each fingertip when asked;
it is read for --press-seconds.")]
pub struct CalibrateArgs {
    /// The robot: sim or ros.
    #[arg(long, value_enum, default_value = "sim")]
    pub backend: Backend,
    /// Where to write the calibration (JSON).
    #[arg(long)]
    pub out: PathBuf,
    /// Still readings averaged into the lower range (at least 10).
    #[arg(long, default_value_t = 10)]
    pub still: usize,
    /// Contact threshold as a fraction of the range.
    #[arg(long, default_value_t = grasp::hardware::calibration::DEFAULT_THRESHOLD_FRACTION)]
    pub fraction: f64,
    /// Sim: the force of a press (N).
    #[arg(long, default_value_t = 10.0)]
    pub press_force: f64,
    /// Sim: object on the table (it does not touch the hand).
    #[arg(long, default_value = "box")]
    pub object: String,
    /// Sim: simulator config (TOML).
    #[arg(long)]
    pub sim_config: Option<PathBuf>,
    /// Robot: seconds each fingertip is read while pressed.
    #[arg(long, default_value_t = 3.0)]
    pub press_seconds: f64,
    /// Robot: rosbridge websocket.
    #[arg(long, default_value = "ws://localhost:9090")]
    pub ros_url: String,
}

pub fn run(a: CalibrateArgs, g: &Global) -> Result<()> {
    if a.still < grasp::hardware::calibration::MIN_STILL_READINGS {
        bail!("--still must be at least 10 (Sec. V-C), got {}", a.still);
    }
    {
        use grasp::util::fsx::{check_outputs, check_writable_file, Named};
        let mut inputs = Vec::new();
        if let Some(p) = &a.sim_config {
            inputs.push(Named::new("--sim-config", p));
        }
        let objects = grasp::objects::sets::files_read(&a.object);
        inputs.extend(objects.iter().map(|p| Named::new("--object", p)));
        check_outputs(&inputs, &[Named::new("--out", &a.out)], &[])?;
        // Checked before the presses: a calibration is not thrown away by its write.
        check_writable_file(&a.out)
            .map_err(|e| anyhow::anyhow!("--out {}: {}", a.out.display(), e.source))?;
    }
    if a.backend != Backend::Ros {
        // A fingertip press is a few newtons; 1000 N bounds any plausible one.
        if !(a.press_force.is_finite() && a.press_force > 0.0 && a.press_force <= 1000.0) {
            bail!(
                "--press-force must be a number of newtons in (0, 1000], got {}",
                grasp::util::num::short(a.press_force)
            );
        }
    }
    let report: CalibrationReport = match a.backend {
        Backend::Sim => sim_calibrate::<grasp::run::sim_backend::SimHandArm>(&a, g)?,
        #[cfg(feature = "mujoco")]
        Backend::Mujoco => sim_calibrate::<grasp::run::mujoco_backend::MujocoHandArm>(&a, g)?,
        #[cfg(not(feature = "mujoco"))]
        Backend::Mujoco => bail!(grasp::run::request::NO_MUJOCO),
        Backend::Ros => ros_calibrate(&a)?,
    };
    report
        .calibration
        .save(&a.out)
        .with_context(|| format!("saving {}", a.out.display()))?;
    if g.json {
        let j = serde_json::json!({ "out": a.out, "report": report });
        println!("{}", serde_json::to_string_pretty(&j)?);
    } else {
        println!(
            "{:<4} {:>10} {:>10} {:>10} {:>10}",
            "tip", "lower", "still max", "threshold", "upper"
        );
        for (k, f) in grasp::robot::joints::FINGERS.iter().enumerate() {
            println!(
                "{:<4} {:>10.2} {:>10.2} {:>10.2} {:>10.2}",
                f,
                report.calibration.lower[k],
                report.still_max[k],
                report.thresholds[k],
                report.calibration.upper[k]
            );
        }
        println!("saved to {}", a.out.display());
    }
    Ok(())
}

/// The calibration of the simulated backend `A`.
fn sim_calibrate<A: grasp::run::simulated::SimulatedArm>(
    a: &CalibrateArgs,
    g: &Global,
) -> Result<CalibrationReport> {
    let mut arm: A = sim_backend(
        sim_object(&a.object)?,
        sim_config(a.sim_config.as_ref())?,
        g.seed.unwrap_or(0),
    )?;
    calibrate_sim(&mut arm, a.still, a.fraction, a.press_force, 5)
}

#[cfg(feature = "ros")]
fn ros_calibrate(a: &CalibrateArgs) -> Result<CalibrationReport> {
    use grasp::hardware::HandArm;
    if !(a.press_seconds.is_finite() && a.press_seconds > 0.0 && a.press_seconds <= 600.0) {
        bail!(
            "--press-seconds must be in (0, 600], got {}",
            grasp::util::num::short(a.press_seconds)
        );
    }
    let mut arm = super::connect_ros(&a.ros_url)?;
    let secs = a.press_seconds;
    eprintln!("keep the hand still and untouched ...");
    Ok(grasp::run::calibrate::calibrate_tactile(
        &mut arm,
        a.still,
        0.05,
        a.fraction,
        |b, f| {
            eprintln!(
                "press fingertip {} now ({secs} s) ...",
                grasp::robot::joints::FINGERS[f]
            );
            let end = b.now() + secs;
            let mut out = Vec::new();
            while b.now() < end {
                out.push(b.read()?);
                b.wait(0.02)?;
            }
            Ok(out)
        },
    )?)
}

#[cfg(not(feature = "ros"))]
fn ros_calibrate(_a: &CalibrateArgs) -> Result<CalibrationReport> {
    bail!(grasp::run::request::NO_ROS)
}
