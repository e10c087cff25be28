//! Tests of `experiment`.

use super::*;

fn grid_text(extra: &str) -> String {
    format!(
        "name = \"g\"\nseeds = [1, 2]\n{extra}\n[[ablation]]\nname = \"policy\"\n\
             configs = [\"gru_m3_pca5.toml\", \"mlp_m3_pca5.toml\"]\n\n[[ablation]]\n\
             name = \"pca\"\nconfigs = [\"gru_m3_pca3.toml\", \"gru_m3_pca5.toml\"]\n"
    )
}

fn write_grid(dir: &Path, text: &str) -> PathBuf {
    let configs = Path::new(env!("CARGO_MANIFEST_DIR")).join("configs");
    for f in [
        "base.toml",
        "gru_m3_pca5.toml",
        "mlp_m3_pca5.toml",
        "gru_m3_pca3.toml",
    ] {
        std::fs::copy(configs.join(f), dir.join(f)).unwrap();
    }
    let p = dir.join("grid.toml");
    std::fs::write(&p, text).unwrap();
    p
}

#[test]
fn resume_refuses_a_grid_that_trains_existing_runs_differently() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let p = write_grid(dir.path(), &grid_text("[budget]\ntransitions = 640\n"));
    let first = plan(&p, &out).unwrap();
    // A finished run, saved as the grid then planned it (threads and the minutes
    // left are set anew on every resume).
    let r = &first.runs[0];
    let mut cfg = first.variants[r.variant].config.clone();
    cfg.seed = r.seed;
    cfg.threads = Some(3);
    std::fs::create_dir_all(&r.dir).unwrap();
    std::fs::write(r.dir.join(files::CONFIG), cfg.to_toml_string().unwrap()).unwrap();
    let record = RunRecord {
        variant: first.variants[r.variant].name.clone(),
        seed: r.seed,
        updates: 1,
        transitions: 640,
        episodes: 1,
        wall_s: 1.0,
        stop: "completed".into(),
    };
    std::fs::write(
        r.dir.join(DONE_FILE),
        serde_json::to_string(&record).unwrap(),
    )
    .unwrap();
    check_unchanged(&first, r).unwrap();
    // The grid edited: other transitions and objects.
    let p = write_grid(
        dir.path(),
        &grid_text("[budget]\ntransitions = 1280\n[overrides]\nobjects = \"box_sugar\"\n"),
    );
    let edited = plan(&p, &out).unwrap();
    let opts = GridOptions {
        budget_minutes: None,
        resume: true,
        threads: 1,
        parallel: None,
    };
    let e = run_grid(&edited, &opts, &|_| {}).unwrap_err().to_string();
    assert!(
        e.contains("cannot resume") && e.contains("objects, total_timesteps"),
        "{e}"
    );
    assert!(!edited.runs[1].dir.exists(), "nothing was trained");
}

#[test]
fn plan_dedupes_variants_and_applies_the_budget() {
    let dir = tempfile::tempdir().unwrap();
    let p = write_grid(
            dir.path(),
            &grid_text("[budget]\ntransitions = 640\nminutes = 2.5\n[overrides]\nnum_envs = 4\nnum_minibatches = 2\n"),
        );
    let plan = plan(&p, Path::new("out")).unwrap();
    let names: Vec<&str> = plan.variants.iter().map(|v| v.name.as_str()).collect();
    assert_eq!(names, ["gru_m3_pca5", "mlp_m3_pca5", "gru_m3_pca3"]);
    let labels: Vec<&str> = plan.variants.iter().map(|v| v.label.as_str()).collect();
    assert_eq!(labels, ["GRU-M3PCA5", "MLP-M3PCA5", "GRU-M3PCA3"]);
    assert_eq!(plan.ablations, vec![vec![0, 1], vec![2, 0]]);
    // No `reference`: each ablation's first config.
    assert_eq!(plan.references, vec![0, 2]);
    assert_eq!(plan.runs.len(), 6);
    assert_eq!(plan.runs[1].dir, Path::new("out/gru_m3_pca5/seed2"));
    let c = &plan.variants[0].config;
    assert_eq!(c.total_timesteps, 640);
    assert_eq!(c.time_budget_minutes, Some(2.5));
    assert_eq!(c.num_envs, 4);
    assert_eq!(c.ppo.num_minibatches, 2);
}

#[test]
fn bad_grids_name_the_field() {
    let dir = tempfile::tempdir().unwrap();
    for (extra, field) in [
        ("parallel = 0", "parallel"),
        ("[budget]\nminutes = -1.0", "budget.minutes"),
        (
            "[overrides]\nnum_envs = 3\nnum_minibatches = 2",
            "num_minibatches",
        ),
        (
            "[eval]\nobjects = \"unseen\"\ntrials = 1\ndifficulty = 2.0",
            "eval.difficulty",
        ),
        ("bogus = 1", "bogus"),
        ("[eval]\nobjects = []\ntrials = 1", "eval.objects"),
        (
            "[eval]\nobjects = \"unseen\"\ntrials = 1\npregrasp = \"sideways\"",
            "`top-down` or `antipodal`",
        ),
    ] {
        let p = write_grid(dir.path(), &grid_text(extra));
        let e = plan(&p, Path::new("out")).unwrap_err().to_string();
        assert!(e.contains(field), "{extra}: {e}");
    }
    let p = write_grid(
        dir.path(),
        "name = \"g\"\nseeds = [1]\n[[ablation]]\nname = \"a\"\nconfigs = \
             [\"gru_m3_pca5.toml\"]\nreference = \"mlp_m3_pca5.toml\"\n",
    );
    let e = plan(&p, Path::new("o")).unwrap_err().to_string();
    assert!(e.contains("ablation[0].reference"), "{e}");
    // A config twice in one ablation compared a variant with itself; a grid's trials
    // are bounded as `grasp eval --trials` is (10^8 ran for hours); a set evaluated
    // twice was shown twice.
    let p = write_grid(
        dir.path(),
        "name = \"g\"\nseeds = [1]\n[[ablation]]\nname = \"a\"\nconfigs = \
             [\"gru_m3_pca5.toml\", \"gru_m3_pca5.toml\"]\n",
    );
    let e = plan(&p, Path::new("o")).unwrap_err().to_string();
    assert!(
        e.contains("ablation[0].configs") && e.contains("gru_m3_pca5.toml is listed twice"),
        "{e}"
    );
    for (eval, want) in [
        (
            "[eval]\nobjects = \"unseen\"\ntrials = 100000000",
            "eval.trials`: 100000000 must be in 0..=10000",
        ),
        (
            "[eval]\nobjects = [\"unseen\", \"unseen\"]\ntrials = 1",
            "eval.objects`: 'unseen' is listed twice",
        ),
    ] {
        let p = write_grid(dir.path(), &grid_text(eval));
        let e = plan(&p, Path::new("o")).unwrap_err().to_string();
        assert!(e.contains(want), "{eval}: {e}");
    }
    let p = write_grid(dir.path(), "name = \"g\"\nseeds = [1, 1]\nablation = []\n");
    assert!(plan(&p, Path::new("o"))
        .unwrap_err()
        .to_string()
        .contains("twice"));
    let p = write_grid(
        dir.path(),
        "name = \"g\"\nseeds = [1]\n[[ablation]]\nname = \"a\"\nconfigs = [\"nope.toml\"]\n",
    );
    assert!(plan(&p, Path::new("o"))
        .unwrap_err()
        .to_string()
        .contains("nope.toml"));
}
