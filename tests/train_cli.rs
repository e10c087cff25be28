//! `grasp train` end to end on tiny runs: run folder contents, resume, determinism, the
//! grasp environment with the primitive objects, and config errors.

mod common;

use grasp::synergy::SynergyModel;
use grasp::train::metrics::{parse_csv, HEADER};
use grasp::train::tfevents::{decode_event, read_records};
use grasp::train::TrainConfig;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn grasp(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_grasp"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("run grasp")
}

fn ok(out: &Output) -> String {
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "grasp failed: {stderr}");
    String::from_utf8_lossy(&out.stdout).into_owned()
}

fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

/// 2 cart-poles x 32 steps per update.
fn cartpole_config(dir: &Path, total: u64) -> PathBuf {
    write(
        dir,
        "cp.toml",
        &format!(
            "name = \"cp\"\nseed = 5\ntotal_timesteps = {total}\nnum_envs = 2\nthreads = 1\n\
             checkpoint_every = 1\nplot_every = 2\nbest_window = 2\n[ppo]\nnum_steps = 32\n\
             num_minibatches = 2\nupdate_epochs = 2\n[policy]\nkind = \"mlp\"\nmlp_hidden = 16\n\
             [env]\nkind = \"cartpole\"\ncartpole_max_steps = 50\n"
        ),
    )
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

fn updates(run: &Path) -> Vec<u64> {
    let text = std::fs::read_to_string(run.join("metrics.csv")).unwrap();
    parse_csv(Path::new("metrics.csv"), &text)
        .unwrap()
        .iter()
        .map(|r| r.update)
        .collect()
}

#[test]
fn cartpole_run_writes_the_run_folder_and_resumes() {
    let tmp = tempfile::tempdir().unwrap();
    let cfg = cartpole_config(tmp.path(), 192);
    let run = tmp.path().join("run");
    let out = ok(&grasp(&["train", "--config", s(&cfg), "--out", s(&run)]));
    assert!(out.contains("completed: 3 updates"), "{out}");
    // Resolved config reads back.
    let c = TrainConfig::load(&run.join("config.toml")).unwrap();
    assert_eq!((c.name.as_str(), c.seed, c.num_envs), ("cp", 5, 2));
    let text = std::fs::read_to_string(run.join("metrics.csv")).unwrap();
    assert_eq!(text.lines().next().unwrap(), HEADER);
    assert_eq!(updates(&run), vec![1, 2, 3]);
    let rows = parse_csv(Path::new("m"), &text).unwrap();
    assert_eq!(rows[2].global_step, 192);
    assert!(rows
        .iter()
        .all(|r| r.curriculum_level.is_none() && r.stats.success_rate.is_none()));
    // TensorBoard: a version record and one scalar event per update, CRCs valid.
    let ev: Vec<PathBuf> = std::fs::read_dir(&run)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.to_string_lossy().contains("tfevents"))
        .collect();
    assert_eq!(ev.len(), 1);
    let recs = read_records(&std::fs::read(&ev[0]).unwrap()).unwrap();
    assert_eq!(recs.len(), 4);
    let last = decode_event(&recs[3]).unwrap();
    assert_eq!(last.step, 192);
    assert!(last.values.iter().any(|(t, _)| t == "losses/policy_loss"));
    for d in ["latest", "best"] {
        let ck = run.join("checkpoints").join(d);
        assert!(ck.join("checkpoint.safetensors").is_file(), "{d}");
        assert!(ck.join("config.toml").is_file(), "{d}");
    }
    let svg = std::fs::read_to_string(run.join("learning_curve.svg")).unwrap();
    assert!(svg.contains("<svg") && svg.contains("episode return"));

    // A second start in the same folder is refused; --resume continues.
    let e = grasp(&["train", "--config", s(&cfg), "--out", s(&run)]);
    assert!(!e.status.success());
    assert!(String::from_utf8_lossy(&e.stderr).contains("--resume"));
    let out = ok(&grasp(&[
        "train",
        "--config",
        s(&cfg),
        "--out",
        s(&run),
        "--resume",
        "--total-timesteps",
        "320",
    ]));
    assert!(out.contains("5 updates (2 new)"), "{out}");
    assert_eq!(updates(&run), vec![1, 2, 3, 4, 5]);

    // Rows written after the last checkpoint (a kill between the two) are dropped on resume.
    let mut text = std::fs::read_to_string(run.join("metrics.csv")).unwrap();
    let extra = text.lines().last().unwrap().replacen("5,", "6,", 1);
    text.push_str(&extra);
    text.push('\n');
    std::fs::write(run.join("metrics.csv"), text).unwrap();
    ok(&grasp(&[
        "train",
        "--config",
        s(&cfg),
        "--out",
        s(&run),
        "--resume",
        "--total-timesteps",
        "384",
    ]));
    assert_eq!(updates(&run), vec![1, 2, 3, 4, 5, 6]);
    let recs = read_records(&std::fs::read(&ev[0]).unwrap()).unwrap();
    assert_eq!(recs.len(), 7);
}

#[test]
fn same_seed_gives_the_same_metrics_and_json_summary() {
    let tmp = tempfile::tempdir().unwrap();
    let cfg = cartpole_config(tmp.path(), 128);
    let untimed = |run: &Path| {
        let text = std::fs::read_to_string(run.join("metrics.csv")).unwrap();
        let mut rows = parse_csv(Path::new("m"), &text).unwrap();
        for r in &mut rows {
            r.transitions_per_s = 0.0;
            r.wall_s = 0.0;
        }
        rows
    };
    let (a, b, c) = (
        tmp.path().join("a"),
        tmp.path().join("b"),
        tmp.path().join("c"),
    );
    let out = ok(&grasp(&[
        "train",
        "--config",
        s(&cfg),
        "--out",
        s(&a),
        "--json",
    ]));
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(v["updates"], 2);
    assert_eq!(v["stop"], "completed");
    ok(&grasp(&[
        "train",
        "--config",
        s(&cfg),
        "--out",
        s(&b),
        "-q",
    ]));
    ok(&grasp(&[
        "train",
        "--config",
        s(&cfg),
        "--out",
        s(&c),
        "-q",
        "--seed",
        "6",
    ]));
    assert_eq!(untimed(&a), untimed(&b));
    assert_ne!(untimed(&a), untimed(&c));
}

/// Saves the shared test synergy model to `path`.
fn test_model(path: &Path) {
    common::test_model().save(path).unwrap();
}

#[test]
fn grasp_env_with_primitives_runs_one_update() {
    let tmp = tempfile::tempdir().unwrap();
    let model = tmp.path().join("model.json");
    test_model(&model);
    let cfg = write(
        tmp.path(),
        "g.toml",
        &format!(
            "base = \"{}\"\nname = \"g\"\ntotal_timesteps = 16\nnum_envs = 2\nthreads = 2\n\
             synergy = \"{}\"\n[ppo]\nnum_steps = 8\nnum_minibatches = 2\nupdate_epochs = 1\n\
             [policy]\nembed_dim = 16\ngru_hidden = 16\n",
            concat!(env!("CARGO_MANIFEST_DIR"), "/configs/base.toml"),
            s(&model)
        ),
    );
    let run = tmp.path().join("run");
    let out = ok(&grasp(&[
        "train",
        "--config",
        s(&cfg),
        "--out",
        s(&run),
        "--json",
    ]));
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(v["global_step"], 16);
    let text = std::fs::read_to_string(run.join("metrics.csv")).unwrap();
    assert!(text.lines().next().unwrap().ends_with(",physics_failures"));
    let rows = parse_csv(Path::new("m"), &text).unwrap();
    assert_eq!(rows.len(), 1);
    let level = rows[0].curriculum_level.expect("curriculum level");
    assert!((0.0..=1.0).contains(&level));
    let latest = run.join("checkpoints/latest");
    assert!(latest.join("checkpoint.safetensors").is_file());
    SynergyModel::load(&latest.join("synergy.json")).unwrap();

    // Ranges set without `enabled = true` randomise nothing: training says so.
    let text = std::fs::read_to_string(&cfg).unwrap();
    let unused = write(
        tmp.path(),
        "g_rand.toml",
        &format!("{text}[env.randomization]\nfriction = [0.6, 0.9]\n"),
    );
    let o = grasp(&[
        "train",
        "--config",
        s(&unused),
        "--out",
        s(&tmp.path().join("rr")),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(
        err.contains("[env.randomization] sets friction but not `enabled = true`"),
        "{err}"
    );

    // The model is truncated to fewer components; more than it has is an error.
    let text = std::fs::read_to_string(&cfg).unwrap();
    let few = write(tmp.path(), "g3.toml", &format!("n_components = 8\n{text}"));
    let e = grasp(&[
        "train",
        "--config",
        s(&few),
        "--out",
        s(&tmp.path().join("r8")),
    ]);
    let err = String::from_utf8_lossy(&e.stderr);
    assert!(!e.status.success() && err.contains("at least 8"), "{err}");

    // On the procedural stream with domain randomisation, chosen on the command line.
    let dr = write(
        tmp.path(),
        "gdr.toml",
        &format!("{text}[env.randomization]\nenabled = true\n"),
    );
    let run = tmp.path().join("stream");
    let out = ok(&grasp(&[
        "train",
        "--config",
        s(&dr),
        "--objects",
        "procedural",
        "--out",
        s(&run),
        "--json",
    ]));
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(v["global_step"], 16);
    let saved = TrainConfig::load(&run.join("config.toml")).unwrap();
    assert_eq!(saved.objects, "procedural");
    assert!(saved.env.grasp.randomization.enabled);
    // A randomisation range outside physics names its key.
    let bad = write(
        tmp.path(),
        "gbad.toml",
        &format!("{text}[env.randomization]\nfriction = [0.5, 1.5]\n"),
    );
    let e = grasp(&[
        "train",
        "--config",
        s(&bad),
        "--out",
        s(&tmp.path().join("rb")),
    ]);
    let err = String::from_utf8_lossy(&e.stderr);
    assert!(
        !e.status.success() && err.contains("randomization.friction"),
        "{err}"
    );
    let bad = write(
        tmp.path(),
        "greuse.toml",
        &format!("{text}[env.stream]\nreuse = 0\n"),
    );
    let e = grasp(&[
        "train",
        "--config",
        s(&bad),
        "--out",
        s(&tmp.path().join("ru")),
    ]);
    let err = String::from_utf8_lossy(&e.stderr);
    assert!(!e.status.success() && err.contains("stream.reuse"), "{err}");
}

#[test]
fn config_errors_name_key_line_and_files() {
    let tmp = tempfile::tempdir().unwrap();
    let typo = write(
        tmp.path(),
        "typo.toml",
        "name = \"t\"\n[ppo]\nnum_steps = 8\nlerning_rate = 0.1\n",
    );
    let e = grasp(&[
        "train",
        "--config",
        s(&typo),
        "--out",
        s(&tmp.path().join("r")),
    ]);
    assert!(!e.status.success());
    let err = String::from_utf8_lossy(&e.stderr);
    assert!(
        err.contains("lerning_rate") && err.contains("line 4") && err.contains("typo.toml"),
        "{err}"
    );

    let missing = tmp.path().join("nowhere/model.json");
    let cfg = write(
        tmp.path(),
        "m.toml",
        &format!(
            "name = \"m\"\nnum_envs = 4\nsynergy = \"{}\"\n",
            s(&missing)
        ),
    );
    let e = grasp(&[
        "train",
        "--config",
        s(&cfg),
        "--out",
        s(&tmp.path().join("r2")),
    ]);
    assert!(!e.status.success());
    let err = String::from_utf8_lossy(&e.stderr);
    assert!(
        err.contains(s(&missing)) && err.contains("does not exist"),
        "{err}"
    );
    assert!(!tmp.path().join("r2").exists());

    let e = grasp(&["train", "--config", s(&tmp.path().join("absent.toml"))]);
    assert!(String::from_utf8_lossy(&e.stderr).contains("absent.toml"));
    let e = grasp(&["train", "--config", s(&cfg), "--num-envs", "0"]);
    assert!(String::from_utf8_lossy(&e.stderr).contains("num_envs"));
    let e = grasp(&["train", "--config", s(&cfg), "--time-budget-minutes", "nan"]);
    assert!(!e.status.success());
    assert!(String::from_utf8_lossy(&e.stderr).contains("time_budget_minutes"));
}

#[test]
fn shipped_configs_load() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("configs");
    let mut n = 0;
    // The recipes in configs/, the variants and screens in configs/levers/.
    let entries = std::fs::read_dir(&dir)
        .unwrap()
        .chain(std::fs::read_dir(dir.join("levers")).unwrap());
    for e in entries {
        let p = e.unwrap().path();
        let name = p.file_name().unwrap().to_string_lossy().into_owned();
        // Simulator configs (sim.toml, sim_*.toml) are not training configs.
        if name.starts_with("sim") || !name.ends_with(".toml") {
            continue;
        }
        // The MuJoCo engine's settings load as such.
        if name == "mujoco.toml" {
            grasp::run::mjcf::MujocoSettings::load(&p).unwrap_or_else(|e| panic!("{name}: {e}"));
            continue;
        }
        let c = TrainConfig::load(&p).unwrap_or_else(|e| panic!("{name}: {e}"));
        if p.parent() == Some(dir.join("levers").as_path()) {
            // ship.toml's one-change levers are named ship_<file>.
            let stem = name.trim_end_matches(".toml");
            assert!(
                c.name == stem || c.name == format!("ship_{stem}"),
                "name of levers/{name}: {}",
                c.name
            );
        } else if name != "base.toml" {
            assert_eq!(format!("{}.toml", c.name), name, "name of {name}");
        }
        n += 1;
    }
    // 15 recipes and 13 variants (21 in configs/ before the variants moved to levers/).
    assert_eq!(n, 28);
    // The main job until 2026-12-06 late morning: the main job without the squeeze at the
    // lift, nothing else.
    let main = TrainConfig::load(&dir.join("quick.toml")).unwrap();
    let delay = TrainConfig::load(&dir.join("levers/quick_grip_delay.toml")).unwrap();
    let act = &main.env.grasp.action;
    assert_eq!(
        (act.lift_squeeze, act.lift_squeeze_in_training),
        (0.25, false)
    );
    assert_eq!(delay.env.grasp.action.lift_squeeze, 0.0);
    let mut as_main = delay.clone();
    as_main.env.grasp.action.lift_squeeze = act.lift_squeeze;
    as_main.name = main.name.clone();
    assert_eq!(as_main, main);
    // Until 2026-12-06 morning: that with the grip's ramp at 0.15 instead of its delay,
    // nothing else.
    let ramp = TrainConfig::load(&dir.join("levers/quick_grip_ramp.toml")).unwrap();
    let act = &delay.env.grasp.action;
    assert_eq!(
        (act.grip_delay, act.grip_ramp, act.grip_ramp_in_training),
        (1, 0.0, false)
    );
    let ramp_act = &ramp.env.grasp.action;
    assert_eq!(
        (
            ramp_act.grip_delay,
            ramp_act.grip_ramp,
            ramp_act.lift_squeeze
        ),
        (0, 0.15, 0.0)
    );
    let mut as_delay = ramp.clone();
    as_delay.env.grasp.action.grip_delay = act.grip_delay;
    as_delay.env.grasp.action.grip_ramp = act.grip_ramp;
    as_delay.name = delay.name.clone();
    assert_eq!(as_delay, delay);
    // Until 2026-12-06 early morning: that without the ramp, nothing else.
    let quarter = TrainConfig::load(&dir.join("levers/quick_grip_quarter.toml")).unwrap();
    let mut as_ramp = quarter.clone();
    as_ramp.env.grasp.action.grip_ramp = ramp_act.grip_ramp;
    as_ramp.env.grasp.action.grip_ramp_in_training = ramp_act.grip_ramp_in_training;
    as_ramp.name = ramp.name.clone();
    assert_eq!(as_ramp, ramp);
    // Training's own episodes are the same in all four (no delay, no ramp, no squeeze):
    // they act differently only afterwards.
    let mut quarter_trains = quarter.env.grasp.for_training();
    quarter_trains.action.lift_squeeze_in_training = true;
    for c in [&main, &delay, &ramp] {
        let mut trains = c.env.grasp.for_training();
        assert_eq!(
            (
                trains.action.grip_delay,
                trains.action.grip_ramp,
                trains.action.lift_squeeze
            ),
            (0, 0.0, 0.0)
        );
        trains.action.grip_ramp_in_training = true;
        trains.action.lift_squeeze_in_training = true;
        assert_eq!(trains, quarter_trains);
    }
    // The main job until 2026-12-05 night: that with the grip at 0.5, nothing else.
    let half = TrainConfig::load(&dir.join("levers/quick_grip_half.toml")).unwrap();
    assert_eq!(
        (
            quarter.env.grasp.action.grip_scale,
            half.env.grasp.action.grip_scale
        ),
        (0.25, 0.5)
    );
    let mut as_quarter = half.clone();
    as_quarter.env.grasp.action.grip_scale = quarter.env.grasp.action.grip_scale;
    as_quarter.name = quarter.name.clone();
    assert_eq!(as_quarter, quarter);
    // The main job until 2026-12-05 evening: that with 5 synergies, nothing else.
    let quick = TrainConfig::load(&dir.join("quick_pca5.toml")).unwrap();
    assert_eq!((half.n_components, quick.n_components), (8, 5));
    let mut as_half = quick.clone();
    as_half.n_components = half.n_components;
    as_half.name = half.name.clone();
    assert_eq!(as_half, half);
    // The modality ablation's arms: that recipe with another modality, nothing else.
    // The main job with the placement mix: [env.placement] and milestones, nothing else.
    let mut placed = TrainConfig::load(&dir.join("levers/quick_placement.toml")).unwrap();
    assert!(placed.env.grasp.placement.antipodal > 0.0 && placed.milestone_every > 0);
    placed.env.grasp.placement = quick.env.grasp.placement;
    placed.milestone_every = quick.milestone_every;
    placed.name = quick.name.clone();
    assert_eq!(placed, quick);
    for (file, m) in [
        ("levers/quick_m1.toml", grasp::env::obs::Modality::M1),
        ("levers/quick_m2.toml", grasp::env::obs::Modality::M2),
    ] {
        let mut c = TrainConfig::load(&dir.join(file)).unwrap();
        assert_eq!(c.env.grasp.modality, m, "{file}");
        c.env.grasp.modality = quick.env.grasp.modality;
        c.name = quick.name.clone();
        assert_eq!(c, quick, "{file}");
    }
    let stream = TrainConfig::load(&dir.join("stream.toml")).unwrap();
    assert_eq!(stream.objects, "procedural");
    assert!(stream.env.grasp.randomization.enabled);
    let base = TrainConfig::load(&dir.join("base.toml")).unwrap();
    let mut dflt = TrainConfig::load(&dir.join("gru_m3_pca5.toml")).unwrap();
    assert_eq!(dflt.name, base.name);
    dflt.name = base.name.clone();
    assert_eq!(dflt, base);
    let m1 = TrainConfig::load(&dir.join("gru_m1_pca5.toml")).unwrap();
    assert_eq!(m1.env.grasp.modality, grasp::env::obs::Modality::M1);
    assert_eq!(
        TrainConfig::load(&dir.join("gru_m3_pca8.toml"))
            .unwrap()
            .n_components,
        8
    );
}

#[test]
fn each_lever_config_is_the_shipped_recipe_with_one_change() {
    // configs/levers/*.toml (the issue-29 lever table): ship.toml with one setting changed.
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("configs");
    let ship = TrainConfig::load(&dir.join("ship.toml")).unwrap();
    let mut n = 0;
    for e in std::fs::read_dir(dir.join("levers")).unwrap() {
        let p = e.unwrap().path();
        let file = p.file_stem().unwrap().to_string_lossy().into_owned();
        // The main job's variants (quick_*) and ship_g90 (ship.toml's run continued at
        // another gamma) live beside the levers; they are checked in shipped_configs_load.
        if file.starts_with("quick_") || file == "ship_g90" {
            continue;
        }
        // The simulator variants for A/B runs are simulator configs, not recipes.
        if file.starts_with("sim_") {
            grasp::sim::SimConfig::load(&p).unwrap_or_else(|e| panic!("{file}: {e}"));
            continue;
        }
        let mut c = TrainConfig::load(&p).unwrap_or_else(|e| panic!("{file}: {e}"));
        assert_eq!(c.name, format!("ship_{file}"));
        c.name = ship.name.clone();
        let g = &mut c.env.grasp;
        match file.as_str() {
            "m3g" => {
                assert_eq!(g.modality, grasp::env::obs::Modality::M3G);
                g.modality = ship.env.grasp.modality;
            }
            "critic_state" => {
                assert!(g.critic_state);
                g.critic_state = false;
            }
            "grip" => {
                assert_eq!(g.action.grip_scale, 1.0);
                g.action.grip_scale = 0.0;
            }
            "grip_half" => {
                assert_eq!(g.action.grip_scale, 0.5);
                g.action.grip_scale = 0.0;
            }
            "displacement" => {
                assert_eq!(g.reward.displacement_weight, 10.0);
                g.reward.displacement_weight = 0.0;
            }
            "object_curriculum" => {
                assert!(g.object_curriculum.enabled);
                g.object_curriculum.enabled = false;
            }
            "no_wrist" => {
                assert_eq!(g.action.wrist_scale, 0.0);
                g.action.wrist_scale = ship.env.grasp.action.wrist_scale;
            }
            other => panic!("an unexpected lever config {other}.toml"),
        }
        assert_eq!(c, ship, "{file}.toml changes more than its lever");
        n += 1;
    }
    assert_eq!(n, 7);
    // The main job (quick.toml) is the grip_half lever's recipe with 8 synergies and the
    // grip at a quarter, delayed by a step and squeezed at the lift where it acts; only
    // that, its name, its time cap and how often it redraws the curve differ.
    let mut quick = TrainConfig::load(&dir.join("quick.toml")).unwrap();
    let half = TrainConfig::load(&dir.join("levers/grip_half.toml")).unwrap();
    assert_eq!(quick.time_budget_minutes, Some(15.0));
    assert_eq!((quick.n_components, half.n_components), (8, 5));
    assert_eq!(quick.env.grasp.action.grip_scale, 0.25);
    quick.env.grasp.action.grip_scale = half.env.grasp.action.grip_scale;
    quick.env.grasp.action.grip_ramp = half.env.grasp.action.grip_ramp;
    quick.env.grasp.action.grip_delay = half.env.grasp.action.grip_delay;
    quick.env.grasp.action.grip_ramp_in_training = half.env.grasp.action.grip_ramp_in_training;
    quick.env.grasp.action.lift_squeeze = half.env.grasp.action.lift_squeeze;
    quick.env.grasp.action.lift_squeeze_in_training =
        half.env.grasp.action.lift_squeeze_in_training;
    quick.n_components = half.n_components;
    quick.name = half.name.clone();
    quick.time_budget_minutes = half.time_budget_minutes;
    quick.plot_every = half.plot_every;
    assert_eq!(quick, half, "quick.toml differs from levers/grip_half.toml");
}

#[test]
fn a_run_killed_before_its_first_checkpoint_starts_afresh() {
    let tmp = tempfile::tempdir().unwrap();
    let cfg = cartpole_config(tmp.path(), 128);
    // What `grasp train` leaves when killed during its first update: the resolved config,
    // a metrics file without rows, an event file, no checkpoint.
    let run = tmp.path().join("run");
    std::fs::create_dir_all(&run).unwrap();
    let c = TrainConfig::load(&cfg).unwrap();
    std::fs::write(run.join("config.toml"), c.to_toml_string().unwrap()).unwrap();
    std::fs::write(run.join("metrics.csv"), format!("{HEADER}\n")).unwrap();
    std::fs::write(run.join("events.out.tfevents.1.grasp"), b"").unwrap();
    for resume in [false, true] {
        let mut args = vec!["train", "--config", s(&cfg), "--out", s(&run)];
        if resume {
            args.push("--resume");
            // Killed again during its first update.
            std::fs::remove_dir_all(run.join("checkpoints")).unwrap();
            std::fs::write(run.join("metrics.csv"), format!("{HEADER}\n")).unwrap();
        }
        let out = ok(&grasp(&args));
        assert!(out.contains("completed: 2 updates (2 new)"), "{out}");
        assert_eq!(updates(&run), vec![1, 2]);
        let events = std::fs::read_dir(&run)
            .unwrap()
            .filter(|e| {
                e.as_ref()
                    .unwrap()
                    .file_name()
                    .to_string_lossy()
                    .contains("tfevents")
            })
            .count();
        assert_eq!(events, 1);
    }
}

#[test]
fn resume_without_metrics_keeps_the_best_checkpoint() {
    let tmp = tempfile::tempdir().unwrap();
    let cfg = cartpole_config(tmp.path(), 128);
    let run = tmp.path().join("run");
    ok(&grasp(&["train", "--config", s(&cfg), "--out", s(&run)]));
    let best = run.join("checkpoints/best/checkpoint.safetensors");
    let before = std::fs::read(&best).unwrap();
    std::fs::remove_file(run.join("metrics.csv")).unwrap();
    let e = grasp(&[
        "train",
        "--config",
        s(&cfg),
        "--out",
        s(&run),
        "--resume",
        "--total-timesteps",
        "256",
    ]);
    assert_eq!(e.status.code(), Some(1));
    let err = String::from_utf8_lossy(&e.stderr);
    assert!(
        err.contains("metrics.csv is missing") && err.contains("checkpoints/best"),
        "{err}"
    );
    assert_eq!(std::fs::read(&best).unwrap(), before);
}

#[cfg(unix)]
#[test]
fn ctrl_c_finishes_the_update_writes_a_checkpoint_and_exits_130() {
    let tmp = tempfile::tempdir().unwrap();
    // Many updates and no periodic checkpoint: only the interrupt writes one.
    let cfg = write(
        tmp.path(),
        "cp.toml",
        "name = \"cp\"\nseed = 5\ntotal_timesteps = 6400000\nnum_envs = 2\nthreads = 1\n\
         checkpoint_every = 100000\nplot_every = 100000\nbest_window = 2\n[ppo]\n\
         num_steps = 32\nnum_minibatches = 2\nupdate_epochs = 2\n[policy]\nkind = \"mlp\"\n\
         mlp_hidden = 16\n[env]\nkind = \"cartpole\"\ncartpole_max_steps = 50\n",
    );
    let run = tmp.path().join("run");
    let mut child = Command::new(env!("CARGO_BIN_EXE_grasp"))
        .args(["train", "--config", s(&cfg), "--out", s(&run)])
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    // Wait for a few updates.
    let start = std::time::Instant::now();
    let ready = || run.join("metrics.csv").is_file() && updates(&run).len() >= 3;
    while !ready() {
        assert!(start.elapsed().as_secs() < 120, "no updates");
        std::thread::sleep(std::time::Duration::from_millis(50));
    }
    let st = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(st.success());
    let start = std::time::Instant::now();
    while child.try_wait().unwrap().is_none() {
        assert!(start.elapsed().as_secs() < 60, "did not stop after SIGINT");
        std::thread::sleep(std::time::Duration::from_millis(50));
    }
    let out = child.wait_with_output().unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert_eq!(out.status.code(), Some(130), "{stdout}");
    assert!(stdout.starts_with("interrupted: "), "{stdout}");
    let done = updates(&run);
    assert!(done.len() >= 3);
    // The checkpoint holds the last finished update: a resume continues after it.
    assert!(run
        .join("checkpoints/latest/checkpoint.safetensors")
        .is_file());
    let n = *done.last().unwrap();
    let total = (n + 1) * 64;
    let more = ok(&grasp(&[
        "train",
        "--config",
        s(&cfg),
        "--out",
        s(&run),
        "--resume",
        "--total-timesteps",
        &total.to_string(),
    ]));
    assert!(
        more.contains(&format!("{} updates (1 new)", n + 1)),
        "{more}"
    );
}

/// A cart-pole run of many updates with no periodic checkpoint, started in the
/// background; returns once it has recorded `updates` updates.
#[cfg(unix)]
fn start_long_run(cfg: &Path, run: &Path, updates: usize) -> std::process::Child {
    let child = Command::new(env!("CARGO_BIN_EXE_grasp"))
        .args(["train", "--config", s(cfg), "--out", s(run)])
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let start = std::time::Instant::now();
    let ready = || run.join("metrics.csv").is_file() && self::updates(run).len() >= updates;
    while !ready() {
        assert!(start.elapsed().as_secs() < 120, "no updates");
        std::thread::sleep(std::time::Duration::from_millis(50));
    }
    child
}

#[cfg(unix)]
fn long_config(dir: &Path) -> PathBuf {
    write(
        dir,
        "long.toml",
        "name = \"cp\"\nseed = 5\ntotal_timesteps = 6400000\nnum_envs = 2\nthreads = 1\n\
         checkpoint_every = 100000\nplot_every = 100000\nbest_window = 2\n[ppo]\n\
         num_steps = 32\nnum_minibatches = 2\nupdate_epochs = 2\n[policy]\nkind = \"mlp\"\n\
         mlp_hidden = 16\n[env]\nkind = \"cartpole\"\ncartpole_max_steps = 50\n",
    )
}

/// Sends `signal` to `child` and waits (at most a minute) for it to end.
#[cfg(unix)]
fn stop(child: std::process::Child, signal: &str) -> Output {
    let st = Command::new("kill")
        .args([signal, &child.id().to_string()])
        .status()
        .unwrap();
    assert!(st.success());
    let mut child = child;
    let start = std::time::Instant::now();
    while child.try_wait().unwrap().is_none() {
        assert!(
            start.elapsed().as_secs() < 60,
            "did not stop after {signal}"
        );
        std::thread::sleep(std::time::Duration::from_millis(50));
    }
    child.wait_with_output().unwrap()
}

#[cfg(unix)]
#[test]
fn one_process_at_a_time_trains_in_a_run_folder() {
    let tmp = tempfile::tempdir().unwrap();
    let cfg = long_config(tmp.path());
    let run = tmp.path().join("run");
    let first = start_long_run(&cfg, &run, 1);
    let other = cartpole_config(tmp.path(), 128);
    for resume in [false, true] {
        let mut args = vec!["train", "--config", s(&other), "--out", s(&run)];
        if resume {
            args.push("--resume");
        }
        let e = grasp(&args);
        let err = String::from_utf8_lossy(&e.stderr);
        assert_eq!(e.status.code(), Some(1), "{err}");
        assert!(err.contains("is in use by another process"), "{err}");
    }
    // The second process changed nothing: the config is the first run's.
    let saved = TrainConfig::load(&run.join("config.toml")).unwrap();
    assert_eq!(saved.total_timesteps, 6_400_000);
    let out = stop(first, "-INT");
    assert_eq!(out.status.code(), Some(130));
    // The lock went with the process.
    let more = ok(&grasp(&[
        "train",
        "--config",
        s(&cfg),
        "--out",
        s(&run),
        "--resume",
        "--total-timesteps",
        &((updates(&run).len() as u64 + 1) * 64).to_string(),
    ]));
    assert!(more.contains("(1 new)"), "{more}");
}

#[cfg(unix)]
#[test]
fn sigterm_writes_a_checkpoint_as_ctrl_c_does() {
    let tmp = tempfile::tempdir().unwrap();
    let cfg = long_config(tmp.path());
    let run = tmp.path().join("run");
    let child = start_long_run(&cfg, &run, 2);
    let out = stop(child, "-TERM");
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert_eq!(out.status.code(), Some(130), "{stdout}");
    assert!(stdout.starts_with("interrupted: "), "{stdout}");
    assert!(run
        .join("checkpoints/latest/checkpoint.safetensors")
        .is_file());
}

#[test]
fn a_run_without_its_latest_checkpoint_is_never_deleted() {
    let tmp = tempfile::tempdir().unwrap();
    let cfg = cartpole_config(tmp.path(), 128);
    let run = tmp.path().join("run");
    ok(&grasp(&["train", "--config", s(&cfg), "--out", s(&run)]));
    std::fs::remove_dir_all(run.join("checkpoints/latest")).unwrap();
    let snapshot = |dir: &Path| {
        let mut files: Vec<(String, Vec<u8>)> = Vec::new();
        let mut stack = vec![dir.to_path_buf()];
        while let Some(d) = stack.pop() {
            for e in std::fs::read_dir(&d).unwrap() {
                let p = e.unwrap().path();
                if p.is_dir() {
                    stack.push(p);
                } else {
                    files.push((p.display().to_string(), std::fs::read(&p).unwrap()));
                }
            }
        }
        files.sort();
        files
    };
    let before = snapshot(&run);
    for resume in [true, false] {
        let mut args = vec!["train", "--config", s(&cfg), "--out", s(&run)];
        if resume {
            args.push("--resume");
        }
        let e = grasp(&args);
        let err = String::from_utf8_lossy(&e.stderr);
        assert_eq!(e.status.code(), Some(1), "{err}");
        assert!(
            err.contains("2 metrics rows") && err.contains("nothing was changed"),
            "{err}"
        );
        assert!(
            err.contains("copy") && err.contains("checkpoints/best"),
            "{err}"
        );
        assert_eq!(snapshot(&run), before);
    }
    // Doing what it says continues the run.
    let best = run.join("checkpoints/best");
    let latest = run.join("checkpoints/latest");
    std::fs::create_dir_all(&latest).unwrap();
    for e in std::fs::read_dir(&best).unwrap() {
        let e = e.unwrap();
        std::fs::copy(e.path(), latest.join(e.file_name())).unwrap();
    }
    let out = ok(&grasp(&[
        "train",
        "--config",
        s(&cfg),
        "--out",
        s(&run),
        "--resume",
        "--total-timesteps",
        "256",
    ]));
    assert!(out.contains("completed: 4 updates"), "{out}");
}

#[test]
fn resume_refuses_a_changed_environment_unless_asked() {
    let tmp = tempfile::tempdir().unwrap();
    let cfg = cartpole_config(tmp.path(), 64);
    let run = tmp.path().join("run");
    ok(&grasp(&["train", "--config", s(&cfg), "--out", s(&run)]));
    let text = std::fs::read_to_string(&cfg).unwrap();
    let changed = write(
        tmp.path(),
        "changed.toml",
        &(text.replace(
            "cartpole_max_steps = 50",
            "cartpole_max_steps = 60\nat_max_steps = \"lift\"",
        ) + "[env.randomization]\nfriction = [0.6, 0.9]\n"),
    );
    let resume = |extra: &[&str]| {
        let mut args = vec![
            "train",
            "--config",
            s(&changed),
            "--out",
            s(&run),
            "--resume",
            "--total-timesteps",
            "128",
        ];
        args.extend(extra);
        grasp(&args)
    };
    let e = resume(&[]);
    let err = String::from_utf8_lossy(&e.stderr);
    assert_eq!(e.status.code(), Some(1), "{err}");
    for key in [
        "env.at_max_steps",
        "env.cartpole_max_steps",
        "env.randomization.friction",
        "--allow-env-change",
    ] {
        assert!(err.contains(key), "{key}: {err}");
    }
    assert_eq!(updates(&run), vec![1]);
    let out = ok(&resume(&["--allow-env-change"]));
    assert!(out.contains("completed: 2 updates (1 new)"), "{out}");
    // The same environment resumes without the flag.
    let out = ok(&grasp(&[
        "train",
        "--config",
        s(&changed),
        "--out",
        s(&run),
        "--resume",
        "--total-timesteps",
        "192",
    ]));
    assert!(out.contains("(1 new)"), "{out}");
}

#[test]
fn milestones_keep_a_checkpoint_every_n_updates() {
    // milestone_every = 2 on a 3-update cart-pole run (64 transitions per update): one
    // milestone, after update 2, named by its transitions, loadable as a checkpoint folder
    // (config.toml beside it), and the resolved config keeps the setting.
    let tmp = tempfile::tempdir().unwrap();
    let base = cartpole_config(tmp.path(), 192);
    let text = std::fs::read_to_string(&base).unwrap();
    let cfg = write(
        tmp.path(),
        "ms.toml",
        &text.replace(
            "checkpoint_every = 1\n",
            "checkpoint_every = 1\nmilestone_every = 2\n",
        ),
    );
    let run = tmp.path().join("run");
    ok(&grasp(&["train", "--config", s(&cfg), "--out", s(&run)]));
    let mut kept: Vec<String> = std::fs::read_dir(run.join("checkpoints"))
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with("step_"))
        .collect();
    kept.sort();
    assert_eq!(kept, vec!["step_128".to_string()]);
    let ms = run.join("checkpoints/step_128");
    assert!(ms.join("checkpoint.safetensors").is_file());
    assert_eq!(
        TrainConfig::load(&ms.join("config.toml"))
            .unwrap()
            .milestone_every,
        2
    );
}

#[test]
fn fig5_and_sensing_configs_change_one_thing_each() {
    // configs/fig5/*.toml (issue 50): ship.toml's recipe (no grip), one change per variant.
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("configs");
    let ship = TrainConfig::load(&dir.join("ship.toml")).unwrap();
    assert_eq!(ship.env.grasp.action.grip_scale, 0.0);
    let m3 = TrainConfig::load(&dir.join("fig5/m3.toml")).unwrap();
    assert_eq!(m3.name, "fig5_gru_m3_pca5");
    let mut same = m3.clone();
    same.name = ship.name.clone();
    assert_eq!(same, ship);
    let mut n = 0;
    for e in std::fs::read_dir(dir.join("fig5")).unwrap() {
        let p = e.unwrap().path();
        let file = p.file_stem().unwrap().to_string_lossy().into_owned();
        let mut c = TrainConfig::load(&p).unwrap_or_else(|e| panic!("{file}: {e}"));
        match file.as_str() {
            "m3" => {}
            "m1" | "m2" => {
                let m = if file == "m1" {
                    grasp::env::obs::Modality::M1
                } else {
                    grasp::env::obs::Modality::M2
                };
                assert_eq!(c.env.grasp.modality, m);
                c.env.grasp.modality = m3.env.grasp.modality;
            }
            "mlp" => {
                assert_eq!(c.policy.kind, grasp::policy::PolicyKind::Mlp);
                c.policy.kind = m3.policy.kind;
            }
            pca => {
                let k: usize = pca.trim_start_matches("pca").parse().unwrap();
                assert_eq!(c.n_components, k);
                c.n_components = m3.n_components;
            }
        }
        c.name = m3.name.clone();
        assert_eq!(c, m3, "{file}");
        n += 1;
    }
    assert_eq!(n, 7);
    // The sensing study: Fig. 5's modality arms from the perturbed pre-grasp, and its
    // evaluation conditions are the training perturbations.
    let s3 = TrainConfig::load(&dir.join("sensing/m3.toml")).unwrap();
    let g = &s3.env.grasp;
    assert_eq!(g.placement.antipodal, 1.0);
    assert!(g.randomization.enabled && g.randomization.size_scale == [1.0, 1.0]);
    let cond = grasp::eval::conditions::EvalConditions::load(&dir.join("sensing/conditions.toml"))
        .unwrap();
    assert_eq!(cond.randomization, g.randomization);
    assert_eq!(
        (
            cond.placement.offset,
            cond.placement.height,
            cond.placement.yaw
        ),
        (g.placement.offset, g.placement.height, g.placement.yaw)
    );
    let mut plain = s3.clone();
    plain.env.grasp.placement = m3.env.grasp.placement;
    plain.env.grasp.randomization = m3.env.grasp.randomization.clone();
    plain.name = m3.name.clone();
    assert_eq!(plain, m3);
    for (file, m) in [
        ("sensing/m1.toml", grasp::env::obs::Modality::M1),
        ("sensing/m2.toml", grasp::env::obs::Modality::M2),
    ] {
        let mut c = TrainConfig::load(&dir.join(file)).unwrap();
        assert_eq!(c.env.grasp.modality, m, "{file}");
        c.env.grasp.modality = s3.env.grasp.modality;
        c.name = s3.name.clone();
        assert_eq!(c, s3, "{file}");
    }
    // Both grids plan: 7 variants x 3 seeds, and 3 x 3.
    for (grid, runs) in [("grids/fig5.toml", 21), ("grids/sensing.toml", 9)] {
        let plan = grasp::experiment::plan(&dir.join(grid), Path::new("runs/x")).unwrap();
        assert_eq!(plan.runs.len(), runs, "{grid}");
    }
}
