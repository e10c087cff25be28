//! Library objects in the simulator: every built-in object of `train` and `unseen` rests
//! stably on the table, and the scripted close-and-lift (power grasp, hand placed by the
//! top-down grasp mapping) holds some objects and drops others. Optimised dev profile;
//! objects run in parallel with rayon.

use grasp::objects::sets::{build, resolve_specs};
use grasp::objects::BuildContext;
use grasp::robot::{Posture, Robot, Side};
use grasp::sim::script::{close_and_lift, power_grasp, ScriptOptions};
use grasp::sim::{HandSim, ObjectSpec, Scene, SimConfig};
use rayon::prelude::*;

/// The simulator specs of the objects of `set` (built with a private hull cache).
fn specs(set: &str) -> Vec<ObjectSpec> {
    let dir = tempfile::tempdir().unwrap();
    let ctx = BuildContext::with_cache_dir(dir.path());
    resolve_specs(set)
        .unwrap()
        .par_iter()
        .map(|s| {
            let o = build(s, &ctx).unwrap();
            ObjectSpec::from_object(&o).unwrap()
        })
        .collect()
}

fn new_sim(obj: &ObjectSpec) -> HandSim {
    HandSim::new(
        &Robot::builtin(Side::Left),
        obj.clone(),
        SimConfig::default(),
    )
    .unwrap()
}

/// How an object behaved resting on the table.
#[derive(Debug)]
struct Rest {
    name: String,
    failure: Option<String>,
    /// Displacement and tilt over the whole rest.
    drift: f64,
    tilt: f64,
    /// Displacement and change of tilt over the last second: still moving or not.
    late_drift: f64,
    late_tilt: f64,
}

fn rest(sim: &mut HandSim, obj: &ObjectSpec, seconds: f64) -> Rest {
    sim.set_object(obj.clone()).unwrap();
    // The hand 30 cm above the object's centre: out of reach of every built-in object.
    sim.reset(&Scene::above(obj, Posture::Open.angles(), 0.3, 0.0))
        .unwrap();
    let start = sim.object_position();
    let steps = (seconds / sim.config().dt).round() as usize;
    let late = steps - (1.0 / sim.config().dt).round() as usize;
    let mut mid = (start, 0.0);
    for i in 0..steps {
        if i == late {
            mid = (sim.object_position(), sim.object_tilt());
        }
        if !sim.step_physics() {
            break;
        }
    }
    Rest {
        name: obj.name.clone(),
        failure: sim.failure().map(|f| format!("{f:?}")),
        drift: (sim.object_position() - start).norm(),
        tilt: sim.object_tilt(),
        late_drift: (sim.object_position() - mid.0).norm(),
        late_tilt: (sim.object_tilt() - mid.1).abs(),
    }
}

/// Every built-in object, placed in its library pose (turned onto a stable face by
/// `objects::rest`), stays where it was put for 2 s: no physics failure, less than 5 mm
/// and 0.15 rad from its start (a tessellated rounded base may settle by a few degrees
/// onto a neighbouring facet: measured at most 0.72 mm and 0.064 rad, egad_c0_d4), and at
/// rest over the last second (less than 0.5 mm and 0.01 rad: no creeping, no rocking).
#[test]
fn every_builtin_object_rests_stably_on_the_table() {
    let objs = specs("all");
    assert_eq!(objs.len(), 80);
    let results: Vec<Rest> = objs
        .par_iter()
        .map_init(|| new_sim(&objs[0]), |sim, o| rest(sim, o, 2.0))
        .collect();
    let mut bad = Vec::new();
    for r in &results {
        println!(
            "{:<16} drift {:.2} mm  tilt {:.4} rad  last second {:.2} mm {:.4} rad  {}",
            r.name,
            r.drift * 1e3,
            r.tilt,
            r.late_drift * 1e3,
            r.late_tilt,
            r.failure.as_deref().unwrap_or("")
        );
        let stable = r.failure.is_none()
            && r.drift < 0.005
            && r.tilt < 0.15
            && r.late_drift < 0.0005
            && r.late_tilt < 0.01;
        if !stable {
            bad.push(r);
        }
    }
    assert!(bad.is_empty(), "objects not at rest: {bad:#?}");
}

/// Objects of the scripted-grasp check: boxes, cans, a mug, a bowl, a hammer, a bottle,
/// EGAD-like shapes, flat and tall ones.
const GRASP_SUBSET: &str = "box_gelatin,box_sugar,cylinder_wood,can_soup,can_tuna,mug,bowl,\
hammer,bottle_tall,egad_c0_d0,egad_c4_d2,star_5";

#[test]
fn scripted_grasp_holds_some_objects_and_drops_others() {
    let objs = specs(GRASP_SUBSET);
    let outcomes: Vec<(String, bool, f64, Option<String>)> = objs
        .par_iter()
        .map_init(
            || new_sim(&objs[0]),
            |sim, o| {
                sim.set_object(o.clone()).unwrap();
                sim.reset(&Scene::top_down(o, Posture::Open.angles(), 0.01, 0.0))
                    .unwrap();
                let r = close_and_lift(sim, ScriptOptions::default(), &power_grasp());
                let lift = r.lift.unwrap();
                (
                    o.name.clone(),
                    lift.success,
                    lift.object_lowest_z,
                    lift.failure.map(|f| format!("{f:?}")),
                )
            },
        )
        .collect();
    for (name, ok, z, f) in &outcomes {
        println!(
            "{name:<14} {} lowest point {z:.3} m {}",
            if *ok { "HELD   " } else { "dropped" },
            f.as_deref().unwrap_or("")
        );
    }
    let held = outcomes.iter().filter(|o| o.1).count();
    assert!(
        0 < held && held < outcomes.len(),
        "{held} of {} held",
        outcomes.len()
    );
}

fn grasp_cli(args: &[&str]) -> (bool, String, String) {
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_grasp"))
        .args(args)
        .output()
        .unwrap();
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn sim_cli_takes_library_objects_and_suggests_names() {
    let (ok, out, err) = grasp_cli(&["sim", "--object", "can_soup", "--close", "--lift", "--json"]);
    assert!(ok, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(v["object"]["name"], "can_soup");
    assert_eq!(v["object"]["shape"]["kind"], "library");
    assert_eq!(v["lift"]["success"], true, "{out}");
    let (ok, _, err) = grasp_cli(&["sim", "--object", "can_sop"]);
    assert!(!ok);
    assert!(err.contains("did you mean can_soup"), "{err}");
    let (ok, _, err) = grasp_cli(&["sim", "--object", "train"]);
    assert!(!ok);
    assert!(err.contains("61 objects"), "{err}");
    let (ok, _, err) = grasp_cli(&["sim", "--object", "/nonexistent/x.obj"]);
    assert!(!ok);
    assert!(err.contains("/nonexistent/x.obj"), "{err}");
}
