//! `grasp robot`: inspect the hand model, write the URDF files, solve UR10e IK.

use anyhow::{bail, Context, Result};
use clap::{Args, Subcommand};
use grasp::robot::joints::{actuators, FINGERS, HAND_JOINTS, KEY_CLOSING_JOINTS};
use grasp::robot::kinematics::{check_limits, parse_posture};
use grasp::robot::{ur10e, urdf_gen, MeshPolicy, Posture, Robot, Side};
use grasp::util::fsx::write_atomic;
use nalgebra::{Isometry3, Translation3, UnitQuaternion};
use std::path::PathBuf;

use super::Global;

/// Inspect the robot model.
#[derive(Debug, Args)]
pub struct RobotArgs {
    #[command(subcommand)]
    pub command: RobotCommand,
}

#[derive(Debug, Subcommand)]
pub enum RobotCommand {
    /// Joint table, actuators, coupling and fingertip positions at a posture.
    #[command(
        after_help = "Examples:\n  grasp robot show\n  grasp robot show --hand right --q c-shape --json\n  grasp robot show --urdf shadowhand_motor.urdf --q my_posture.txt"
    )]
    Show(ShowArgs),
    /// Write the project's URDF files (generated from the published kinematic facts).
    #[command(
        after_help = "Examples:\n  grasp robot urdf --hand left > left.urdf\n  grasp robot urdf --all --out-dir assets/robots"
    )]
    Urdf(UrdfArgs),
    /// UR10e inverse kinematics for a flange pose (base frame, metres and radians).
    #[command(after_help = "Example:\n  grasp robot ik --xyz 0.6 0.2 0.4 --rpy 3.1416 0 0")]
    Ik(IkArgs),
    /// Write the simulated scene (hand on its mount, table, object) as MuJoCo MJCF, as the
    /// MuJoCo backend simulates it, to open in MuJoCo's own viewer.
    #[command(
        after_help = "Examples:\n  grasp robot mjcf --object box_gelatin --out scene.xml\n  python -m mujoco.viewer --mjcf scene.xml\n\nThe hand hangs open 15 cm above the object's top (the start of `grasp run`); the\nengine settings are configs/mujoco.toml's unless --mujoco-settings names a file."
    )]
    Mjcf(MjcfArgs),
}

#[derive(Debug, Args)]
pub struct MjcfArgs {
    /// Object on the table: box, cylinder, a library object name, or `none`.
    #[arg(long, default_value = "box_gelatin")]
    pub object: String,
    /// Write to this file instead of stdout.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Simulator config (TOML): gains, frictions, gravity; built-in defaults when absent.
    #[arg(long)]
    pub sim_config: Option<PathBuf>,
    /// MuJoCo engine settings (TOML); configs/mujoco.toml's when absent.
    #[arg(long)]
    pub mujoco_settings: Option<PathBuf>,
}

#[derive(Debug, Args)]
pub struct ShowArgs {
    /// A URDF file to load instead of the built-in hand (the maker's files work too).
    #[arg(long)]
    pub urdf: Option<PathBuf>,
    /// Which built-in hand.
    #[arg(long, default_value = "left")]
    pub hand: Side,
    /// Posture: zero, open, c-shape, or a file of `JOINT VALUE` lines (radians).
    #[arg(long, default_value = "zero")]
    pub q: String,
    /// Fail on mesh files that cannot be found instead of approximating them.
    #[arg(long)]
    pub strict: bool,
}

#[derive(Debug, Args)]
pub struct UrdfArgs {
    /// Which model: left, right (hands) or arm (UR10e with the left hand).
    #[arg(long, default_value = "left")]
    pub hand: String,
    /// Write to this file instead of stdout.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Write all three shipped files into --out-dir.
    #[arg(long)]
    pub all: bool,
    /// Folder for --all.
    #[arg(long, default_value = "assets/robots")]
    pub out_dir: PathBuf,
}

#[derive(Debug, Args)]
pub struct IkArgs {
    /// Flange position x y z (m) in the UR10e base frame.
    #[arg(long, num_args = 3, allow_negative_numbers = true, required = true)]
    pub xyz: Vec<f64>,
    /// Flange orientation roll pitch yaw (rad).
    #[arg(long, num_args = 3, allow_negative_numbers = true, default_values_t = [std::f64::consts::PI, 0.0, 0.0])]
    pub rpy: Vec<f64>,
}

pub fn run(args: RobotArgs, g: &Global) -> Result<()> {
    match args.command {
        RobotCommand::Show(a) => show(a, g),
        RobotCommand::Urdf(a) => urdf(a),
        RobotCommand::Ik(a) => ik(a, g),
        RobotCommand::Mjcf(a) => mjcf(a),
    }
}

fn mjcf(a: MjcfArgs) -> Result<()> {
    use grasp::run::mjcf::{scene_xml, MujocoSettings};
    let robot = Robot::builtin(Side::Left);
    let sim = super::sim_config(a.sim_config.as_ref())?;
    let settings = match &a.mujoco_settings {
        Some(p) => {
            MujocoSettings::load(p).with_context(|| format!("--mujoco-settings {}", p.display()))?
        }
        None => MujocoSettings::builtin(),
    };
    let object = match a.object.trim() {
        "none" => None,
        name => Some(super::sim_object(name)?),
    };
    let top = object.as_ref().map_or(0.0, |o| 2.0 * o.rest_height());
    let open = Posture::Open.angles();
    let grasp_point = nalgebra::Point3::new(0.0, 0.0, top + 0.15);
    let mount = grasp::sim::placement::hand_root_pose(&robot, &grasp_point, 0.0, &open)
        .context("placing the hand")?;
    let xml = scene_xml(&robot, &mount, object.as_ref(), &sim, &settings)?;
    match &a.out {
        Some(p) => {
            write_atomic(p, xml.as_bytes()).with_context(|| format!("writing {}", p.display()))?
        }
        None => print!("{xml}"),
    }
    Ok(())
}

fn load_posture(spec: &str) -> Result<[f64; 24]> {
    if let Ok(p) = spec.parse::<Posture>() {
        return Ok(p.angles());
    }
    let path = PathBuf::from(spec);
    if !path.exists() {
        bail!("unknown posture '{spec}': expected zero, open, c-shape or an existing file");
    }
    let text = grasp::util::fsx::read_to_string_bounded(&path, grasp::util::fsx::limits::DATA)
        .with_context(|| format!("cannot read posture file {}", path.display()))?;
    parse_posture(&text, &path.display().to_string()).map_err(anyhow::Error::msg)
}

fn show(a: ShowArgs, g: &Global) -> Result<()> {
    let robot = match &a.urdf {
        Some(p) => {
            let policy = if a.strict {
                MeshPolicy::Strict
            } else {
                MeshPolicy::Fallback
            };
            Robot::load(p, policy)?
        }
        None => Robot::builtin(a.hand),
    };
    let q = load_posture(&a.q)?;
    check_limits(&robot, &q, 1e-9).map_err(|e| anyhow::anyhow!("posture '{}': {e}", a.q))?;
    let tips = robot.fingertips_palm(&q);
    let acts = actuators();
    if g.json {
        let joints: Vec<_> = HAND_JOINTS
            .iter()
            .zip(robot.hand.joints)
            .zip(q)
            .map(|((name, j), angle)| {
                let jt = &robot.joints[j];
                serde_json::json!({
                    "name": name, "urdf_name": jt.name, "type": jt.kind,
                    "axis": [jt.axis.x, jt.axis.y, jt.axis.z],
                    "lower": jt.lower, "upper": jt.upper, "effort": jt.effort,
                    "angle": angle,
                })
            })
            .collect();
        let out = serde_json::json!({
            "robot": robot.name,
            "source": robot.source.display().to_string(),
            "side": robot.hand.side,
            "links": robot.links.len(),
            "joints": joints,
            "actuators": acts,
            "key_closing_joints": KEY_CLOSING_JOINTS,
            "fingertips_palm_frame": FINGERS.iter().zip(tips).map(|(f, p)| {
                serde_json::json!({"finger": f, "xyz": [p.x, p.y, p.z]})
            }).collect::<Vec<_>>(),
        });
        println!("{}", serde_json::to_string_pretty(&out)?);
        return Ok(());
    }
    println!(
        "{} ({} hand) from {}: {} links, {} joints",
        robot.name,
        robot.hand.side.name(),
        robot.source.display(),
        robot.links.len(),
        robot.joints.len()
    );
    println!();
    println!(
        "{:>3}  {:<6} {:<10} {:>22} {:>8} {:>8} {:>6} {:>8}",
        "#", "joint", "urdf", "axis", "lower", "upper", "effort", "angle"
    );
    for (k, name) in HAND_JOINTS.iter().enumerate() {
        let jt = &robot.joints[robot.hand.joints[k]];
        let axis = format!("({:.3}, {:.3}, {:.3})", jt.axis.x, jt.axis.y, jt.axis.z);
        let key = if KEY_CLOSING_JOINTS.contains(name) {
            " *"
        } else {
            ""
        };
        println!(
            "{:>3}  {:<6} {:<10} {:>22} {:>8.4} {:>8.4} {:>6.1} {:>8.4}{key}",
            k, name, jt.name, axis, jt.lower, jt.upper, jt.effort, q[k]
        );
    }
    println!("(* key closing joints of eq. 5)");
    println!();
    println!("{} actuators:", acts.len());
    for a in &acts {
        if a.joints.len() == 2 {
            println!(
                "  {:<6} drives {} + {} (coupled, J0 = J1 + J2 in [0, pi])",
                a.name, a.joints[0], a.joints[1]
            );
        }
    }
    println!(
        "  the other {} drive one joint each",
        acts.iter().filter(|a| a.joints.len() == 1).count()
    );
    println!();
    println!("fingertips in the palm frame (m):");
    for (f, p) in FINGERS.iter().zip(tips) {
        println!("  {f}  ({:>8.4}, {:>8.4}, {:>8.4})", p.x, p.y, p.z);
    }
    Ok(())
}

fn urdf(a: UrdfArgs) -> Result<()> {
    let text_for = |which: &str| -> Result<String> {
        Ok(match which {
            "left" => urdf_gen::hand_urdf(Side::Left),
            "right" => urdf_gen::hand_urdf(Side::Right),
            "arm" => urdf_gen::ur10e_with_hand_urdf(),
            other => bail!("unknown model '{other}': expected left, right or arm"),
        })
    };
    if a.all {
        for (which, file) in [
            ("left", "shadow_hand_left.urdf"),
            ("right", "shadow_hand_right.urdf"),
            ("arm", "ur10e.urdf"),
        ] {
            let path = a.out_dir.join(file);
            write_atomic(&path, text_for(which)?.as_bytes())?;
            eprintln!("wrote {}", path.display());
        }
        return Ok(());
    }
    let text = text_for(&a.hand)?;
    match a.out {
        Some(p) => write_atomic(&p, text.as_bytes())?,
        None => print!("{text}"),
    }
    Ok(())
}

fn ik(a: IkArgs, g: &Global) -> Result<()> {
    let [x, y, z] = [a.xyz[0], a.xyz[1], a.xyz[2]];
    let [r, p, yaw] = [a.rpy[0], a.rpy[1], a.rpy[2]];
    let target = Isometry3::from_parts(
        Translation3::new(x, y, z),
        UnitQuaternion::from_euler_angles(r, p, yaw),
    );
    let q = ur10e::ik(&target, &ur10e::HOME)?;
    let back = ur10e::fk(&q);
    let err = (back.translation.vector - target.translation.vector).norm();
    if g.json {
        let out = serde_json::json!({
            "joints": ur10e::JOINT_NAMES.iter().zip(q).map(|(n, v)| serde_json::json!({"name": n, "angle": v})).collect::<Vec<_>>(),
            "position_error_m": err,
        });
        println!("{}", serde_json::to_string_pretty(&out)?);
    } else {
        for (n, v) in ur10e::JOINT_NAMES.iter().zip(q) {
            println!("{n:<20} {v:>9.5} rad");
        }
        println!("position error after FK: {err:.2e} m");
    }
    Ok(())
}
