//! `grasp sim`: one scripted close-and-lift in the simulator, printed step by step.

use anyhow::{bail, Context, Result};
use clap::{Args, ValueEnum};
use grasp::objects::sets::{self, BuildContext};
use grasp::robot::joints::{FINGERS, KEY_CLOSING_JOINTS};
use grasp::robot::{Posture, Robot, Side};
use grasp::sim::script::{close_and_lift, power_grasp, ScriptOptions, ScriptResult};
use grasp::sim::{HandSim, ObjectShape, ObjectSpec, Scene};
use std::path::PathBuf;
use std::time::Instant;

use super::Global;

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
    after_help = "Examples:\n  grasp sim --close --lift\n  grasp sim --object cylinder --mass 0.2 --friction 0.5 --posture c-shape --close --lift --json\n  grasp sim --object can_soup --close --lift\n  grasp sim --object ./meshes/part.obj --depth 0.02 --close --lift --json\n  grasp sim --config configs/sim.toml --friction 0.05 --close --lift\n\n`--object` takes `box`, `cylinder`, any built-in library object (`grasp objects list`), or\nan `--objects`-style spec (mesh file, manifest, folder) that holds exactly one object.\nBy default the grasp point (the thumb/little-finger tip midpoint) is `--depth` below the\nobject's top but not below its centre; `--z-offset` places it relative to the centre."
)]
pub struct SimArgs {
    /// Simulator config (TOML); built-in defaults when absent.
    #[arg(long)]
    pub config: Option<PathBuf>,
    /// The object to grasp: box, cylinder, a library object name, or a spec of one object.
    #[arg(long, default_value = "box")]
    pub object: String,
    /// Object mass (kg); default 0.1 for the box, 0.15 for the cylinder, the library's mass
    /// for library objects.
    #[arg(long, allow_negative_numbers = true)]
    pub mass: Option<f64>,
    /// Object friction coefficient in [0, 1] (default 0.8, or the library's value).
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
    /// Height of the grasp point above the object centre (m); overrides --depth.
    #[arg(long, allow_negative_numbers = true)]
    pub z_offset: Option<f64>,
    /// Depth of the grasp point below the object's top (m), never below its centre.
    #[arg(long, default_value_t = 0.01, allow_negative_numbers = true)]
    pub depth: f64,
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
    let cfg = super::sim_config(a.config.as_ref())?;
    let obj = checked_object(&a)?;
    let start = match a.posture {
        StartPosture::Open => Posture::Open.angles(),
        StartPosture::CShape => Posture::CShape.angles(),
    };
    let robot = Robot::builtin(Side::Left);
    let mut sim = HandSim::new(&robot, obj.clone(), cfg)?;
    let seed = g.seed.unwrap_or(0);
    let scene = match a.z_offset {
        Some(z) => Scene::above(&obj, start, z, 0.0),
        None => Scene::top_down(&obj, start, a.depth, 0.0),
    }
    .with_noise(a.noise, 0.0, seed);
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
            "failure_step": sim.failure_step(),
            "deepest_contact": sim.deepest_contact(),
            "physics_steps": r.physics_steps,
            "sim_seconds": r.sim_time,
            "wall_seconds": wall,
        });
        println!("{}", serde_json::to_string_pretty(&out)?);
        return Ok(());
    }
    let shape = shape_line(&obj);
    println!(
        "{shape}, {:.3} kg, friction {:.2}; dt {:.5} s x {} substeps, control period {} s",
        obj.mass,
        obj.friction,
        sim.config().dt,
        sim.config().substeps,
        sim.config().control_period
    );
    print_steps(&r);
    print_outcome(&sim, &r, wall);
    Ok(())
}

/// The object of `--object` with `--mass`/`--friction`, after every flag's range check.
fn checked_object(a: &SimArgs) -> Result<ObjectSpec> {
    let mut obj = object_spec(&a.object)?;
    if let Some(m) = a.mass {
        obj.mass = m;
    }
    if let Some(f) = a.friction {
        obj.friction = f;
    }
    obj.validate().context("--mass/--friction")?;
    for (name, v) in [
        ("--z-offset", a.z_offset.unwrap_or(0.0)),
        ("--depth", a.depth),
        ("--noise", a.noise),
    ] {
        if !v.is_finite() || v.abs() > 1.0 {
            bail!(
                "{name} = {}: must be finite and at most 1 m in size",
                grasp::util::num::short(v)
            );
        }
    }
    if a.noise < 0.0 {
        bail!(
            "--noise = {}: must be >= 0",
            grasp::util::num::short(a.noise)
        );
    }
    if a.close_steps > 1000 || a.hold_steps > 1000 {
        bail!("--close-steps/--hold-steps: at most 1000");
    }
    Ok(obj)
}

/// The object's name, size and parts, in mm.
fn shape_line(obj: &ObjectSpec) -> String {
    match &obj.shape {
        ObjectShape::Box { half } => format!(
            "{} {:.0} x {:.0} x {:.0} mm",
            obj.name,
            2000.0 * half[0],
            2000.0 * half[1],
            2000.0 * half[2]
        ),
        ObjectShape::Cylinder {
            radius,
            half_height,
        } => format!(
            "{} r {:.0} mm, h {:.0} mm",
            obj.name,
            1000.0 * radius,
            2000.0 * half_height
        ),
        ObjectShape::Library {
            part_count, half, ..
        } => format!(
            "{} {:.0} x {:.0} x {:.0} mm, {part_count} convex part(s)",
            obj.name,
            2000.0 * half[0],
            2000.0 * half[1],
            2000.0 * half[2]
        ),
    }
}

/// One line per control step: phase, touch, torque levels, key joint angles, object height.
fn print_steps(r: &ScriptResult) {
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
}

/// The physics failure, the deepest contact, the lift and the speed.
fn print_outcome(sim: &HandSim, r: &ScriptResult, wall: f64) {
    if let Some(f) = sim.failure() {
        println!(
            "physics failure at physics step {}: {} ({f})",
            sim.failure_step().unwrap_or(0),
            f.kind()
        );
    }
    if let Some(c) = sim.deepest_contact() {
        println!(
            "deepest object contact: {:.2} mm with {}{} at physics step {}",
            c.depth * 1e3,
            c.with,
            c.part
                .map(|p| format!(" (object part {p})"))
                .unwrap_or_default(),
            c.step
        );
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
}

/// The object of `--object`: the primitive `box` or `cylinder`, or the one library object
/// the spec resolves to.
fn object_spec(arg: &str) -> Result<ObjectSpec> {
    match arg.trim() {
        "box" => return Ok(ObjectSpec::default_box()),
        "cylinder" => return Ok(ObjectSpec::default_cylinder()),
        _ => {}
    }
    let mut specs = sets::resolve_specs(arg).with_context(|| {
        format!("--object `{arg}` (besides library objects, `box` and `cylinder` are known)")
    })?;
    if specs.len() != 1 {
        bail!(
            "--object `{arg}` holds {} objects; it must name exactly one (see `grasp objects list --set {arg}`)",
            specs.len()
        );
    }
    let spec = specs.remove(0);
    let object = sets::build(&spec, &BuildContext::from_env())
        .with_context(|| format!("--object: cannot build object `{}`", spec.spec.name))?;
    ObjectSpec::from_object(&object).with_context(|| {
        format!(
            "--object: object `{}` has no collision geometry",
            object.name
        )
    })
}
