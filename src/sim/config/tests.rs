//! Tests of `config`.

use super::*;

#[test]
fn one_rule_for_an_optional_sim_config_file() {
    // None: the built-in defaults; the shipped file: itself (it holds the defaults),
    // also when absent from the working folder; any other file must exist.
    assert_eq!(
        SimConfig::load_or_default(None).unwrap(),
        SimConfig::default()
    );
    let shipped = Path::new(env!("CARGO_MANIFEST_DIR")).join(DEFAULT_PATH);
    assert_eq!(
        SimConfig::load_or_default(Some(&shipped)).unwrap(),
        SimConfig::default()
    );
    let here = std::env::current_dir().unwrap();
    if !here.join(DEFAULT_PATH).exists() {
        assert!(SimConfig::load_or_default(Some(Path::new(DEFAULT_PATH))).is_ok());
    }
    let e = SimConfig::load_or_default(Some(Path::new("no/such/sim.toml")))
        .unwrap_err()
        .to_string();
    assert!(e.contains("no/such/sim.toml"), "{e}");
}

#[test]
fn embedded_defaults_are_valid() {
    let c = SimConfig::default();
    c.validate().unwrap();
    assert_eq!(
        c.sensors.torque_thresholds,
        vec![-20.0, -10.0, 0.0, 10.0, 20.0]
    );
    assert_eq!(
        c.steps_per_control(),
        (c.control_period / c.dt).round() as usize
    );
}

#[test]
fn settings_that_decide_every_episode_are_refused() {
    // Each valid alone before issue 49; together with the defaults every lift failed,
    // every floating object succeeded, or every episode was a physics failure.
    type Edit = fn(&mut SimConfig);
    let cases: [(Edit, &str); 5] = [
        (
            |c| c.lift.success_height = 0.5,
            "'lift.success_height' = 0.5: must be below lift.height 0.15 m",
        ),
        (|c| c.gravity = 9.81, "'gravity' = 9.81: must be negative"),
        (|c| c.gravity = 0.0, "'gravity' = 0: must be negative"),
        (
            |c| c.contacts.natural_frequency = 1e-6,
            "'contacts.natural_frequency' = 1e-6: too soft: a body resting on such a \
                 contact sinks about 2.48e11 m, beyond failure.max_penetration 0.02 m",
        ),
        (
            |c| c.contacts.static_natural_frequency = 2.0,
            "use more than 3.5 Hz",
        ),
    ];
    for (edit, want) in cases {
        let mut c = SimConfig::default();
        edit(&mut c);
        let e = c.validate().unwrap_err().to_string();
        assert!(e.contains(want), "want '{want}', got: {e}");
    }
    // Just inside the bounds is accepted.
    let mut c = SimConfig::default();
    c.lift.success_height = 0.149;
    c.contacts.natural_frequency = 4.0;
    c.gravity = -1.0;
    c.validate().unwrap();
}

#[test]
fn table_hull_config_is_the_default_but_for_its_switch() {
    let path = Path::new("configs/levers/sim_table_hull.toml");
    let hull = SimConfig::parse(
        path,
        include_str!("../../../configs/levers/sim_table_hull.toml"),
    )
    .unwrap();
    let mut default = SimConfig::default();
    assert!(!default.contacts.table_hull && hull.contacts.table_hull);
    default.contacts.table_hull = true;
    assert_eq!(hull, default);
    // The stiffness is checked.
    for bad in [0.5, 9.0, f64::NAN] {
        let mut c = hull.clone();
        c.contacts.table_hull_stiffness = bad;
        let e = c.validate().unwrap_err().to_string();
        assert!(e.contains("contacts.table_hull_stiffness"), "{e}");
    }
}

#[test]
fn absent_solver_and_recycling_fields_keep_rapiers_defaults() {
    let text: String = DEFAULT_SIM_TOML
        .lines()
        .filter(|l| {
            !l.starts_with("pgs_iterations")
                && !l.starts_with("recycle_distance")
                && !l.starts_with("coriolis")
        })
        .map(|l| format!("{l}\n"))
        .collect();
    let c = SimConfig::parse(Path::new("s.toml"), &text).unwrap();
    assert_eq!(c.pgs_iterations, 1);
    assert_eq!(c.contacts.recycle_distance, 0.05);
    assert_eq!(c.coriolis, CoriolisModel::Implicit);
    let d = SimConfig::default();
    assert_eq!(d.pgs_iterations, 4);
    assert_eq!(d.coriolis, CoriolisModel::Explicit);
    assert_ne!(c, d);
}

#[test]
fn out_of_range_fields_are_named() {
    let mut c = SimConfig::default();
    c.friction.hand = 1.2;
    let e = c.validate().unwrap_err().to_string();
    assert!(e.contains("friction.hand"), "{e}");
    let c = SimConfig {
        dt: 0.0,
        ..Default::default()
    };
    assert!(c.validate().unwrap_err().to_string().contains("'dt'"));
    for bad in [0.0, -0.01, 0.2, f64::NAN] {
        let c = SimConfig {
            prediction_distance: bad,
            ..Default::default()
        };
        let e = c.validate().unwrap_err().to_string();
        assert!(e.contains("prediction_distance"), "{e}");
    }
    let c = SimConfig {
        ccd_substeps: 17,
        ..Default::default()
    };
    assert!(c
        .validate()
        .unwrap_err()
        .to_string()
        .contains("ccd_substeps"));
    for bad_damping in [-0.1, f64::NAN, 11.0] {
        let c = SimConfig {
            object_angular_damping: bad_damping,
            ..Default::default()
        };
        let e = c.validate().unwrap_err().to_string();
        assert!(e.contains("object_angular_damping"), "{e}");
    }
    // A tiny value is printed short, not as 300 digits.
    let e = SimConfig {
        dt: 1e-300,
        ..Default::default()
    }
    .validate()
    .unwrap_err()
    .to_string();
    assert!(e.contains("= 1e-300: must be in"), "{e}");
    // Values that pass `> 0` but would never finish an episode.
    for (field, c) in [
        (
            "'dt'",
            SimConfig {
                dt: 1e-300,
                ..Default::default()
            },
        ),
        (
            "'control_period'",
            SimConfig {
                control_period: 1e9,
                ..Default::default()
            },
        ),
    ] {
        let e = c.validate().unwrap_err().to_string();
        assert!(e.contains(field), "{e}");
    }
    for (field, ramp, hold) in [("lift.ramp_time", 1e9, 0.5), ("lift.hold_time", 0.6, 1e9)] {
        let mut c = SimConfig::default();
        c.lift.ramp_time = ramp;
        c.lift.hold_time = hold;
        let e = c.validate().unwrap_err().to_string();
        assert!(e.contains(field), "{e}");
    }
    for bad in [0, 65] {
        let c = SimConfig {
            pgs_iterations: bad,
            ..Default::default()
        };
        let e = c.validate().unwrap_err().to_string();
        assert!(e.contains("pgs_iterations"), "{e}");
    }
    for bad in [-0.01, f64::NAN, 0.2] {
        let mut c = SimConfig::default();
        c.contacts.recycle_distance = bad;
        let e = c.validate().unwrap_err().to_string();
        assert!(e.contains("contacts.recycle_distance"), "{e}");
    }
    let mut c = SimConfig::default();
    c.contacts.recycle_distance = 0.0;
    assert!(c.validate().is_ok(), "0 turns recycling off");
    let mut c = SimConfig::default();
    c.motors.thumb.kp = f64::NAN;
    assert!(c
        .validate()
        .unwrap_err()
        .to_string()
        .contains("motors.thumb.kp"));
    let mut c = SimConfig::default();
    c.sensors.torque_thresholds = vec![0.0, -1.0];
    assert!(c
        .validate()
        .unwrap_err()
        .to_string()
        .contains("torque_thresholds[1]"));
}

#[test]
fn unknown_coriolis_model_is_an_error_naming_it() {
    let text = DEFAULT_SIM_TOML.replace("coriolis = \"explicit\"", "coriolis = \"sideways\"");
    let e = SimConfig::parse(Path::new("s.toml"), &text)
        .unwrap_err()
        .to_string();
    assert!(e.contains("s.toml") && e.contains("sideways"), "{e}");
}

#[test]
fn model_names_of_another_type_list_the_valid_ones() {
    for (key, old, want) in [
        (
            "coriolis",
            "coriolis = \"explicit\"",
            "one of \"implicit\", \"explicit\"",
        ),
        (
            "drive",
            "drive = \"spring\"",
            "one of \"spring\", \"motor_row\"",
        ),
        (
            "limit_rows",
            "limit_rows = \"near\"",
            "one of \"near\", \"always\"",
        ),
    ] {
        let text = DEFAULT_SIM_TOML.replace(old, &format!("{key} = 1"));
        let e = SimConfig::parse(Path::new("s.toml"), &text)
            .unwrap_err()
            .to_string();
        assert!(e.contains("s.toml") && e.contains(want), "{e}");
    }
}

#[test]
fn unknown_key_is_an_error_with_line() {
    let text = DEFAULT_SIM_TOML.replace("substeps =", "substepz =");
    let e = SimConfig::parse(Path::new("s.toml"), &text)
        .unwrap_err()
        .to_string();
    assert!(e.contains("s.toml") && e.contains("substepz"), "{e}");
}
