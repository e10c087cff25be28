//! `grasp eval`: per-object success rates of trained policies and baselines (Table I).

use anyhow::{bail, Context, Result};
use clap::Args;
use grasp::env::obs::Modality;
use grasp::eval::plot::{check_plot_path, write_per_object_plot};
use grasp::eval::rank::MAX_RANK_TOP;
use grasp::eval::record::RecordOptions;
use grasp::eval::request::{EvalEvent, EvalRequest};
use grasp::eval::{
    csv_table, markdown_table, paired_lines, paired_with_first, physics_line, read_results,
    text_table, unpaired_lines, AgentResult,
};
use grasp::util::fsx::{check_writable_file, write_atomic};
use grasp::util::signal;
use std::path::PathBuf;

use super::Global;

/// Evaluate agents per object on identical initial poses and print a Table-I-style table.
#[derive(Debug, Args)]
#[command(
    after_help = "Examples:\n  grasp eval --policy baseline1,baseline2 --objects unseen --trials 10 --markdown\n  grasp eval --policy runs/quick/checkpoints/best --policy baseline2 --objects train --csv table.csv\n  grasp eval --policy assets/policies/quick_gru_m3_pca5 --objects unseen --json\n  grasp eval --policy baseline2 --objects box_sugar --trials 2 --record rec/\n  grasp eval --policy assets/policies/quick_gru_m3_pca5,baseline1,baseline2 --objects unseen --trials 20 --plot unseen.svg\n  grasp eval --from-json eval.json --policy baseline1,baseline2 --labels B1,B2 --plot b.svg\n  grasp eval --from-json seed0.json,seed1.json,seed2.json --markdown\n\nCheckpoints are evaluated in the setup saved beside them (config.toml: modality,\ncomponents, history, action scales; synergy.json); --modality and --components apply to\nbaselines, and an error is raised when they contradict a checkpoint.\n\nWith several agents, the first is also compared with each other one trial by trial (every\nagent sees the same start poses): the counts of trials only one of them won and the exact\nMcNemar p-value. --json gives each trial's outcome per object.\n\n--plot draws the per-object success of every agent side by side (horizontal bars with Wilson\n95 % intervals, each agent's mean first, objects sorted by the first agent's margin over the\nbest other agent). --from-json reads the --json output of an earlier evaluation instead of\nrunning one, and prints, compares and plots it again; --policy then picks agents of the file\nby name (baseline1, baseline2 or the name in the file). Several files (e.g. --seed 0, 1 and 2 of
the same evaluation) are pooled into one evaluation of their trials: each agent's trials are
joined in the files' order, so agents stay paired trial by trial; their seeds, placement,
attempts and objects are checked."
)]
pub struct EvalArgs {
    /// Agents: baseline1, baseline2, or a checkpoint folder; repeat or separate by commas.
    /// With --from-json: the agents of the file to show (all when absent).
    #[arg(long, value_delimiter = ',', required_unless_present = "from_json")]
    pub policy: Vec<String>,
    /// Read the results of an earlier `grasp eval --json` from this file instead of
    /// evaluating: print, compare and plot them again. Several files (repeat or separate by
    /// commas), e.g. one per seed of scenes, are pooled: each agent's trials joined in the
    /// files' order (the same agents on the same objects, each seed once).
    #[arg(long, value_name = "FILE", value_delimiter = ',', conflicts_with_all = ["objects", "trials", "stochastic", "synergy", "components", "modality", "difficulty", "sim_config", "threads", "record", "pregrasp", "perturb", "attempts", "rank_top", "ranker"])]
    pub from_json: Vec<PathBuf>,
    /// Draw the per-object success of every agent (Wilson 95 % intervals, means) to this
    /// SVG file.
    #[arg(long, value_name = "FILE.svg")]
    pub plot: Option<PathBuf>,
    /// Title of the plot (default: the object set and seed, or the --from-json file); the
    /// number of objects and trials is added.
    #[arg(long, requires = "plot")]
    pub plot_title: Option<String>,
    /// Names of the agents in the outputs, in order, instead of their checkpoint paths
    /// (one per agent, separated by commas).
    #[arg(long, value_delimiter = ',')]
    pub labels: Vec<String>,
    /// Objects: train, unseen, all, validation (choose checkpoints on it), procedural, a folder of OBJ/STL, a manifest.toml, or names.
    #[arg(long, default_value = "unseen")]
    pub objects: String,
    /// Trials per object.
    #[arg(long, default_value_t = 10)]
    pub trials: usize,
    /// Checkpoints act with actions sampled from their distribution, as in training
    /// (seeded by --seed), instead of its mode. A policy whose lift probability stays
    /// below 0.5 never lifts with the mode: its episodes are truncated as failures.
    #[arg(long)]
    pub stochastic: bool,
    /// Print a Markdown table.
    #[arg(long)]
    pub markdown: bool,
    /// Also write one CSV row per (agent, object) to this file.
    #[arg(long)]
    pub csv: Option<PathBuf>,
    /// Synergy model (JSON) of the baselines and of checkpoints saved without one; the
    /// shipped model when absent. Checkpoints use the synergy.json saved beside them.
    #[arg(long)]
    pub synergy: Option<PathBuf>,
    /// Synergy components (baselines; default 5). Checkpoints use the number in their
    /// config.toml: a different value is an error.
    #[arg(long)]
    pub components: Option<usize>,
    /// Sensing modality M1, M2, M3 or M3G (baselines; default M3). Checkpoints use the one in
    /// their config.toml: a different value is an error.
    #[arg(long)]
    pub modality: Option<Modality>,
    /// Curriculum success rate r_s that sets the start-pose randomisation (eq. 6).
    #[arg(long, default_value_t = 1.0, allow_negative_numbers = true)]
    pub difficulty: f64,
    /// Simulator config (TOML). When absent: the one the checkpoints were trained with
    /// (their config.toml's sim_config, a path from the current directory; refused when
    /// they differ; the built-in one, with a warning, when the file cannot be read), else
    /// the built-in defaults. Given, it applies to every agent, with a warning for each
    /// checkpoint trained with another.
    #[arg(long)]
    pub sim_config: Option<PathBuf>,
    /// Worker threads (default: available cores).
    #[arg(long)]
    pub threads: Option<usize>,
    /// Where every agent's hand starts: `top-down` over the object's centre, 1 cm below
    /// its top (the training placement), or `antipodal`, the pre-grasp `grasp run` plans:
    /// the best top-down antipodal grasp on the simulated depth cloud of the object at
    /// rest (the default placement where the sampler finds none).
    #[arg(long, value_enum, default_value_t = Placement::TopDown)]
    pub pregrasp: Placement,
    /// Evaluate every agent in perturbed conditions: a TOML file with `[placement]`
    /// (start-pose offsets, yaw, height and a share of antipodal pre-grasps, as a training
    /// config's `[env.placement]`) and `[randomization]` (object mass, friction, size,
    /// sensor noise, as `[env.randomization]`), e.g. configs/sensing/conditions.toml.
    /// Every agent meets the same draws, trial by trial.
    #[arg(long, value_name = "FILE")]
    pub perturb: Option<PathBuf>,
    /// Attempts per trial (beyond the paper, whose trials lift once). After a failed lift
    /// the hand opens where it is, the object comes to rest wherever the attempt left it
    /// (no teleporting), and the hand is placed again as --pregrasp says, on the object as
    /// it now lies: with `antipodal` the planner sees the new depth cloud and skips the
    /// grasps the trial already tried. A trial succeeds when any attempt does; the JSON
    /// gives each trial's attempts and how many trials were won at the first.
    #[arg(long, default_value_t = 1)]
    pub attempts: usize,
    /// With `--pregrasp antipodal` (beyond the paper): compare the planner's K best
    /// distinct placements and start from the one a trained critic values most: for each,
    /// stage 1 closes the hand there in a probe simulation and the critic of --ranker
    /// values the first observation (joint angles, touch, torque levels). One ranker
    /// places every agent, so all agents still start each trial from the same pose. 1:
    /// the planner's best (its geometric score).
    #[arg(long, default_value_t = 1, value_name = "K")]
    pub rank_top: usize,
    /// The checkpoint whose critic ranks the placements (--rank-top above 1); by default
    /// the first checkpoint of --policy.
    #[arg(long, value_name = "CHECKPOINT")]
    pub ranker: Option<PathBuf>,
    #[command(flatten)]
    pub rec: super::RecordArgs,
}

/// Where an episode's hand starts (`--pregrasp`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Placement {
    /// Over the object's centre, `grasp_depth` below its top.
    TopDown,
    /// `grasp run`'s antipodal pre-grasp on the simulated depth cloud.
    Antipodal,
}

/// Runs the evaluation the flags describe, or reads an earlier one's results, and prints
/// and writes them.
pub fn run(mut a: EvalArgs, g: &Global) -> Result<()> {
    // Every output is checked before the first episode, so that no evaluation is thrown
    // away by a write bound to fail.
    if let Some(p) = &a.plot {
        check_plot_path(p)?;
    }
    if let Some(p) = &a.csv {
        check_writable_file(p)
            .map_err(|e| anyhow::anyhow!("--csv {}: {}", p.display(), e.source))?;
    }
    check_overlaps(&a)?;
    // `--labels "A, B"` names B, not " B".
    for l in &mut a.labels {
        *l = l.trim().to_string();
    }
    check_labels(&a)?;
    let (mut results, title) = match a.from_json.as_slice() {
        [] => (
            measure(&a, g)?,
            format!(
                "Per-object success on '{}', seed {}",
                a.objects,
                g.seed.unwrap_or(0)
            ),
        ),
        files => (
            saved(&a, files)?,
            format!(
                "Per-object success, {}",
                files
                    .iter()
                    .map(|f| f.display().to_string())
                    .collect::<Vec<_>>()
                    .join(" + ")
            ),
        ),
    };
    let interrupted = signal::stopped();
    if interrupted && results.is_empty() {
        super::exit_interrupted(" before any trial finished: nothing to report", false);
    }
    if !a.labels.is_empty() {
        // Agents a signal kept from starting have no results (nor labels to take).
        if interrupted {
            a.labels.truncate(results.len());
        }
        if a.labels.len() != results.len() {
            bail!(
                "--labels names {} agents, but there are {}: {}",
                a.labels.len(),
                results.len(),
                results
                    .iter()
                    .map(|r| r.agent.as_str())
                    .collect::<Vec<_>>()
                    .join(", ")
            );
        }
        for (r, l) in results.iter_mut().zip(&a.labels) {
            r.agent = l.clone();
        }
    }
    // The results are printed before any file is written: a failed write loses nothing.
    print_results(&a, g, &results)?;
    if let Some(p) = &a.csv {
        write_atomic(p, csv_table(&results).as_bytes())?;
    }
    if let Some(p) = &a.plot {
        let title = a.plot_title.clone().unwrap_or(title);
        write_per_object_plot(p, &title, &results)?;
        if !g.quiet {
            eprintln!("wrote the per-object plot to {}", p.display());
        }
    }
    if let (Some(dir), true) = (&a.rec.record, a.from_json.is_empty()) {
        let entries: Vec<_> = results.iter().flat_map(|r| r.recordings.clone()).collect();
        let errors: Vec<String> = results
            .iter()
            .flat_map(|r| r.record_errors.iter().cloned())
            .collect();
        super::finish_recordings(dir, &entries, &errors, g.quiet)?;
    }
    if interrupted {
        super::exit_interrupted(
            ": the results above are of the trials that finished",
            g.quiet,
        );
    }
    Ok(())
}

/// Refuses outputs that would overwrite an input (a `--from-json` file, a checkpoint's
/// files, `--perturb`, ...) or each other (`--csv`, `--plot`, files inside `--record`).
fn check_overlaps(a: &EvalArgs) -> Result<()> {
    use grasp::util::fsx::{check_outputs, Named};
    let dirs: Vec<PathBuf> = a
        .policy
        .iter()
        .filter(|p| !matches!(p.as_str(), "baseline1" | "baseline2"))
        .map(PathBuf::from)
        .chain(a.ranker.iter().cloned())
        .collect();
    let ckpt: Vec<PathBuf> = dirs
        .iter()
        .flat_map(|d| grasp::checkpoint::files::read_by_commands(d))
        .collect();
    let mut inputs: Vec<Named> = a
        .from_json
        .iter()
        .map(|f| Named::new("--from-json", f))
        .collect();
    for (flag, p) in [
        ("--perturb", &a.perturb),
        ("--synergy", &a.synergy),
        ("--sim-config", &a.sim_config),
    ] {
        if let Some(p) = p {
            inputs.push(Named::new(flag, p));
        }
    }
    let objects = if a.from_json.is_empty() {
        grasp::objects::sets::files_read(&a.objects)
    } else {
        Vec::new()
    };
    inputs.extend(objects.iter().map(|p| Named::new("--objects", p)));
    inputs.extend(ckpt.iter().map(|p| Named::new("the checkpoint file", p)));
    let mut outputs = Vec::new();
    if let Some(p) = &a.csv {
        outputs.push(Named::new("--csv", p));
    }
    if let Some(p) = &a.plot {
        outputs.push(Named::new("--plot", p));
    }
    let folders: Vec<Named> = a
        .rec
        .record
        .iter()
        .map(|d| Named::new("--record", d))
        .collect();
    check_outputs(&inputs, &outputs, &folders)?;
    Ok(())
}

/// Refuses empty or repeated `--labels` (the outputs would say "A vs A"), and, before an
/// evaluation, a number of labels other than the number of `--policy` agents.
fn check_labels(a: &EvalArgs) -> Result<()> {
    for (i, l) in a.labels.iter().enumerate() {
        if l.trim().is_empty() {
            bail!("--labels: label {} is empty; give each agent a name", i + 1);
        }
        if a.labels[..i].contains(l) {
            bail!("--labels: '{l}' is given twice; each agent needs its own name");
        }
        // A line break would split the agent's row of --csv and --markdown.
        if l.chars().any(char::is_control) {
            bail!(
                "--labels: label {} ({l:?}) holds a control character (a line break or \
                 tab); give each agent a one-line name",
                i + 1
            );
        }
    }
    if a.from_json.is_empty() && !a.labels.is_empty() && a.labels.len() != a.policy.len() {
        bail!(
            "--labels names {} agents, but --policy gives {}: {}",
            a.labels.len(),
            a.policy.len(),
            a.policy.join(", ")
        );
    }
    Ok(())
}

/// The agents of earlier `grasp eval --json` evaluations in `files` (pooled when several:
/// [`grasp::eval::pool`]): those named by --policy, in that order, or all.
fn saved(a: &EvalArgs, files: &[PathBuf]) -> Result<Vec<AgentResult>> {
    if let [file] = files {
        return Ok(grasp::eval::select_agents(
            file,
            read_results(file)?,
            &a.policy,
        )?);
    }
    let wanted: Vec<String> = a
        .policy
        .iter()
        .map(|p| grasp::eval::saved_agent_name(p))
        .collect();
    let mut read = Vec::with_capacity(files.len());
    let mut held: Vec<String> = Vec::new();
    for f in files {
        let mut agents = read_results(f)?;
        for r in &agents {
            if !held.contains(&r.agent) {
                held.push(r.agent.clone());
            }
        }
        if !wanted.is_empty() {
            agents.retain(|r| wanted.contains(&r.agent));
        }
        read.push((f.clone(), agents));
    }
    let all = grasp::eval::pool::pool(&read)?;
    if wanted.is_empty() {
        return Ok(all);
    }
    wanted
        .iter()
        .map(|name| {
            all.iter()
                .find(|r| &r.agent == name)
                .cloned()
                .with_context(|| {
                    format!(
                        "the files hold no agent '{name}'; they hold: {}",
                        held.join(", ")
                    )
                })
        })
        .collect()
}

/// Checks the flags that need no file: `--trials`, `--difficulty`, the recording flags.
fn check_flags(a: &EvalArgs) -> Result<()> {
    use grasp::eval::MAX_TRIALS;
    if a.trials == 0 || a.trials > MAX_TRIALS {
        bail!(
            "--trials {} must be in 1..={MAX_TRIALS} (trials per object, each a simulated \
             episode per agent)",
            a.trials
        );
    }
    super::check_attempts(a.attempts, "lifts per trial; 1 is the paper's protocol")?;
    if a.rank_top == 0 || a.rank_top > MAX_RANK_TOP {
        bail!(
            "--rank-top {} must be in 1..={MAX_RANK_TOP} (the planner's best placements a \
             critic compares; 1: the planner's best)",
            a.rank_top
        );
    }
    if a.rank_top > 1 && a.pregrasp != Placement::Antipodal {
        bail!(
            "--rank-top {} ranks the planner's placements: it needs --pregrasp antipodal",
            a.rank_top
        );
    }
    if let Some(r) = &a.ranker {
        if a.rank_top < 2 {
            bail!(
                "--ranker {} ranks placements only with --rank-top 2 or more",
                r.display()
            );
        }
        if !r.join(grasp::ppo::CHECKPOINT_FILE).is_file() {
            bail!(
                "--ranker {}: not a checkpoint folder (no {})",
                r.display(),
                grasp::ppo::CHECKPOINT_FILE
            );
        }
    }
    super::check_difficulty(a.difficulty)?;
    a.rec.check()
}

/// Evaluates the agents the flags name ([`grasp::eval::request::measure`]), saying its
/// warnings and progress on stderr unless `--quiet`; a SIGINT or SIGTERM starts no new
/// trial.
fn measure(a: &EvalArgs, g: &Global) -> Result<Vec<AgentResult>> {
    check_flags(a)?;
    let req = EvalRequest {
        policy: a.policy.clone(),
        stochastic: a.stochastic,
        objects: a.objects.clone(),
        trials: a.trials,
        attempts: a.attempts,
        synergy: a.synergy.clone(),
        components: a.components,
        modality: a.modality,
        difficulty: a.difficulty,
        sim_config: a.sim_config.clone(),
        threads: a.threads,
        pregrasp: match a.pregrasp {
            Placement::TopDown => grasp::eval::request::Placement::TopDown,
            Placement::Antipodal => grasp::eval::request::Placement::Antipodal,
        },
        perturb: a.perturb.clone(),
        rank_top: a.rank_top,
        ranker: a.ranker.clone(),
        record: a.rec.record.as_ref().map(|dir| RecordOptions {
            dir: dir.clone(),
            every: a.rec.record_every,
            only_failures: a.rec.record_failures,
            name: None,
        }),
        labels: a.labels.clone(),
        seed: g.seed.unwrap_or(0),
    };
    signal::stop_on_signal(
        "finishing the trials in progress, then printing and writing the finished ones",
        g.quiet,
    )
    .context("installing the Ctrl-C and SIGTERM handler")?;
    let say = |e: EvalEvent| match e {
        EvalEvent::Warning(m) if !g.quiet => eprintln!("warning: {m}"),
        EvalEvent::Progress(m) if !g.quiet => eprintln!("{m}"),
        _ => {}
    };
    Ok(grasp::eval::request::measure(
        &req,
        &say,
        Some(&signal::STOP),
    )?)
}

/// Prints `results` as the flags ask: JSON, Markdown or text, with the lift statistics and
/// the paired comparisons with the first agent.
fn print_results(a: &EvalArgs, g: &Global, results: &[AgentResult]) -> Result<()> {
    // Agents whose trials are not the same scenes are said to be so, not left out.
    let pairs = paired_lines(&paired_with_first(results)) + &unpaired_lines(results);
    let lift_lines: String = results.iter().map(lift_line).collect::<String>()
        + &results.iter().filter_map(retry_line).collect::<String>();
    let physics_lines: String = results.iter().map(physics_line).collect::<String>()
        + &results
            .iter()
            .filter(|r| r.interrupted)
            .map(|r| {
                format!(
                    "{}: interrupted (SIGINT or SIGTERM): only the trials that finished are \
                     counted\n",
                    r.agent
                )
            })
            .collect::<String>();
    if g.json {
        println!("{}", serde_json::to_string_pretty(results)?);
    } else if a.markdown {
        print!("{}", markdown_table(results));
        print!("\n{lift_lines}{physics_lines}");
        if !pairs.is_empty() {
            print!("\n{pairs}");
        }
    } else {
        print!("{}", text_table(results));
        print!("{lift_lines}{physics_lines}{pairs}");
    }
    Ok(())
}

/// One line on how an agent's trials used their attempts (`--attempts` > 1).
fn retry_line(r: &AgentResult) -> Option<String> {
    let s = r.retries.as_ref()?;
    let n: usize = r.objects.iter().map(|o| o.trials).sum();
    let stopped: Vec<String> = s
        .not_retried
        .iter()
        .map(|(k, v)| format!("{v} {}", k.replace('_', " ")))
        .collect();
    Some(format!(
        "{}: {} attempts per trial: {} of {n} trials won at the first ({:.1} %), {} more on a \
         later attempt; {} trials retried{}\n",
        r.agent,
        s.attempts,
        s.first_attempt_successes,
        100.0 * s.first_attempt_successes as f64 / n.max(1) as f64,
        s.won_on_retry,
        s.retried,
        if stopped.is_empty() {
            String::new()
        } else {
            format!("; not retried: {}", stopped.join(", "))
        }
    ))
}

/// One line on how an agent's lifts were made: thumb contact and grip, and how the failed
/// lifts ended (left out for results saved before it was recorded: `--from-json` of an
/// older file).
fn lift_line(r: &grasp::eval::AgentResult) -> String {
    let l = &r.lifts;
    let mut line = format!(
        "{}: {} lifts, thumb touching at {:.1} % of them; grip through the lift {:.2} N m \
         (held {:.2}, dropped {:.2})",
        r.agent,
        l.lifted,
        100.0 * l.thumb_contact_rate,
        l.mean_grip_effort,
        l.mean_grip_held,
        l.mean_grip_dropped,
    );
    if r.objects.iter().any(|o| !o.lift_turns.is_empty()) {
        line += &format!(
            "; failed lifts: {} with the object still in the hand, too low, {} with it out \
             of the hand",
            l.failed_in_hand, l.failed_out_of_hand,
        );
        match (l.median_turn_held_deg, l.median_turn_failed_deg) {
            (Some(held), Some(failed)) => {
                line += &format!(
                    "; the object turned by a median {held:.0} deg in the lifts that held it, \
                     {failed:.0} deg in those that failed"
                )
            }
            (Some(held), None) => {
                line += &format!(
                    "; the object turned by a median {held:.0} deg in the lifts that held it \
                     (the failed lifts' median is in each file)"
                )
            }
            _ => {}
        }
    }
    line + "\n"
}

#[cfg(test)]
mod tests {
    use super::lift_line;

    #[test]
    fn the_lift_line_tells_how_failed_lifts_ended_where_it_was_recorded() {
        let read = |f: &str| {
            let p = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(f);
            grasp::eval::read_results(&p).unwrap()
        };
        // Saved before the record existed: no claim about it.
        let old = read("docs/results/delay_2026_12/novel_top-down_seed0.json");
        let line = lift_line(&old[0]);
        assert!(line.starts_with("gd1_s1: 200 lifts"), "{line}");
        assert!(!line.contains("failed lifts"), "{line}");
        // Recorded: the counts and median turns of the file.
        let new = read("docs/results/squeeze_2026_12/report/novel_top-down_seed0.json");
        let l = &new[0].lifts;
        assert!(l.failed_in_hand + l.failed_out_of_hand > 0);
        let line = lift_line(&new[0]);
        let want = format!(
            "failed lifts: {} with the object still in the hand, too low, {} with it out of the hand",
            l.failed_in_hand, l.failed_out_of_hand
        );
        assert!(line.contains(&want), "{line}");
        assert!(line.ends_with("deg in those that failed\n"), "{line}");
    }
}
