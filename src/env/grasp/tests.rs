//! Tests of `grasp`.

use super::*;
use crate::env::placement::PlacementConfig;
use crate::env::reward::RewardConfig;
use crate::robot::Side;

/// The default environment on `object` alone (named "box").
pub(super) fn env_on(object: ObjectSpec) -> GraspEnv {
    env_with(object, EnvConfig::default())
}

/// The environment of `cfg` on `object` alone (named "box").
fn env_with(object: ObjectSpec, cfg: EnvConfig) -> GraspEnv {
    GraspEnv::new(
        &Robot::builtin(Side::Left),
        vec![("box".to_string(), object)],
        crate::synergy::default_model(),
        SimConfig::default(),
        cfg,
    )
    .expect("env")
}

/// The default environment on the default box alone.
fn box_env() -> GraspEnv {
    env_on(ObjectSpec::default_box())
}

#[test]
fn the_grip_ramp_counts_the_episodes_control_steps() {
    // With the grip at full scale and the ramp at 0.125, the grip g = 1 at steps 1 and
    // 2 commands what g = 0.125 and then g = 0.25 command without the ramp (exact in
    // binary).
    let ramped_by = |ramp: f64| {
        let mut c = EnvConfig::default();
        c.action.grip_scale = 1.0;
        c.action.grip_ramp = ramp;
        let mut env = env_with(ObjectSpec::default_box(), c);
        env.reset(3);
        env
    };
    let n = crate::synergy::default_model().n_components();
    let grip = |g: f32| {
        let mut cont = vec![0.0; n + 3];
        cont[n + 2] = g;
        Action { cont, lift: false }
    };
    let (mut ramped, mut plain, mut at_once) = (ramped_by(0.125), ramped_by(0.0), ramped_by(0.0));
    for (k, g) in [0.125, 0.25].into_iter().enumerate() {
        ramped.step(&grip(1.0));
        plain.step(&grip(g));
        at_once.step(&grip(1.0));
        assert_eq!(ramped.sim.targets(), plain.sim.targets(), "step {}", k + 1);
        assert_ne!(
            ramped.sim.targets(),
            at_once.sim.targets(),
            "step {}",
            k + 1
        );
    }
}

#[test]
fn the_lift_holds_the_squeezed_targets() {
    // Two environments on the same scene and the same action before the lift: the
    // squeezing one lifts with `lift_targets` of the other's last targets (the plain
    // one lifts with its targets unchanged), and the squeeze holds the box harder.
    let with = |squeeze: f64| {
        let mut c = EnvConfig::default();
        c.action.lift_squeeze = squeeze;
        let mut env = env_with(ObjectSpec::default_box(), c);
        env.reset(3);
        let n = crate::synergy::default_model().n_components();
        env.step(&Action {
            cont: vec![0.5; n + 2],
            lift: false,
        });
        env
    };
    let (mut plain, mut squeezed) = (with(0.0), with(0.5));
    let before = plain.sim.targets();
    assert_eq!(squeezed.sim.targets(), before);
    let lift = Action {
        cont: Vec::new(),
        lift: true,
    };
    plain.step(&lift);
    squeezed.step(&lift);
    assert_eq!(plain.sim.targets(), before);
    let want = lift_targets(
        &squeezed.cfg.action,
        &before,
        &squeezed.closed,
        &squeezed.finger_limits,
    );
    // The simulator couples J1/J2 and clamps; the squeezed targets are already
    // feasible up to the coupling's averaging.
    for (k, (got, want)) in squeezed.sim.targets().iter().zip(want).enumerate() {
        assert!((got - want).abs() < 1e-12, "joint {k}: {got} vs {want}");
    }
    assert_ne!(squeezed.sim.targets(), before);
    let (p, s) = (plain.last.clone().unwrap(), squeezed.last.clone().unwrap());
    assert!(p.lifted && s.lifted);
    assert!(
        s.grip_effort > p.grip_effort,
        "{} vs {}",
        s.grip_effort,
        p.grip_effort
    );
}

#[test]
fn training_drops_the_grip_ramp_only_where_asked() {
    let mut c = EnvConfig::default();
    c.action.grip_scale = 0.25;
    c.action.grip_ramp = 0.15;
    c.action.grip_delay = 1;
    assert_eq!(c.for_training(), c);
    c.action.grip_ramp_in_training = false;
    let t = c.for_training();
    assert_eq!((t.action.grip_ramp, t.action.grip_delay), (0.0, 0));
    assert_eq!(t.action.grip_scale, 0.25);
    let mut back = t.clone();
    back.action.grip_ramp = 0.15;
    back.action.grip_delay = 1;
    assert_eq!(back, c);
    assert!(c.validate().is_ok() && t.validate().is_ok());
    // The squeeze at the lift has its own switch.
    c.action.lift_squeeze = 0.25;
    assert_eq!(c.for_training().action.lift_squeeze, 0.25);
    c.action.lift_squeeze_in_training = false;
    let t = c.for_training();
    assert_eq!(t.action.lift_squeeze, 0.0);
    assert_eq!((t.action.grip_ramp, t.action.grip_delay), (0.0, 0));
}

#[test]
fn each_phase_counts_its_own_physics_steps() {
    let robot = Robot::builtin(Side::Left);
    let objects = vec![("box".to_string(), ObjectSpec::default_box())];
    let cfg = SimConfig::default();
    let per_control = cfg.steps_per_control() as u64;
    let mut env = GraspEnv::new(
        &robot,
        objects,
        crate::synergy::default_model(),
        cfg,
        EnvConfig::default(),
    )
    .expect("env");
    env.reset(1);
    let closing = env.phases().closing.physics_steps;
    assert!(closing > 0);
    assert_eq!(closing, env.sim.physics_steps());
    let n = env.action_spec().continuous;
    for lift in [false, false, true] {
        env.step(&Action {
            cont: vec![0.0; n],
            lift,
        });
    }
    let p = *env.phases();
    assert_eq!(p.policy.physics_steps, 2 * per_control);
    assert!(p.lift.physics_steps > 0);
    assert_eq!(p.reset.physics_steps, 0);
    assert_eq!(p.total().physics_steps, env.sim.physics_steps());
    assert!(p.phases().iter().all(|(_, ph)| ph.wall_s > 0.0), "{p:?}");
    // A baseline: its closing and settle, then the lift.
    let before = p;
    env.run_baseline(false, 2).expect("baseline");
    let b = env.phases().since(&before);
    assert_eq!(b.policy.physics_steps, 0);
    assert_eq!(
        b.closing.physics_steps + b.lift.physics_steps,
        env.sim.physics_steps()
    );
}

/// A planner that always returns `plan`.
struct Fixed(Option<PlannedGrasp>);

impl PregraspPlanner for Fixed {
    fn plan(
        &mut self,
        _sim: &HandSim,
        _seed: u64,
        _avoid: &[PlannedGrasp],
    ) -> Option<PlannedGrasp> {
        self.0
    }
}

#[test]
fn a_pregrasp_plan_places_the_hand_and_no_plan_keeps_the_default() {
    // The default placement puts the grasp point on the box's axis at yaw 0; a plan
    // 3 cm along x and 5 cm higher at the same yaw moves the palm by exactly that;
    // a NaN plan or none leaves the default placement.
    let env = |planner: Option<Fixed>| match planner {
        Some(p) => box_env().with_pregrasp(Box::new(p)),
        None => box_env(),
    };
    let palm = |e: &mut GraspEnv| {
        e.reset_scene(3).expect("scene");
        e.sim.critic_geometry().expect("geometry").palm
    };
    let mut plain = env(None);
    let p0 = palm(&mut plain);
    let scene = Scene::top_down(
        &ObjectSpec::default_box(),
        plain.path.start(),
        plain.cfg.grasp_depth,
        0.0,
    );
    let g = scene.grasp_point;
    // 5 cm higher as well, clear of the box (no raise for clearance).
    let moved = Fixed(Some(PlannedGrasp {
        grasp_point: [g[0] + 0.03, g[1], g[2] + 0.05],
        hand_yaw: 0.0,
    }));
    let p1 = palm(&mut env(Some(moved)));
    let d = p1.translation.vector - p0.translation.vector;
    assert!(
        (d - nalgebra::Vector3::new(0.03, 0.0, 0.05)).norm() < 1e-5,
        "{d}"
    );
    assert!(p1.rotation.angle_to(&p0.rotation) < 1e-5);
    for none in [
        Fixed(None),
        Fixed(Some(PlannedGrasp {
            grasp_point: [f64::NAN, 0.0, 0.1],
            hand_yaw: 0.0,
        })),
    ] {
        let p = palm(&mut env(Some(none)));
        assert!((p.translation.vector - p0.translation.vector).norm() < 1e-9);
    }
}

#[test]
fn placement_moves_the_hand_by_its_draw_and_keeps_the_object_pose() {
    // [env.placement] with an offset, a yaw and no height change: the palm moves by
    // exactly the drawn horizontal shift and turns by the drawn yaw about z, and the
    // object starts where it does without placement settings (the placement draws
    // from its own generator). With antipodal = 1 the env's own planner places the
    // hand (the default box is 6.5 cm wide: a plan exists and moves the palm).
    let env_with = |placement: PlacementConfig| {
        GraspEnv::new(
            &Robot::builtin(Side::Left),
            vec![("box".to_string(), ObjectSpec::default_box())],
            crate::synergy::default_model(),
            SimConfig::default(),
            EnvConfig {
                placement,
                ..EnvConfig::default()
            },
        )
        .expect("env")
    };
    let start = |e: &mut GraspEnv, seed| {
        e.reset_scene(seed).expect("scene");
        (
            e.sim.critic_geometry().expect("geometry").palm,
            e.sim.object_pose_raw(),
        )
    };
    let shifted = PlacementConfig {
        yaw: 0.3,
        offset: 0.02,
        ..PlacementConfig::default()
    };
    for seed in [3, 11] {
        let (p0, o0) = start(&mut box_env(), seed);
        let (p1, o1) = start(&mut env_with(shifted), seed);
        assert_eq!(o0, o1, "the object's start pose");
        let d = shifted.draw(seed);
        assert!(!d.antipodal);
        let expected_turn =
            nalgebra::UnitQuaternion::from_axis_angle(&nalgebra::Vector3::z_axis(), d.yaw);
        let turn = p1.rotation * p0.rotation.inverse();
        assert!(turn.angle_to(&expected_turn) < 1e-5, "seed {seed}");
        // The palm turns about the grasp point: compare grasp points, i.e. undo the
        // turn about the default grasp point before comparing positions.
        let g = Scene::top_down(
            &ObjectSpec::default_box(),
            box_env().path.start(),
            EnvConfig::default().grasp_depth,
            0.0,
        )
        .grasp_point;
        let g = nalgebra::Vector3::new(g[0], g[1], g[2]);
        let shift = nalgebra::Vector3::from(d.shift);
        let unturned = turn.inverse() * (p1.translation.vector - g - shift) + g;
        assert!(
            (unturned - p0.translation.vector).norm() < 1e-5,
            "seed {seed}: {unturned} against {}",
            p0.translation.vector
        );
    }
    let planned = PlacementConfig {
        antipodal: 1.0,
        ..PlacementConfig::default()
    };
    let (p0, _) = start(&mut box_env(), 5);
    let (p1, _) = start(&mut env_with(planned), 5);
    assert!((p1.translation.vector - p0.translation.vector).norm() > 1e-4);
    // An evaluation's env (placement turned off) is the default.
    let (p2, _) = start(&mut env_with(PlacementConfig::default()), 5);
    assert!((p2.translation.vector - p0.translation.vector).norm() < 1e-9);
}

#[test]
fn m3g_sees_the_surface_the_critic_its_state_and_a_push_costs_reward() {
    // M3G with the critic's state and the displacement penalty: the observation is
    // the stacked frames (M3's values and 18 surface values), then 46 critic values;
    // after stage 1 a fingertip
    // touches the box, so some surface vector is within 1 cm, and every vector is
    // within 30 cm.
    let robot = Robot::builtin(Side::Left);
    let objects = vec![("box".to_string(), ObjectSpec::default_box())];
    let cfg = EnvConfig {
        modality: Modality::M3G,
        critic_state: true,
        reward: RewardConfig {
            displacement_weight: 1000.0,
        },
        ..EnvConfig::default()
    };
    let syn = crate::synergy::default_model();
    let mut env = GraspEnv::new(
        &robot,
        objects.clone(),
        syn.clone(),
        SimConfig::default(),
        cfg,
    )
    .expect("env");
    let fl = env.layout().frame_len();
    let pa = env.action_spec().continuous;
    assert_eq!(fl, pa + 5 + 20 + N_SURFACE + 24);
    assert_eq!(env.obs_dim(), 3 * fl + super::super::obs::CRITIC_STATE_LEN);
    let o = env.reset(1);
    assert_eq!(o.len(), env.obs_dim());
    let frame = &o[2 * fl..3 * fl];
    let surface = &frame[pa + 5 + 20..pa + 5 + 20 + N_SURFACE];
    let lens: Vec<f32> = surface
        .chunks(3)
        .map(|v| v.iter().map(|x| x * x).sum::<f32>().sqrt())
        .collect();
    assert!(lens.iter().any(|&l| l < 0.01), "{lens:?}");
    assert!(lens.iter().all(|&l| l < 0.3), "{lens:?}");
    // The critic's copy of the vectors equals the newest frame's.
    let critic = &o[3 * fl..];
    assert_eq!(&critic[15..33], surface);
    // A step that moves the box pays for it: the same step costs more with the
    // penalty than without (identical scenes and actions).
    let n = env.action_spec().continuous;
    let push = Action {
        cont: vec![1.0; n],
        lift: false,
    };
    let r_pen = env.step(&push).reward;
    let mut plain = GraspEnv::new(
        &robot,
        objects,
        syn,
        SimConfig::default(),
        EnvConfig {
            modality: Modality::M3G,
            ..EnvConfig::default()
        },
    )
    .expect("env");
    plain.reset(1);
    let r_plain = plain.step(&push).reward;
    assert!(r_pen < r_plain, "{r_pen} against {r_plain}");
}

#[test]
fn the_object_curriculum_draws_the_failing_object_more_often() {
    let robot = Robot::builtin(Side::Left);
    let objects = vec![
        ("box".to_string(), ObjectSpec::default_box()),
        ("cylinder".to_string(), ObjectSpec::default_cylinder()),
    ];
    let mut cfg = EnvConfig::default();
    cfg.object_curriculum.enabled = true;
    let model = crate::synergy::default_model();
    let mut env = GraspEnv::new(
        &robot,
        objects.clone(),
        model.clone(),
        SimConfig::default(),
        cfg.clone(),
    )
    .expect("env");
    let c = env
        .object_curriculum
        .as_mut()
        .expect("enabled for two objects");
    for _ in 0..8 {
        c.record(0, true);
        c.record(1, false);
    }
    // Weights 0.1 + 1/10 and 0.1 + 9/10: the cylinder in 5 of 6 draws.
    let n = 600;
    let mut cylinder = 0;
    for seed in 0..n {
        env.reset_scene(seed).unwrap();
        cylinder += usize::from(env.episode_object == 1);
    }
    let share = cylinder as f64 / n as f64;
    assert!((share - 1.0 / 1.2).abs() < 0.05, "{share}");
    // One object: nothing to choose, the draw is the paper's.
    cfg.object_curriculum.enabled = true;
    let one = GraspEnv::new(
        &robot,
        objects[..1].to_vec(),
        model,
        SimConfig::default(),
        cfg.clone(),
    )
    .expect("env");
    assert!(one.object_curriculum.is_none());
    cfg.object_curriculum.window = 0;
    assert!(cfg
        .validate()
        .unwrap_err()
        .to_string()
        .contains("object_curriculum.window"));
}

#[test]
fn a_refused_scene_ends_as_a_reported_failure() {
    let mut env = box_env();
    // One ordinary episode leaves a world behind.
    env.reset(1);
    let n = env.action_spec().continuous;
    let step = env.step(&Action {
        cont: vec![0.0; n],
        lift: true,
    });
    assert!(step.terminated);
    // An object the simulator refuses (bypassing the set's validation, as a corrupt
    // object would): the next episode must not run on the old world.
    env.objects[0].1.mass = f64::NAN;
    env.current_object = None;
    env.reset(2);
    let step = env.step(&Action {
        cont: vec![0.0; n],
        lift: true,
    });
    assert!(
        step.terminated && step.info.physics_failure,
        "{:?}",
        step.info
    );
    let s = env.last_episode().expect("summary");
    assert!(!s.success && s.physics_failure);
    let kind = s.failure.as_ref().map(|f| f.failure.kind());
    assert_eq!(kind, Some("refused_scene"), "{s:?}");
    assert_eq!(s.steps, 0);
    // A valid object afterwards runs again.
    env.objects[0].1 = ObjectSpec::default_box();
    env.reset(3);
    let step = env.step(&Action {
        cont: vec![0.0; n],
        lift: true,
    });
    assert!(!step.info.physics_failure);
}
