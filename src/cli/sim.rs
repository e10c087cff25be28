//! `grasp sim`: one scripted close-and-lift in the simulator, printed step by step.

use anyhow::{bail, Context, Result};
use clap::{Args, ValueEnum};
use grasp::robot::joints::{FINGERS, KEY_CLOSING_JOINTS};
use grasp::robot::{Posture, Robot, Side};
use grasp::sim::script::{close_and_lift, power_grasp, ScriptOptions};
use grasp::sim::{HandSim, ObjectShape, ObjectSpec, Scene, SimConfig};
use std::path::PathBuf;
use std::time::Instant;

use super::Global;

/// Object kinds of `--object`.
#[derive(Debug, Clone, Copy, ValueEnum)]
pub enum ObjectKind {
    /// A 5 x 5 x 8 cm box.
    Box,
    /// A cylinder of radius 3 cm, 10 cm tall.
    Cylinder,
}

/// Start postures of `--posture`.
#[derive(Debug, Clone, Copy, ValueEnum)]
pub enum StartPosture {
    /// Fingers straight, thumb under the palm.
    Open,
    /// The "C" shape of the paper's grasp mapping.
    CShape,
}

/// Run one scripted grasp in the simulator.
#[derive(Debug, Args)]
#[command(
    after_help = "Examples:\n  grasp sim --close --lift\n  grasp sim --object cylinder --mass 0.2 --friction 0.5 --posture c-shape --close --lift --json\n  grasp sim --config configs/sim.toml --friction 0.05 --close --lift"
)]
pub struct SimArgs {
    /// Simulator config (TOML); built-in defaults when absent.
    #[arg(long)]
    pub config: Option<PathBuf>,
    /// The object to grasp.
    #[arg(long, value_enum, default_value = "box")]
    pub object: ObjectKind,
    /// Object mass (kg); default 0.1 for the box, 0.15 for the cylinder.
    #[arg(long)]
    pub mass: Option<f64>,
    /// Object friction coefficient in [0, 1] (default 0.8).
    #[arg(long)]
    pub friction: Option<f64>,
    /// Start posture of the hand.
    #[arg(long, value_enum, default_value = "open")]
    pub posture: StartPosture,
    /// Close the hand along the scripted trajectory (else it holds the start posture).
    #[arg(long)]
    pub close: bool,
    /// Lift and judge the grasp at the end.
    #[arg(long)]
    pub lift: bool,
    /// Height of the grasp point above the object centre (m).
    #[arg(long, default_value_t = 0.03, allow_negative_numbers = true)]
    pub z_offset: f64,
    /// Uniform x/y noise of the grasp point (m), drawn with --seed.
    #[arg(long, default_value_t = 0.0)]
    pub noise: f64,
    /// Control steps of the closing trajectory.
    #[arg(long, default_value_t = 5)]
    pub close_steps: usize,
    /// Control steps holding the final targets before the lift.
    #[arg(long, default_value_t = 2)]
    pub hold_steps: usize,
}

pub fn run(a: SimArgs, g: &Global) -> Result<()> {
    let cfg = match &a.config {
        Some(p) => SimConfig::load(p).with_context(|| format!("loading {}", p.display()))?,
        None => SimConfig::default(),
    };
    let mut obj = match a.object {
        ObjectKind::Box => ObjectSpec::default_box(),
        ObjectKind::Cylinder => ObjectSpec::default_cylinder(),
    };
    if let Some(m) = a.mass {
        obj.mass = m;
    }
    if let Some(f) = a.friction {
        obj.friction = f;
    }
    obj.validate().context("--mass/--friction")?;
    for (name, v) in [("--z-offset", a.z_offset), ("--noise", a.noise)] {
        if !v.is_finite() || v.abs() > 1.0 {
            bail!("{name} = {v}: must be finite and at most 1 m in size");
        }
    }
    if a.noise < 0.0 {
        bail!("--noise = {}: must be >= 0", a.noise);
    }
    if a.close_steps > 1000 || a.hold_steps > 1000 {
        bail!("--close-steps/--hold-steps: at most 1000");
    }
    let start = match a.posture {
        StartPosture::Open => Posture::Open.angles(),
        StartPosture::CShape => Posture::CShape.angles(),
    };
    let robot = Robot::builtin(Side::Left);
    let mut sim = HandSim::new(&robot, obj, cfg)?;
    let seed = g.seed.unwrap_or(0);
    let scene = Scene::randomized(&obj, start, a.z_offset, a.noise, 0.0, seed);
    sim.reset(&scene)?;
    let opts = ScriptOptions {
        close: a.close,
        lift: a.lift,
        close_steps: a.close_steps,
        hold_steps: a.hold_steps,
    };
    let t0 = Instant::now();
    let r = close_and_lift(&mut sim, opts, &power_grasp());
    let wall = t0.elapsed().as_secs_f64();
    if g.json {
        let out = serde_json::json!({
            "object": obj,
            "scene": scene,
            "config": sim.config(),
            "steps": r.steps,
            "lift": r.lift,
            "failure": sim.failure(),
            "physics_steps": r.physics_steps,
            "sim_seconds": r.sim_time,
            "wall_seconds": wall,
        });
        println!("{}", serde_json::to_string_pretty(&out)?);
        return Ok(());
    }
    let shape = match obj.shape {
        ObjectShape::Box { half } => format!(
            "box {:.0} x {:.0} x {:.0} mm",
            2000.0 * half[0],
            2000.0 * half[1],
            2000.0 * half[2]
        ),
        ObjectShape::Cylinder {
            radius,
            half_height,
        } => format!(
            "cylinder r {:.0} mm, h {:.0} mm",
            1000.0 * radius,
            2000.0 * half_height
        ),
    };
    println!(
        "{shape}, {:.3} kg, friction {:.2}; dt {:.5} s x {} substeps, control period {} s",
        obj.mass,
        obj.friction,
        sim.config().dt,
        sim.config().substeps,
        sim.config().control_period
    );
    let key: Vec<usize> = KEY_CLOSING_JOINTS
        .iter()
        .filter_map(|j| grasp::robot::joints::hand_index(j))
        .collect();
    println!(
        "{:>4} {:<5} {:<11} {:<41} {:<36} {:>8}",
        "step",
        "phase",
        format!("tactile {}", FINGERS.map(|f| &f[..1]).concat()),
        "torque levels (20 actuators)",
        format!("angles {} (rad)", KEY_CLOSING_JOINTS.join(" ")),
        "obj z m"
    );
    for s in &r.steps {
        let tact: String = s.sensors.tactile.iter().map(|b| b.to_string()).collect();
        let lv: Vec<String> = s
            .sensors
            .torque_level
            .iter()
            .map(|l| l.to_string())
            .collect();
        let ang: Vec<String> = key
            .iter()
            .map(|&k| format!("{:6.3}", s.sensors.q[k]))
            .collect();
        println!(
            "{:>4} {:<5} {:<11} {:<41} {:<36} {:>8.4}",
            s.step,
            s.phase,
            tact,
            lv.join(" "),
            ang.join(" "),
            s.object_z
        );
    }
    if let Some(f) = sim.failure() {
        println!("physics failure: {f:?}");
    }
    match &r.lift {
        Some(l) => println!(
            "lift: {} (object lowest point {:.4} m above the table, in contact with the hand: {})",
            if l.success { "SUCCESS" } else { "failed" },
            l.object_lowest_z,
            l.in_contact
        ),
        None => println!("no lift (use --lift)"),
    }
    println!(
        "{} physics steps, {:.2} simulated s in {:.3} s wall ({:.1} simulated s per wall s)",
        r.physics_steps,
        r.sim_time,
        wall,
        r.sim_time / wall.max(1e-9)
    );
    Ok(())
}
