//! Episode recordings: every episode of an evaluation or rollout written as a JSON file
//! and as a self-contained HTML page that replays it in 3D (three.js r149, embedded, so
//! the page opens offline from `file://`).
//!
//! A recording holds two streams:
//! - `frames`: every [`RecordOptions::every`] physics steps (4 by default, 60 frames per
//!   simulated second at 240 Hz), the world pose of every hand collider, the object pose,
//!   the tactile bits, the 20 torque levels, the lift height and the stage (`closing`
//!   for stage 1 and the baselines' scripted closing, `control` for stage 2, `lift`);
//! - `control`: one record per control step: the action (continuous part and lift bit),
//!   the reward, the sensors, joint angles and targets after the step; record 0 is the
//!   state at the end of stage 1 (no action).
//!
//! The geometry (`hand_geometry`, `object_geometry`) comes from the simulator's colliders
//! ([`crate::sim::world::record`]), so the page shows exactly what was simulated.

use crate::env::api::Env;
use crate::env::grasp::{Agent, EpisodeSummary, GraspEnv};
use crate::sim::world::record::{PlacedShape, ShapeGeometry, SimFrame};
use crate::sim::SimError;
use crate::util::fsx::write_atomic;
use serde::Serialize;
use std::path::{Path, PathBuf};

/// The three.js build embedded into every page (MIT licence in `assets/viewer`).
const THREE_JS: &str = include_str!("../../assets/viewer/three.min.js");
/// The page template.
const TEMPLATE: &str = include_str!("../../assets/viewer/viewer.html");
/// The replay script.
const VIEWER_JS: &str = include_str!("../../assets/viewer/viewer.js");

/// Format version of the recording JSON.
pub const RECORDING_VERSION: u32 = 1;

/// Where and how finely episodes are recorded.
#[derive(Debug, Clone, PartialEq)]
pub struct RecordOptions {
    /// Output folder (created when missing).
    pub dir: PathBuf,
    /// Physics steps between two frames (at least 1).
    pub every: u64,
    /// Write only the episodes that ended in a physics failure.
    pub only_failures: bool,
    /// The agent's name in the recordings and their file names (`grasp eval --labels`);
    /// its label when `None`.
    pub name: Option<String>,
}

impl RecordOptions {
    /// Recording into `dir` every 4 physics steps.
    pub fn new(dir: impl Into<PathBuf>) -> Self {
        RecordOptions {
            dir: dir.into(),
            every: 4,
            only_failures: false,
            name: None,
        }
    }
}

/// The file in a folder that says it holds recordings.
pub const INDEX_FILE: &str = "index.html";

/// A frame with the stage it belongs to.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RecordedFrame {
    /// `closing`, `control` or `lift`.
    pub stage: &'static str,
    /// The sampled state.
    #[serde(flatten)]
    pub frame: SimFrame,
}

/// The state after one control step.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ControlRecord {
    /// Control step (0: the end of stage 1, before any action).
    pub step: usize,
    /// Simulated time after the step (s).
    pub t: f64,
    /// The continuous action (synergy increments, then wrist increments), `None` at step 0.
    pub action: Option<Vec<f32>>,
    /// The lift bit rho.
    pub lift: bool,
    /// The step's reward (eq. 4).
    pub reward: f32,
    /// Binary fingertip contacts (FF, MF, RF, LF, TH).
    pub tactile: [u8; 5],
    /// Torque levels of the 20 actuators.
    pub torque_level: [u8; 20],
    /// The 24 joint angles (rad).
    pub q: Vec<f32>,
    /// The 24 joint targets (rad).
    pub targets: Vec<f32>,
}

/// One recorded episode.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct EpisodeRecording {
    /// [`RECORDING_VERSION`].
    pub version: u32,
    /// Agent label.
    pub agent: String,
    /// Object name.
    pub object: String,
    /// Scene seed.
    pub seed: u64,
    /// The episode's outcome.
    pub summary: EpisodeSummary,
    /// Physics step (s).
    pub dt: f64,
    /// Physics steps between frames.
    pub frame_every: u64,
    /// Physics steps of stage 1 (the scripted closing).
    pub closing_steps: u64,
    /// Every hand collider's shape in its own frame (order of the frames' `hand`).
    pub hand_geometry: Vec<ShapeGeometry>,
    /// For every hand collider, the tactile finger (0..5) it belongs to, if any.
    pub hand_tactile_fingers: Vec<Option<u8>>,
    /// The object's pieces in its body frame.
    pub object_geometry: Vec<PlacedShape>,
    /// Frames every `frame_every` physics steps.
    pub frames: Vec<RecordedFrame>,
    /// One record per control step.
    pub control: Vec<ControlRecord>,
}

/// Errors of writing recordings.
#[derive(Debug, thiserror::Error)]
pub enum RecordError {
    /// A file could not be written.
    #[error(transparent)]
    Write(#[from] crate::util::fsx::WriteError),
    /// The folder could not be created.
    #[error("creating recording folder {path}: {source}")]
    Dir {
        /// The folder.
        path: PathBuf,
        /// The cause.
        source: std::io::Error,
    },
    /// The recording could not be serialised.
    #[error("serialising recording: {0}")]
    Json(#[from] serde_json::Error),
}

fn to_f32(v: &[f64]) -> Vec<f32> {
    v.iter().map(|&x| x as f32).collect()
}

fn control_record(
    env: &GraspEnv,
    step: usize,
    action: Option<&crate::env::api::Action>,
    reward: f32,
) -> ControlRecord {
    let sim = env.sim();
    let s = sim.sensors();
    ControlRecord {
        step,
        t: sim.time(),
        action: action.map(|a| a.cont.clone()),
        lift: action.is_some_and(|a| a.lift),
        reward,
        tactile: s.tactile,
        torque_level: s.torque_level,
        q: to_f32(&s.q),
        targets: to_f32(&sim.targets()),
    }
}

/// Labels frames: `lift` while the arm lifts, `closing` up to `closing_steps`, else
/// `control`.
fn stage_frames(frames: Vec<SimFrame>, closing_steps: u64) -> Vec<RecordedFrame> {
    frames
        .into_iter()
        .map(|frame| RecordedFrame {
            stage: if frame.lifting {
                "lift"
            } else if frame.physics_step <= closing_steps {
                "closing"
            } else {
                "control"
            },
            frame,
        })
        .collect()
}

fn assemble(
    env: &mut GraspEnv,
    agent: &str,
    seed: u64,
    every: u64,
    closing_steps: Option<u64>,
    summary: EpisodeSummary,
    control: Vec<ControlRecord>,
) -> EpisodeRecording {
    let frames = env.sim_mut().take_recording();
    // Without a stage 2 (baselines) the closing lasts until the lift.
    let closing_steps = closing_steps.unwrap_or_else(|| {
        frames
            .iter()
            .filter(|f| !f.lifting)
            .map(|f| f.physics_step)
            .max()
            .unwrap_or(0)
    });
    let sim = env.sim();
    EpisodeRecording {
        version: RECORDING_VERSION,
        agent: agent.to_string(),
        object: summary.object.clone(),
        seed,
        dt: sim.config().dt,
        frame_every: every,
        closing_steps,
        hand_geometry: sim.hand_geometry(),
        hand_tactile_fingers: sim.hand_tactile_fingers(),
        object_geometry: sim.object_geometry(),
        frames: stage_frames(frames, closing_steps),
        control,
        summary,
    }
}

/// Runs one episode of `agent` on the scene of `seed` (exactly as
/// [`crate::env::grasp::run_episode`]) and records it under the agent name `label`.
pub fn record_agent_episode(
    env: &mut GraspEnv,
    agent: &mut dyn Agent,
    label: &str,
    seed: u64,
    every: u64,
) -> EpisodeRecording {
    agent.reset();
    env.sim_mut().start_recording(every);
    let mut obs = env.reset(seed);
    let closing_steps = env.sim().physics_steps();
    let mut control = vec![control_record(env, 0, None, 0.0)];
    loop {
        let a = agent.act(&obs);
        let s = env.step(&a);
        control.push(control_record(env, control.len(), Some(&a), s.reward));
        obs = s.obs;
        if s.terminated || s.truncated {
            break;
        }
    }
    let summary = env
        .last_episode()
        .cloned()
        .unwrap_or_else(|| unreachable!("a finished episode has a summary"));
    assemble(
        env,
        label,
        seed,
        every,
        Some(closing_steps),
        summary,
        control,
    )
}

/// Runs scripted baseline 1 (`stop_on_touch = false`) or 2 on the scene of `seed` (as
/// [`GraspEnv::run_baseline`]) and records it. Baselines have no control steps; the
/// closing lasts until the lift.
pub fn record_baseline_episode(
    env: &mut GraspEnv,
    stop_on_touch: bool,
    label: &str,
    seed: u64,
    every: u64,
) -> Result<EpisodeRecording, SimError> {
    env.sim_mut().start_recording(every);
    let summary = match env.run_baseline(stop_on_touch, seed) {
        Ok(s) => s,
        Err(e) => {
            env.sim_mut().take_recording();
            return Err(e);
        }
    };
    Ok(assemble(env, label, seed, every, None, summary, Vec::new()))
}

/// `s` reduced to file-name-safe characters (letters, digits, `-`, `_`, `.`; others
/// become `_`), at most 80 characters: a longer name keeps its first 71 and ends in `-`
/// and 8 hex digits of a hash of the whole name, so two long names sharing their first 80
/// characters are still told apart.
pub fn slug(s: &str) -> String {
    let t: Vec<char> = s
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || matches!(c, '-' | '_' | '.') {
                c
            } else {
                '_'
            }
        })
        .collect();
    let t: String = if t.len() > 80 {
        let mut h = crate::util::hash::Fnv128::new();
        h.write(s.as_bytes());
        let head: String = t[..71].iter().collect();
        format!("{head}-{:08x}", h.finish() as u32)
    } else {
        t.into_iter().collect()
    };
    let t = t.trim_matches('.').to_string();
    if t.is_empty() {
        "episode".into()
    } else {
        t
    }
}

/// JSON safe to embed in a `<script>` element: `<` is escaped as `\u003c` (valid JSON
/// inside strings, and it never occurs outside them in serde_json's output).
fn script_safe(json: &str) -> String {
    json.replace('<', "\\u003c")
}

fn html_escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// An episode's outcome in words: `success`, `failure`, or the physics failure with its
/// step (e.g. `physics failure at step 412: 23.1 mm deep contact with rfdistal`).
pub fn outcome_text(s: &EpisodeSummary) -> String {
    match (&s.failure, s.success) {
        (Some(f), _) => format!("physics failure at step {}: {}", f.step, f.failure),
        (None, _) if s.physics_failure => "physics failure".into(),
        (None, true) => "success".into(),
        (None, false) => "failure".into(),
    }
}

/// The self-contained replay page of `rec`.
pub fn episode_html(rec: &EpisodeRecording) -> Result<String, serde_json::Error> {
    let json = script_safe(&serde_json::to_string(rec)?);
    let title = html_escape(&format!(
        "{} on {} (seed {}): {}",
        rec.agent,
        rec.object,
        rec.seed,
        outcome_text(&rec.summary)
    ));
    // Placeholders are replaced in an order where no inserted text is scanned again.
    let (head, rest) = TEMPLATE.split_once("__DATA__").unwrap_or((TEMPLATE, ""));
    let (mid, tail) = rest.split_once("__THREE__").unwrap_or((rest, ""));
    let (mid2, tail2) = tail.split_once("__VIEWER__").unwrap_or((tail, ""));
    let mut out = String::with_capacity(THREE_JS.len() + json.len() + TEMPLATE.len() + 16_384);
    out.push_str(&head.replace("__TITLE__", &title));
    out.push_str(&json);
    out.push_str(mid);
    out.push_str(&THREE_JS.replace("</script", "<\\/script"));
    out.push_str(mid2);
    out.push_str(VIEWER_JS);
    out.push_str(tail2);
    Ok(out)
}

/// One written recording, for the index page.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RecordingEntry {
    /// Agent label.
    pub agent: String,
    /// Object name.
    pub object: String,
    /// Trial (or episode) index.
    pub trial: usize,
    /// The trial's attempt (1 = its first; later ones with `grasp eval --attempts`).
    pub attempt: usize,
    /// Scene seed.
    pub seed: u64,
    /// Outcome.
    pub success: bool,
    /// The outcome in words, a physics failure's kind, body pair, depth and step included.
    pub outcome: String,
    /// Stage-2 control steps.
    pub steps: usize,
    /// The JSON file's name inside the folder.
    pub json: String,
    /// The HTML page's name inside the folder.
    pub html: String,
}

/// The part of a file name that names agent `agent` (a label as [`super::AgentSpec::label`]
/// gives it): a checkpoint path is shortened to its folder's name, or `<run>_<folder>` for
/// `<run>/checkpoints/<folder>`, so `/home/me/runs/quick/checkpoints/best` gives
/// `quick_best`; ` (sampled)` becomes `_sampled`; other labels are kept. File-safe.
pub fn agent_file_name(agent: &str) -> String {
    use std::path::Component;
    let (base, sampled) = match agent.strip_suffix(" (sampled)") {
        Some(b) => (b, true),
        None => (agent, false),
    };
    let names: Vec<&str> = Path::new(base)
        .components()
        .filter_map(|c| match c {
            Component::Normal(s) => s.to_str(),
            _ => None,
        })
        .collect();
    let short = match names.as_slice() {
        [.., run, "checkpoints", folder] => format!("{run}_{folder}"),
        [.., last] => last.to_string(),
        [] => base.to_string(),
    };
    let short = slug(&short);
    if sampled {
        format!("{short}_sampled")
    } else {
        short
    }
}

/// Checks, before any episode, that the recordings of every agent (`agents`: the names
/// the recordings take) on every object get their own files: the file stem
/// `<agent>_<object>` of [`write_recording`] can be shared by two pairs (agent `P_box` on
/// `sugar`, agent `P` on `box_sugar`), and one would overwrite the other. `Err` names both
/// pairs and the shared stem.
pub fn check_file_names(agents: &[String], objects: &[String]) -> Result<(), String> {
    let mut seen: std::collections::HashMap<String, (&str, &str)> = Default::default();
    for a in agents {
        for o in objects {
            let stem = format!("{}_{}", agent_file_name(a), slug(o));
            if let Some((a0, o0)) = seen.insert(stem.clone(), (a, o)) {
                if (a0, o0) != (a.as_str(), o.as_str()) {
                    return Err(format!(
                        "agent '{a0}' on object '{o0}' and agent '{a}' on object '{o}' would \
                         both be recorded as '{stem}_<trial>', one overwriting the other"
                    ));
                }
            }
        }
    }
    Ok(())
}

/// Writes `rec` as `<stem>.json` and `<stem>.html` into `dir` (atomically, the folder
/// created when missing), where the stem is `<agent>_<object>_<trial>` made file-safe,
/// the agent as [`agent_file_name`] gives it, and `_attempt<k>` added for a trial's
/// attempt `k` after its first (`attempt` counts from 0).
pub fn write_recording(
    dir: &Path,
    rec: &EpisodeRecording,
    trial: usize,
    attempt: usize,
) -> Result<RecordingEntry, RecordError> {
    crate::util::fsx::create_dirs(dir).map_err(|source| RecordError::Dir {
        path: dir.to_path_buf(),
        source,
    })?;
    let mut stem = format!(
        "{}_{}_{:03}",
        agent_file_name(&rec.agent),
        slug(&rec.object),
        trial
    );
    if attempt > 0 {
        stem.push_str(&format!("_attempt{}", attempt + 1));
    }
    let json = format!("{stem}.json");
    let html = format!("{stem}.html");
    write_atomic(&dir.join(&json), serde_json::to_string(rec)?.as_bytes())?;
    write_atomic(&dir.join(&html), episode_html(rec)?.as_bytes())?;
    Ok(RecordingEntry {
        agent: rec.agent.clone(),
        object: rec.object.clone(),
        trial,
        attempt: attempt + 1,
        seed: rec.seed,
        success: rec.summary.success,
        outcome: outcome_text(&rec.summary),
        steps: rec.summary.steps,
        json,
        html,
    })
}

/// An index page linking every recorded episode.
pub fn index_html(entries: &[RecordingEntry]) -> String {
    let mut s = String::from(
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>grasp \
         recordings</title><style>body{font:14px system-ui,sans-serif;margin:20px}\
         td,th{padding:2px 10px;text-align:left}.ok{color:#2ca02c}.no{color:#d62728}\
         </style></head><body><h1>Recorded episodes</h1><table><tr><th>agent</th>\
         <th>object</th><th>trial</th><th>seed</th><th>outcome</th><th>steps</th>\
         <th>data</th></tr>\n",
    );
    for e in entries {
        s.push_str(&format!(
            "<tr><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td class=\"{}\">{}</td>\
             <td>{}</td><td><a href=\"{}\">replay</a> <a href=\"{}\">json</a></td></tr>\n",
            html_escape(&e.agent),
            html_escape(&e.object),
            if e.attempt > 1 {
                format!("{} (attempt {})", e.trial, e.attempt)
            } else {
                e.trial.to_string()
            },
            e.seed,
            if e.success { "ok" } else { "no" },
            html_escape(&e.outcome),
            e.steps,
            html_escape(&e.html),
            html_escape(&e.json)
        ));
    }
    s.push_str("</table></body></html>\n");
    s
}

/// A recording folder once its index is written: the index's path, the episodes it
/// links, and the failure to tell when some episodes could not be written (the
/// evaluation's results are complete all the same).
#[derive(Debug, Clone, PartialEq)]
pub struct Finished {
    /// `dir/index.html`.
    pub index: PathBuf,
    /// Episodes linked from the index.
    pub episodes: usize,
    /// `Some("--record DIR: N episodes could not be recorded (...): first error")` when
    /// any episode's files could not be written.
    pub lost: Option<String>,
}

/// Writes the index of `entries` into `dir` and says which of the episodes were lost
/// (`errors`, one message per episode that could not be written).
pub fn finish(
    dir: &Path,
    entries: &[RecordingEntry],
    errors: &[String],
) -> Result<Finished, RecordError> {
    let index = write_index(dir, entries)?;
    let lost = errors.first().map(|first| {
        format!(
            "--record {}: {} episodes could not be recorded (the results above are \
             complete): {first}",
            dir.display(),
            errors.len()
        )
    });
    Ok(Finished {
        index,
        episodes: entries.len(),
        lost,
    })
}

/// Writes `index.html` for `entries` into `dir` (atomically).
pub fn write_index(dir: &Path, entries: &[RecordingEntry]) -> Result<PathBuf, RecordError> {
    let p = dir.join(INDEX_FILE);
    write_atomic(&p, index_html(entries).as_bytes())?;
    Ok(p)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::env::grasp::{EnvConfig, RandomAgent};
    use crate::robot::{Robot, Side};
    use crate::sim::{ObjectSpec, SimConfig};

    /// Every frame has a pose per hand collider and time runs forward.
    fn frames_cover_episode(rec: &EpisodeRecording) -> bool {
        let hand = rec.hand_geometry.len();
        !rec.frames.is_empty()
            && rec.frames.iter().all(|f| f.frame.hand.len() == hand)
            && rec.frames.windows(2).all(|w| w[0].frame.t < w[1].frame.t)
    }

    fn env() -> GraspEnv {
        let robot = Robot::builtin(Side::Left);
        let model = crate::synergy::default_model().truncated(5).unwrap();
        GraspEnv::new(
            &robot,
            vec![("box".into(), ObjectSpec::default_box())],
            model,
            SimConfig::default(),
            EnvConfig::default(),
        )
        .unwrap()
    }

    #[test]
    fn slug_and_escapes() {
        assert_eq!(slug("Baseline 2_box/x_001"), "Baseline_2_box_x_001");
        assert_eq!(slug("..."), "episode");
        assert_eq!(agent_file_name("Baseline 2"), "Baseline_2");
        assert_eq!(
            agent_file_name("/home/me/runs/quick/checkpoints/best"),
            "quick_best"
        );
        assert_eq!(
            agent_file_name("/opt/grasp/assets/policies/quick_gru_m3_pca5 (sampled)"),
            "quick_gru_m3_pca5_sampled"
        );
        assert_eq!(agent_file_name("runs/x/"), "x");
        assert_eq!(
            script_safe(r#"{"a":"</script>"}"#),
            r#"{"a":"\u003c/script>"}"#
        );
        assert_eq!(html_escape("a<b&\"c\">"), "a&lt;b&amp;&quot;c&quot;&gt;");
    }

    #[test]
    fn baseline_recording_matches_the_unrecorded_episode() {
        // Each from a fresh environment: the grip through the lift is a continuous
        // reading, and rapier's caches left by an earlier episode in the same world
        // change its rounding.
        let plain = env().run_baseline(true, 7).unwrap();
        let mut e = env();
        let rec = record_baseline_episode(&mut e, true, "Baseline 2", 7, 4).unwrap();
        assert_eq!(rec.summary, plain);
        assert!(frames_cover_episode(&rec));
        assert!(!e.sim().is_recording());
        // The closing then the lift: (ramp + hold) / dt physics steps, a frame every 4.
        assert_eq!(rec.frames[0].stage, "closing");
        let cfg = e.sim().config();
        let lift_steps = ((cfg.lift.ramp_time / cfg.dt).round().max(1.0)
            + (cfg.lift.hold_time / cfg.dt).round()) as i64;
        let lift = rec.frames.iter().filter(|f| f.stage == "lift").count() as i64;
        assert!(
            (lift - lift_steps / 4).abs() <= 1,
            "{lift} vs {lift_steps} / 4"
        );
        assert!(rec.frames.iter().all(|f| f.stage != "control"));
        assert!(rec.control.is_empty());
        // The forces: before the hand moves, nothing touches the object but the table,
        // which carries its weight; at the lift's end of a held object the hand carries
        // it, the table nothing, and the distal phalanges are part of the hand.
        let f0 = &rec.frames[0].frame;
        assert_eq!(f0.hand_force, 0.0);
        assert_eq!(f0.tip_force, [0.0; 5]);
        let weight = ObjectSpec::default_box().mass * 9.81;
        assert!(
            (f0.table_force as f64 - weight).abs() < 0.1 * weight,
            "{} vs {weight}",
            f0.table_force
        );
        if rec.summary.success {
            let last = &rec.frames.last().unwrap().frame;
            assert_eq!(last.table_force, 0.0);
            assert!(last.hand_force as f64 > 0.5 * weight, "{}", last.hand_force);
            let tips: f32 = last.tip_force.iter().sum();
            assert!(
                tips <= last.hand_force + 1e-3,
                "{tips} > {}",
                last.hand_force
            );
        }
    }

    #[test]
    fn agent_recording_has_all_stages_and_control_records() {
        let n = env().action_spec().continuous;
        let plain =
            crate::env::grasp::run_episode(&mut env(), &mut RandomAgent::new(n, 0.3, 3), 11);
        let mut e = env();
        let rec = record_agent_episode(&mut e, &mut RandomAgent::new(n, 0.3, 3), "random", 11, 4);
        assert_eq!(rec.summary, plain);
        assert_eq!(rec.control.len(), plain.steps + 1);
        assert_eq!(rec.control[0].action, None);
        assert!(rec.control[1..]
            .iter()
            .all(|c| c.action.as_ref().is_some_and(|a| a.len() == n)));
        assert!(frames_cover_episode(&rec));
        assert_eq!(rec.frames[0].stage, "closing");
        if plain.steps > 1 {
            assert!(rec.frames.iter().any(|f| f.stage == "control"));
        }
        if plain.lifted {
            assert_eq!(rec.frames.last().map(|f| f.stage), Some("lift"));
        }
        let html = episode_html(&rec).unwrap();
        assert!(html.contains("Three.js Authors") && html.contains("WebGLRenderer"));
        assert!(!html.contains("__DATA__") && !html.contains("__VIEWER__"));
        // The data parses back from the page.
        let start = html.find("id=\"episode\">").unwrap() + "id=\"episode\">".len();
        let end = start + html[start..].find("</script>").unwrap();
        let v: serde_json::Value = serde_json::from_str(&html[start..end]).unwrap();
        assert_eq!(v["object"], "box");
        assert_eq!(v["frames"].as_array().unwrap().len(), rec.frames.len());
    }

    #[test]
    fn files_and_index_are_written() {
        let dir = tempfile::tempdir().unwrap();
        let mut e = env();
        let rec = record_baseline_episode(&mut e, false, "Baseline 1", 3, 8).unwrap();
        let entry = write_recording(dir.path(), &rec, 2, 0).unwrap();
        assert_eq!(entry.json, "Baseline_1_box_002.json");
        let v: serde_json::Value =
            serde_json::from_slice(&std::fs::read(dir.path().join(&entry.json)).unwrap()).unwrap();
        assert_eq!(v["version"], RECORDING_VERSION);
        assert_eq!(v["summary"]["success"], rec.summary.success);
        assert!(dir.path().join(&entry.html).is_file());
        let idx = write_index(dir.path(), &[entry]).unwrap();
        let text = std::fs::read_to_string(idx).unwrap();
        assert!(text.contains("Baseline_1_box_002.html"));
    }

    #[test]
    fn long_names_stay_apart_and_shared_stems_are_found() {
        let a = format!("{}{}", "o".repeat(100), "a".repeat(21));
        let b = format!("{}{}", "o".repeat(100), "b".repeat(21));
        let (sa, sb) = (slug(&a), slug(&b));
        assert_ne!(sa, sb);
        assert_eq!(sa.len(), 80);
        assert_eq!(slug("box_sugar"), "box_sugar");
        let names = |v: &[&str]| v.iter().map(|s| s.to_string()).collect::<Vec<_>>();
        let e =
            check_file_names(&names(&["P_box", "P"]), &names(&["box_sugar", "sugar"])).unwrap_err();
        assert!(
            e.contains("'P_box' on object 'sugar'") && e.contains("'P' on object 'box_sugar'"),
            "{e}"
        );
        check_file_names(&names(&["A", "B"]), &names(&["box_sugar", "sugar"])).unwrap();
        check_file_names(&names(&["P"]), &[a, b]).unwrap();
    }
}
