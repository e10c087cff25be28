//! `grasp bench`: throughput measurements.

use anyhow::{Context, Result};
use clap::{Args, Subcommand};
use grasp::robot::{Robot, Side};
use grasp::sim::bench::{self, BenchFigures};
use grasp::sim::SimConfig;
use std::path::PathBuf;

use super::Global;

/// Measure throughput.
#[derive(Debug, Args)]
pub struct BenchArgs {
    #[command(subcommand)]
    pub command: BenchCommand,
}

#[derive(Debug, Subcommand)]
pub enum BenchCommand {
    /// Simulator throughput: scripted close-and-lift episodes on one env, then on --envs
    /// envs in one rayon pool of --threads threads (default: the number of cores).
    #[command(
        after_help = "Examples:\n  grasp bench sim\n  grasp bench sim --envs 20 --seconds 10 --json"
    )]
    Sim(BenchSimArgs),
}

#[derive(Debug, Args)]
pub struct BenchSimArgs {
    /// Simulator config (TOML); built-in defaults when absent.
    #[arg(long)]
    pub config: Option<PathBuf>,
    /// Environments stepped in parallel for the second measurement.
    #[arg(long, default_value_t = 20)]
    pub envs: usize,
    /// Threads of the pool (default: available cores).
    #[arg(long)]
    pub threads: Option<usize>,
    /// Wall seconds per measurement.
    #[arg(long, default_value_t = 5.0)]
    pub seconds: f64,
}

pub fn run(a: BenchArgs, g: &Global) -> Result<()> {
    match a.command {
        BenchCommand::Sim(a) => sim(a, g),
    }
}

fn sim(a: BenchSimArgs, g: &Global) -> Result<()> {
    let cfg = match &a.config {
        Some(p) => SimConfig::load(p).with_context(|| format!("loading {}", p.display()))?,
        None => SimConfig::default(),
    };
    let threads = a.threads.unwrap_or_else(|| {
        std::thread::available_parallelism()
            .map(|n| n.get())
            .unwrap_or(1)
    });
    let robot = Robot::builtin(Side::Left);
    let one = bench::run(&robot, &cfg, 1, 1, a.seconds)?;
    let many = bench::run(&robot, &cfg, a.envs, threads, a.seconds)?;
    if g.json {
        let out = serde_json::json!({
            "dt": cfg.dt,
            "substeps": cfg.substeps,
            "control_period": cfg.control_period,
            "single": one,
            "parallel": many,
        });
        println!("{}", serde_json::to_string_pretty(&out)?);
        return Ok(());
    }
    println!(
        "simulator: dt {:.5} s, {} substeps, control period {} s; scripted close-and-lift episodes",
        cfg.dt, cfg.substeps, cfg.control_period
    );
    let row = |f: &BenchFigures| {
        println!(
            "{:>3} envs on {:>2} threads: {:>9.0} physics steps/s  {:>7.1} simulated s/s  {:>8.1} control steps/s  ({} episodes in {:.1} s)",
            f.envs,
            f.threads,
            f.physics_steps_per_s,
            f.sim_seconds_per_s,
            f.control_steps_per_s,
            f.episodes,
            f.wall_seconds
        )
    };
    row(&one);
    row(&many);
    println!("reference: MuJoCo steps the Shadow hand with a block at 55-78 simulated s per wall s on one core");
    Ok(())
}
