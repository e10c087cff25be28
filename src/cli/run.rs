//! `grasp run`: a grasp attempt of a trained policy on the simulated or the real robot
//! (Sec. V-B): plan a two-finger grasp, map it to the hand, stage 1, the policy, the lift.

use anyhow::{Context, Result};
use clap::Args;
use grasp::run::request::{execute, GraspInput, RunAttempt, RunEvent, RunOutput, RunRequest};
use grasp::util::signal;
use std::path::PathBuf;
use std::sync::OnceLock;

use super::{Backend, Global};

/// Run a grasp attempt of a trained policy on the simulated or the real robot (with
/// --attempts, more after a failed lift: sim backend).
#[derive(Debug, Args)]
#[command(after_help = "Examples:
  grasp run --backend sim --object box_gelatin
  grasp run --backend sim --object box_gelatin --cloud scan.pcd --log attempt.jsonl --json
  grasp run --backend sim --center 0,0,0.02 --closing 1,0,0 --calibration tactile.json
  grasp run --backend ros --ros-url ws://robot:9090 --grasp grasp.toml --calibration tactile.json
  grasp run --backend sim --objects unseen --trials 10 --policy assets/policies/fig5_gru_m3_pca8,baseline1,baseline2 --json

With the sim backend and no grasp or cloud, the cloud is what four simulated depth
camera views (one from each side) see of the object (noisy, partial); --save-cloud
writes it as PCD. Where the cloud holds no usable antipodal pair, the hand closes across
the cloud's narrowest horizontal extent. Without
--calibration the sim backend calibrates its fingertips first (as `grasp calibrate`).
A grasp file is TOML or JSON: center = [x, y, z], closing = [x, y, z], and optionally
approach = [x, y, z] (default [0, 0, -1]), world frame, metres. Every step is appended
to the attempt log (JSON lines). The sim backend places the hand palm down only, so its
grasps are made top-down.

With --objects (a simulated backend), the command makes Table I through the robot path:
every agent of --policy (checkpoint folders, baseline1, baseline2) on --trials scenes of
each object (scene t of object o seeded as `grasp eval` seeds it from --seed: the object's
offset and yaw, the raw sensors' noise), each trial the whole pipeline on a fresh
simulated robot (calibration, cameras, plan, attempt, lift) judged by the simulator. It
prints per-object success with Wilson intervals as `grasp eval` does; --json has the shape
of `grasp eval --json` (plus each agent's backend and the trials that ended in an error),
so `grasp eval --from-json` reads it. Attempt logs are written only with --log (all trials
into that file).")]
pub struct RunArgs {
    /// The robot: sim, ros or mujoco.
    #[arg(long, value_enum, default_value = "sim")]
    pub backend: Backend,
    /// Checkpoint folder of the policy (default: the shipped policy that lifted the most
    /// validation objects from the pre-grasp, the placement `grasp run` plans; found from
    /// any working directory, see docs/robot-hardware.md). With --objects, a comma list
    /// of agents: checkpoint folders, baseline1 and baseline2.
    #[arg(long, default_value = grasp::run::DEFAULT_POLICY)]
    pub policy: String,
    /// Two-finger grasp file (TOML or JSON).
    #[arg(long, conflicts_with_all = ["cloud", "center"])]
    pub grasp: Option<PathBuf>,
    /// Point cloud of the object (PCD or PLY, world frame) to plan the grasp on.
    #[arg(long, conflicts_with = "center")]
    pub cloud: Option<PathBuf>,
    /// Grasp centre x,y,z (m): a grasp given on the command line (with --closing).
    #[arg(
        long,
        value_delimiter = ',',
        value_name = "X,Y,Z",
        allow_negative_numbers = true,
        requires = "closing"
    )]
    pub center: Option<Vec<f64>>,
    /// Closing direction x,y,z of a command-line grasp.
    #[arg(
        long,
        value_delimiter = ',',
        value_name = "X,Y,Z",
        allow_negative_numbers = true,
        requires = "center"
    )]
    pub closing: Option<Vec<f64>>,
    /// Approach direction x,y,z of a command-line grasp (default straight down).
    #[arg(
        long,
        value_delimiter = ',',
        value_name = "X,Y,Z",
        allow_negative_numbers = true,
        requires = "center"
    )]
    pub approach: Option<Vec<f64>>,
    /// Tactile calibration file (from `grasp calibrate`).
    #[arg(long)]
    pub calibration: Option<PathBuf>,
    /// Object in the simulator: box, cylinder or a library object name.
    #[arg(long, default_value = "box_gelatin")]
    pub object: String,
    /// Table I through the robot path on this object set (a set name, a manifest or a
    /// comma list of objects, as `grasp eval --objects`): every --policy agent on --trials
    /// scenes of each object (simulated backends).
    #[arg(long, conflicts_with_all = ["object", "grasp", "cloud", "center", "save_cloud"])]
    pub objects: Option<String>,
    /// With --objects: trials per object.
    #[arg(long, default_value_t = 10, requires = "objects")]
    pub trials: usize,
    /// With --objects: worker threads (default: available cores).
    #[arg(long, requires = "objects")]
    pub threads: Option<usize>,
    /// Attempt log (JSON lines, appended; default attempt.jsonl). With --objects, every
    /// trial's attempt is appended to it, and none is written without it.
    #[arg(long)]
    pub log: Option<PathBuf>,
    /// Pipeline config (TOML, see `PipelineConfig`); defaults when absent.
    #[arg(long)]
    pub config: Option<PathBuf>,
    /// Simulator config (TOML); built-in defaults when absent.
    #[arg(long)]
    pub sim_config: Option<PathBuf>,
    /// MuJoCo engine settings (TOML, mujoco backend); configs/mujoco.toml's when absent.
    #[arg(long)]
    pub mujoco_settings: Option<PathBuf>,
    /// Write the point cloud the grasp was planned on (sim cameras or --cloud) as PCD.
    #[arg(long)]
    pub save_cloud: Option<PathBuf>,
    /// rosbridge websocket of the robot (ros backend).
    #[arg(long, default_value = "ws://localhost:9090")]
    pub ros_url: String,
    /// Attempts (sim backend, planned on the cameras' cloud): after a failed lift the hand
    /// opens, the object settles where the attempt left it, the cameras look again and
    /// the next best grasp that was not tried yet is planned, as `grasp eval --attempts`.
    #[arg(long, default_value_t = 1)]
    pub attempts: usize,
}

/// The library's request of these flags.
fn request(a: &RunArgs, g: &Global) -> RunRequest {
    let grasp = if let Some(p) = &a.grasp {
        Some(GraspInput::File(p.clone()))
    } else if let Some(p) = &a.cloud {
        Some(GraspInput::Cloud(p.clone()))
    } else if let (Some(center), Some(closing)) = (&a.center, &a.closing) {
        Some(GraspInput::Given {
            center: center.clone(),
            closing: closing.clone(),
            approach: a.approach.clone(),
        })
    } else {
        None
    };
    RunRequest {
        backend: a.backend.into(),
        policy: a.policy.clone(),
        grasp,
        calibration: a.calibration.clone(),
        object: a.object.clone(),
        objects: a.objects.clone(),
        trials: a.trials,
        threads: a.threads,
        log: a.log.clone(),
        config: a.config.clone(),
        sim_config: a.sim_config.clone(),
        mujoco_settings: a.mujoco_settings.clone(),
        save_cloud: a.save_cloud.clone(),
        ros_url: a.ros_url.clone(),
        attempts: a.attempts,
        seed: g.seed.unwrap_or(0),
    }
}

pub fn run(a: RunArgs, g: &Global) -> Result<()> {
    let req = request(&a, g);
    if req.objects.is_some() {
        // Installed before the table is announced: a signal from then on stops it cleanly.
        signal::stop_on_signal(
            "finishing the trials in progress, then printing the finished ones",
            g.quiet,
        )
        .context("installing the Ctrl-C and SIGTERM handler")?;
    }
    let bar = OnceLock::new();
    let on_event = |e: RunEvent<'_>| match e {
        RunEvent::TableStarts {
            agents,
            objects,
            trials,
            backend,
        } => {
            let total = (agents * objects * trials) as u64;
            bar.get_or_init(|| progress_bar(total, !(g.quiet || g.json)));
            if !g.quiet && !g.json {
                eprintln!(
                    "running {agents} agents on {objects} objects x {trials} trials through the {backend} robot ..."
                );
            }
        }
        RunEvent::TrialDone => {
            if let Some(b) = bar.get() {
                b.inc(1);
            }
        }
        RunEvent::Attempt(r) => {
            if !g.json {
                print_attempt(r);
            }
        }
    };
    let out = execute(&req, &on_event, Some(&signal::STOP))?;
    if let Some(b) = bar.get() {
        b.finish_and_clear();
    }
    match out {
        RunOutput::Attempts { attempts, stopped } => {
            if let Some(why) = stopped.filter(|_| !g.quiet) {
                eprintln!("{why}");
            }
            print_reports(attempts, g)
        }
        RunOutput::Table {
            results,
            interrupted,
        } => {
            if interrupted && results.is_empty() {
                super::exit_interrupted(" before any trial finished: nothing to report", false);
            }
            if g.json {
                println!("{}", serde_json::to_string_pretty(&results)?);
            } else {
                print_table(&results);
            }
            if let Some(p) = a.log.as_ref().filter(|_| !g.json) {
                eprintln!("attempt logs appended to {}", p.display());
            }
            if interrupted {
                super::exit_interrupted(
                    ": the results above are of the trials that finished",
                    g.quiet,
                );
            }
            Ok(())
        }
    }
}

/// Prints one attempt's text report.
fn print_attempt(r: &RunAttempt) {
    let (plan, out) = (&r.plan, &r.outcome);
    if let Some(n) = r.number {
        println!("attempt {n}:");
    }
    let where_ = match &r.object {
        Some(o) => format!(" on {o}"),
        None => String::new(),
    };
    println!(
        "grasp at ({:.3}, {:.3}, {:.3}) m, closing ({:.2}, {:.2}, {:.2}){}",
        plan.center[0],
        plan.center[1],
        plan.center[2],
        plan.closing[0],
        plan.closing[1],
        plan.closing[2],
        match plan.score {
            Some(s) => format!(
                ", score {s:.3} (best reachable of {} candidates)",
                plan.candidates
            ),
            None if plan.fallback => format!(
                ", across the cloud's narrow axis (no usable antipodal candidate of {})",
                plan.candidates
            ),
            None => String::new(),
        }
    );
    println!(
        "stage 1: {} updates, {}; policy: {} steps, {}; {} clamped commands",
        out.stage1_updates,
        if out.touched { "touched" } else { "no touch" },
        out.policy_steps,
        if out.lifted { "lifted" } else { "no lift" },
        out.clamped_commands
    );
    println!(
        "{}{}: {} ({}; judged by the {}), {:.2} s, {} log lines in {}",
        if out.success { "SUCCESS" } else { "FAILURE" },
        where_,
        out.reason,
        if r.calibrated_now {
            "calibrated now"
        } else {
            "calibration file"
        },
        out.judged_by,
        out.time_s,
        out.log_lines,
        r.log.display()
    );
}

/// With `--json`: one attempt's report as it is, several as `{"attempts": [...],
/// "success": ...}`.
fn print_reports(mut reports: Vec<RunAttempt>, g: &Global) -> Result<()> {
    if !g.json {
        return Ok(());
    }
    let j = if reports.len() == 1 {
        serde_json::to_value(reports.remove(0))?
    } else {
        let success = reports.last().is_some_and(|r| r.outcome.success);
        serde_json::json!({ "attempts": reports, "success": success })
    };
    println!("{}", serde_json::to_string_pretty(&j)?);
    Ok(())
}

/// The table's text: `grasp eval`'s table, physics and paired lines, and each failed
/// trial's reason.
fn print_table(results: &[grasp::run::table::TableAgentResult]) {
    let plain: Vec<grasp::eval::AgentResult> = results.iter().map(|r| r.result.clone()).collect();
    print!("{}", grasp::eval::text_table(&plain));
    for r in &plain {
        print!("{}", grasp::eval::physics_line(r));
        if r.interrupted {
            println!(
                "{}: interrupted (SIGINT or SIGTERM): only the trials that finished are counted",
                r.agent
            );
        }
    }
    for r in results {
        for e in &r.trial_errors {
            println!(
                "{}: {} trial {} failed: {}",
                r.result.agent, e.object, e.trial, e.reason
            );
        }
    }
    let pairs = grasp::eval::paired_lines(&grasp::eval::paired_with_first(&plain))
        + &grasp::eval::unpaired_lines(&plain);
    print!("{pairs}");
}

/// A progress bar of `total` trials on stderr when `show` and stderr is a terminal.
fn progress_bar(total: u64, show: bool) -> indicatif::ProgressBar {
    use std::io::IsTerminal;
    if show && std::io::stderr().is_terminal() {
        let b = indicatif::ProgressBar::new(total);
        if let Ok(style) = indicatif::ProgressStyle::with_template(
            "{bar:40} {pos}/{len} trials, {elapsed} (eta {eta})",
        ) {
            b.set_style(style);
        }
        b
    } else {
        indicatif::ProgressBar::hidden()
    }
}
