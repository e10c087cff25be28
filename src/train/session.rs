//! A training run in its run folder: environments, trainer, metrics, checkpoints, plots.

use super::envs::{build_envs, CurriculumLevels, TrainEnvs};
use super::metrics::{self, MetricsRow};
use super::{plot, tfevents, TrainError};
use crate::checkpoint::files;
use crate::checkpoint::TrainConfig;
use crate::ppo::{Trainer, UpdateMetrics, CHECKPOINT_FILE};
use crate::util::fsx::write_atomic;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Instant, SystemTime, UNIX_EPOCH};

/// How [`TrainSession::open_with`] treats an existing run folder.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct OpenOptions {
    /// Continue the run from `checkpoints/latest`.
    pub resume: bool,
    /// Resume even though the `[env]` table differs from the one the checkpoint was
    /// trained under (the differing keys are logged).
    pub allow_env_change: bool,
}

use crate::checkpoint::{best_dir, latest_dir, milestone_dir};

/// What the caller sees after each update.
#[derive(Debug, Clone, Copy)]
pub struct Progress<'a> {
    /// The update's metrics row.
    pub row: &'a MetricsRow,
    /// Updates planned in total.
    pub planned_updates: u64,
    /// Transitions planned in total (`planned_updates * batch`).
    pub planned_steps: u64,
}

/// Why a run stopped.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum StopReason {
    /// All planned updates are done.
    Completed,
    /// `time_budget_minutes` ran out.
    TimeBudget,
    /// The stop flag ([`TrainSession::set_stop_flag`], Ctrl-C in `grasp train`) was
    /// raised: the update in progress was finished and a checkpoint written.
    Interrupted,
}

/// The outcome of [`TrainSession::run`].
#[derive(Debug, Clone, serde::Serialize)]
pub struct TrainSummary {
    /// The run folder.
    pub run_dir: PathBuf,
    /// Updates done in total (over resumes).
    pub updates: u64,
    /// Updates done by this call.
    pub new_updates: u64,
    /// Transitions collected in total.
    pub global_step: u64,
    /// Episodes finished in total.
    pub episodes: u64,
    /// The last metrics row.
    pub last: Option<MetricsRow>,
    /// The most recent success rate recorded (updates where no episode ended have none).
    pub last_success_rate: Option<f64>,
    /// The most recent mean episode return recorded.
    pub last_return: Option<f64>,
    /// Best windowed score so far (success rate, or return without success).
    pub best_score: Option<f64>,
    /// Why it stopped.
    pub stop: StopReason,
    /// Training wall time in total (s).
    pub wall_s: f64,
}

/// A run folder with its trainer, ready to train.
pub struct TrainSession {
    cfg: TrainConfig,
    dir: PathBuf,
    trainer: Trainer,
    rows: Vec<MetricsRow>,
    levels: Option<CurriculumLevels>,
    synergy_json: Option<String>,
    config_text: String,
    events_path: PathBuf,
    t0_unix: f64,
    best: Option<f64>,
    wall_offset: f64,
    stop_flag: Option<Arc<AtomicBool>>,
    /// The run folder's lock file, locked for the session's life (the OS releases the
    /// lock when the process ends, however it ends).
    _lock: std::fs::File,
}

fn now_unix() -> f64 {
    SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map_or(0.0, |d| d.as_secs_f64())
}

/// Removes what a run killed before its first update left in `dir` (a metrics file
/// without rows, event files, plot), so a fresh start does not mix with it. The caller
/// has checked that no metrics row and no best checkpoint exist.
fn discard_unfinished(dir: &Path) -> Result<(), TrainError> {
    let io = |path: &Path| {
        let path = path.to_path_buf();
        move |source| TrainError::Io { path, source }
    };
    let rd = std::fs::read_dir(dir).map_err(io(dir))?;
    for entry in rd.flatten() {
        let name = entry.file_name().to_string_lossy().into_owned();
        let stale = name == files::METRICS
            || name == files::PLOT
            || (name.starts_with(files::EVENTS_PREFIX) && name.ends_with(files::EVENTS_SUFFIX));
        if stale && entry.path().is_file() {
            std::fs::remove_file(entry.path()).map_err(|source| TrainError::Remove {
                path: entry.path(),
                source,
            })?;
        }
    }
    Ok(())
}

/// Takes the exclusive lock of run folder `dir` (created if needed), or says which
/// folder is in use.
/// Refuses a folder that is no run folder, before anything is written in it: a
/// checkpoint folder (its `config.toml` would be replaced by the run's, and the
/// checkpoint no longer load), a folder inside a run's `checkpoints`, or a non-empty
/// folder without a run's `config.toml` (the repository, a folder of other files). A
/// missing or empty folder, or a run folder, is fine.
pub fn check_run_folder(dir: &Path) -> Result<(), TrainError> {
    let refuse = |why: String| {
        Err(TrainError::NotARunFolder {
            dir: dir.to_path_buf(),
            why,
        })
    };
    if !dir.exists() {
        return Ok(());
    }
    if dir.join(CHECKPOINT_FILE).exists() {
        return refuse(format!(
            "is a checkpoint folder (it holds {CHECKPOINT_FILE}); training there would replace \
             its config.toml"
        ));
    }
    let resolved = crate::util::fsx::resolved(dir);
    if resolved.ancestors().skip(1).any(|a| {
        a.join(CHECKPOINT_FILE).is_file()
            || (a.file_name().is_some_and(|n| n == "checkpoints")
                && a.parent().is_some_and(|p| p.join(files::CONFIG).is_file()))
    }) {
        return refuse("lies inside a run's checkpoints or a checkpoint folder".into());
    }
    let entries = std::fs::read_dir(dir).map_err(|source| TrainError::Io {
        path: dir.to_path_buf(),
        source,
    })?;
    let mut others = Vec::new();
    let mut has_config = false;
    for e in entries.flatten() {
        let name = e.file_name().to_string_lossy().into_owned();
        match name.as_str() {
            files::LOCK => {}
            files::CONFIG => has_config = true,
            _ => others.push(name),
        }
    }
    if !has_config && !others.is_empty() {
        others.sort();
        let shown: Vec<&str> = others.iter().take(3).map(String::as_str).collect();
        return refuse(format!(
            "is not empty and not a run folder (no {}; it holds {}{})",
            files::CONFIG,
            shown.join(", "),
            if others.len() > 3 { ", ..." } else { "" }
        ));
    }
    Ok(())
}

fn lock_run_dir(dir: &Path) -> Result<std::fs::File, TrainError> {
    crate::util::fsx::create_dirs(dir).map_err(|source| TrainError::Create {
        path: dir.to_path_buf(),
        source,
    })?;
    let path = dir.join(files::LOCK);
    let file = std::fs::OpenOptions::new()
        .create(true)
        .truncate(false)
        .write(true)
        .open(&path)
        .map_err(|source| TrainError::Create {
            path: path.clone(),
            source,
        })?;
    match file.try_lock() {
        Ok(()) => Ok(file),
        Err(std::fs::TryLockError::WouldBlock) => Err(TrainError::RunInUse {
            dir: dir.to_path_buf(),
        }),
        Err(std::fs::TryLockError::Error(e)) if e.kind() == std::io::ErrorKind::Unsupported => {
            tracing::warn!(
                "{}: the file system does not support file locks; make sure no other \
                 process trains into this folder",
                dir.display()
            );
            Ok(file)
        }
        Err(std::fs::TryLockError::Error(source)) => Err(TrainError::Create { path, source }),
    }
}

/// The keys (dotted, e.g. `env.randomization.friction`) whose values differ between two
/// TOML tables.
fn table_differences(prefix: &str, a: &toml::Table, b: &toml::Table, out: &mut Vec<String>) {
    let mut keys: Vec<&String> = a.keys().chain(b.keys()).collect();
    keys.sort();
    keys.dedup();
    for k in keys {
        let name = format!("{prefix}.{k}");
        match (a.get(k), b.get(k)) {
            (Some(toml::Value::Table(x)), Some(toml::Value::Table(y))) => {
                table_differences(&name, x, y, out)
            }
            (x, y) if x != y => out.push(name),
            _ => {}
        }
    }
}

/// The `[env]` keys (and the object set, `objects`) in which `new` differs from the
/// config the checkpoint in `latest` was trained under (`config.toml` beside it); empty
/// when that file is absent.
fn env_differences(latest: &Path, new: &TrainConfig) -> Result<Vec<String>, TrainError> {
    let path = latest.join(files::CONFIG);
    if !path.is_file() {
        return Ok(Vec::new());
    }
    let text = crate::util::fsx::read_to_string_bounded(&path, crate::util::fsx::limits::DATA)
        .map_err(|source| TrainError::Io {
            path: path.clone(),
            source,
        })?;
    let env_table = |t: &str, p: &Path| -> Result<toml::Table, TrainError> {
        let table: toml::Table =
            crate::util::config::parse_toml(p, t).map_err(TrainError::ConfigFile)?;
        Ok(match table.get("env") {
            Some(toml::Value::Table(e)) => e.clone(),
            _ => toml::Table::new(),
        })
    };
    // Both sides resolved the same way: the old file parsed to a config and written back.
    let old_cfg = TrainConfig::parse(&path, &text)?;
    let old = env_table(&old_cfg.to_toml_string()?, &path)?;
    let new_env = env_table(&new.to_toml_string()?, Path::new("config.toml"))?;
    let mut out = Vec::new();
    table_differences("env", &old, &new_env, &mut out);
    // The objects trained on are part of the environment too (`--objects unseen` on a
    // resume would switch training to the test set).
    if old_cfg.objects != new.objects {
        out.push(format!(
            "objects ('{}', now '{}')",
            old_cfg.objects, new.objects
        ));
    }
    Ok(out)
}

/// The existing event file of `dir` and its start time, if any.
fn find_events(dir: &Path) -> Result<Option<(PathBuf, f64)>, TrainError> {
    let rd = std::fs::read_dir(dir).map_err(|source| TrainError::Io {
        path: dir.to_path_buf(),
        source,
    })?;
    for entry in rd.flatten() {
        let name = entry.file_name().to_string_lossy().into_owned();
        if let Some(t0) = name
            .strip_prefix(files::EVENTS_PREFIX)
            .and_then(|r| r.strip_suffix(files::EVENTS_SUFFIX))
            .and_then(|t| t.parse::<u64>().ok())
        {
            return Ok(Some((entry.path(), t0 as f64)));
        }
    }
    Ok(None)
}

impl TrainSession {
    /// Prepares run folder `dir` for `cfg`: [`TrainSession::open_with`] with `resume`
    /// and no change of `[env]` allowed.
    pub fn open(cfg: TrainConfig, dir: &Path, resume: bool) -> Result<TrainSession, TrainError> {
        Self::open_with(
            cfg,
            dir,
            OpenOptions {
                resume,
                allow_env_change: false,
            },
        )
    }

    /// Prepares run folder `dir` for `cfg`. First the folder's exclusive lock is taken
    /// (held until the session is dropped or the process ends): a second process on the
    /// same folder is refused. A new run (`resume = false`) refuses a folder that already
    /// holds a checkpoint. With `resume`, the trainer is restored from
    /// `checkpoints/latest` (its network must match `cfg`, and its `[env]` too unless
    /// `allow_env_change`; the other settings of `cfg` apply from now on, so
    /// `total_timesteps` can be raised), the metrics rows after the checkpoint's update
    /// are dropped and the TensorBoard file is rebuilt from the rest; without the metrics
    /// file it refuses while `checkpoints/best` exists (the best score would be lost).
    /// A folder without `checkpoints/latest` starts afresh only when it recorded nothing
    /// (a run killed during its first update); one with metrics rows or
    /// `checkpoints/best` but no `checkpoints/latest` is refused with what to do, and
    /// nothing is deleted.
    pub fn open_with(
        cfg: TrainConfig,
        dir: &Path,
        opts: OpenOptions,
    ) -> Result<TrainSession, TrainError> {
        // Fails on values the run folder's config.toml cannot hold, before the folder
        // is created.
        let config_text = cfg.to_toml_string()?;
        check_run_folder(dir)?;
        let created = !dir.exists();
        let lock = lock_run_dir(dir)?;
        let opened = Self::open_locked(cfg, dir, opts, lock, config_text);
        if opened.is_err() && created {
            // Refused before anything was written: leave no empty folder behind.
            let _ = std::fs::remove_file(dir.join(files::LOCK));
            let _ = std::fs::remove_dir(dir);
        }
        opened
    }

    /// [`TrainSession::open_with`] once the folder's lock is held.
    fn open_locked(
        cfg: TrainConfig,
        dir: &Path,
        opts: OpenOptions,
        lock: std::fs::File,
        config_text: String,
    ) -> Result<TrainSession, TrainError> {
        let resume = opts.resume;
        let latest = latest_dir(dir);
        let ck_file = latest.join(CHECKPOINT_FILE);
        let metrics_path = dir.join(files::METRICS);
        let has_checkpoint = ck_file.exists();
        if !resume && has_checkpoint {
            return Err(TrainError::RunExists {
                dir: dir.to_path_buf(),
            });
        }
        if resume && has_checkpoint && !metrics_path.exists() && best_dir(dir).exists() {
            return Err(TrainError::MetricsMissing {
                metrics: metrics_path,
                best: best_dir(dir),
            });
        }
        if !has_checkpoint {
            let rows = if metrics_path.is_file() {
                metrics::read_csv(&metrics_path)?.len()
            } else {
                0
            };
            let best = best_dir(dir).join(CHECKPOINT_FILE).exists();
            if rows > 0 || best {
                let mut what = format!("{rows} metrics rows");
                let advice = if best {
                    what += &format!(" and {}", best_dir(dir).display());
                    format!(
                        "To continue from the best checkpoint, copy {} to {} and pass \
                         --resume (the metrics rows after its update are dropped); or train \
                         into another --out folder",
                        best_dir(dir).display(),
                        latest.display()
                    )
                } else {
                    "Train into another --out folder (or delete this one to start it \
                     afresh)"
                        .to_string()
                };
                return Err(TrainError::LatestMissing {
                    dir: dir.to_path_buf(),
                    latest,
                    detail: format!("{what}; nothing was changed. {advice}"),
                });
            }
            if resume {
                tracing::warn!(
                    "{} holds no checkpoint and no metrics (the run stopped during its first \
                     update): starting afresh",
                    dir.display()
                );
            }
        }
        if resume && has_checkpoint {
            let changed = env_differences(&latest, &cfg)?;
            if !changed.is_empty() {
                if !opts.allow_env_change {
                    return Err(TrainError::EnvChanged {
                        checkpoint: latest.clone(),
                        keys: changed.join(", "),
                    });
                }
                tracing::warn!(
                    "resuming {} under a changed environment: {}",
                    dir.display(),
                    changed.join(", ")
                );
            }
        }
        let resume = resume && has_checkpoint;
        if !resume && dir.join(files::CONFIG).is_file() {
            discard_unfinished(dir)?;
        }
        let TrainEnvs {
            envs,
            levels,
            synergy: model,
        } = build_envs(&cfg)?;
        let mut trainer = Trainer::new(cfg.ppo_config(), envs)?;
        let mut rows = Vec::new();
        if resume {
            trainer.load_checkpoint(&latest)?;
            if metrics_path.exists() {
                rows = metrics::read_csv(&metrics_path)?;
            }
            rows.retain(|r| r.update <= trainer.update_index());
        }
        let (events_path, t0_unix) = match if resume { find_events(dir)? } else { None } {
            Some(found) => found,
            None => {
                let t0 = now_unix().floor();
                let name = format!(
                    "{}{}{}",
                    files::EVENTS_PREFIX,
                    t0 as u64,
                    files::EVENTS_SUFFIX
                );
                (dir.join(name), t0)
            }
        };
        let mut best: Option<f64> = None;
        for k in 1..=rows.len() {
            let s = metrics::window_score(&rows[..k], cfg.best_window);
            if let Some(s) = s {
                best = Some(best.map_or(s, |b: f64| b.max(s)));
            }
        }
        let session = TrainSession {
            wall_offset: rows.last().map_or(0.0, |r| r.wall_s),
            synergy_json: model.map(|m| m.to_json()),
            cfg,
            dir: dir.to_path_buf(),
            trainer,
            rows,
            levels,
            config_text,
            events_path,
            t0_unix,
            best,
            stop_flag: None,
            _lock: lock,
        };
        write_atomic(&dir.join(files::CONFIG), session.config_text.as_bytes())?;
        session.write_logs()?;
        Ok(session)
    }

    /// Makes [`TrainSession::run`] stop cleanly once `flag` is raised: it finishes the
    /// update in progress, saves `checkpoints/latest` and returns with
    /// [`StopReason::Interrupted`].
    pub fn set_stop_flag(&mut self, flag: Arc<AtomicBool>) {
        self.stop_flag = Some(flag);
    }

    fn stop_requested(&self) -> bool {
        self.stop_flag
            .as_ref()
            .is_some_and(|f| f.load(Ordering::SeqCst))
    }

    /// The configuration.
    pub fn config(&self) -> &TrainConfig {
        &self.cfg
    }

    /// The metrics rows so far.
    pub fn rows(&self) -> &[MetricsRow] {
        &self.rows
    }

    /// The trainer.
    pub fn trainer(&self) -> &Trainer {
        &self.trainer
    }

    /// The run folder.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// Rewrites `metrics.csv` and the TensorBoard file from the rows.
    fn write_logs(&self) -> Result<(), TrainError> {
        write_atomic(
            &self.dir.join(files::METRICS),
            metrics::to_csv(&self.rows).as_bytes(),
        )?;
        let entries: Vec<(f64, i64, tfevents::Scalars<'_>)> = self
            .rows
            .iter()
            .map(|r| {
                let scalars = r
                    .scalars()
                    .into_iter()
                    .map(|(k, v)| (k, v as f32))
                    .collect();
                (self.t0_unix + r.wall_s, r.global_step as i64, scalars)
            })
            .collect();
        write_atomic(
            &self.events_path,
            &tfevents::event_file(self.t0_unix, &entries),
        )?;
        Ok(())
    }

    /// Saves the trainer with the synergy model and the config into `dir`.
    fn save_checkpoint(&self, dir: &Path) -> Result<(), TrainError> {
        if let Some(json) = &self.synergy_json {
            write_atomic(&dir.join(files::SYNERGY), json.as_bytes())?;
        }
        write_atomic(&dir.join(files::CONFIG), self.config_text.as_bytes())?;
        self.trainer.save_checkpoint(dir)?;
        Ok(())
    }

    fn plot(&self) -> Result<(), TrainError> {
        plot::write_learning_curve(&self.dir.join(files::PLOT), &self.cfg.name, &self.rows)
    }

    fn row_from(&self, m: &UpdateMetrics, wall_s: f64) -> MetricsRow {
        let episodes_before = self.rows.last().map_or(0, |r| r.episodes);
        let level = self.levels.as_ref().map(|p| p.mean());
        MetricsRow::new(m, episodes_before, level, wall_s)
    }

    /// Trains until the planned updates are done or the time budget runs out, calling
    /// `on_update` after each update. After every update the metrics and TensorBoard files
    /// are rewritten; `checkpoints/latest` is saved every `checkpoint_every` updates and at
    /// the end, `checkpoints/best` whenever the windowed score improves, and the plot every
    /// `plot_every` updates and at the end.
    pub fn run(
        &mut self,
        on_update: &mut dyn FnMut(Progress<'_>),
    ) -> Result<TrainSummary, TrainError> {
        let start = Instant::now();
        let (planned, planned_steps) = self.trainer.planned();
        let budget = self.cfg.time_budget_minutes.map(|m| m * 60.0);
        let first = self.trainer.update_index();
        let mut stop = StopReason::Completed;
        let mut saved_at = first;
        while self.trainer.wants_update() {
            if self.stop_requested() {
                stop = StopReason::Interrupted;
                break;
            }
            let m = self.trainer.train_update()?;
            tracing::debug!(
                update = m.update,
                rollout_s = m.rollout_secs,
                optimize_s = m.optimize_secs,
                "update timing"
            );
            let row = self.row_from(&m, self.wall_offset + start.elapsed().as_secs_f64());
            self.rows.push(row);
            self.write_logs()?;
            let u = m.update;
            if let Some(s) = metrics::window_score(&self.rows, self.cfg.best_window) {
                if self.best.is_none_or(|b| s > b) {
                    self.best = Some(s);
                    self.save_checkpoint(&best_dir(&self.dir))?;
                }
            }
            if u.is_multiple_of(self.cfg.checkpoint_every) {
                self.save_checkpoint(&latest_dir(&self.dir))?;
                saved_at = u;
            }
            if self.cfg.milestone_every > 0 && u.is_multiple_of(self.cfg.milestone_every) {
                let step = self.trainer.global_step();
                self.save_checkpoint(&milestone_dir(&self.dir, step))?;
            }
            if u.is_multiple_of(self.cfg.plot_every) {
                self.plot()?;
            }
            if let Some(last) = self.rows.last() {
                on_update(Progress {
                    row: last,
                    planned_updates: planned,
                    planned_steps,
                });
            }
            if budget.is_some_and(|b| start.elapsed().as_secs_f64() >= b) {
                stop = StopReason::TimeBudget;
                break;
            }
        }
        if saved_at != self.trainer.update_index()
            || !latest_dir(&self.dir).join(CHECKPOINT_FILE).exists()
        {
            self.save_checkpoint(&latest_dir(&self.dir))?;
        }
        self.plot()?;
        let last = self.rows.last().cloned();
        Ok(TrainSummary {
            run_dir: self.dir.clone(),
            updates: self.trainer.update_index(),
            new_updates: self.trainer.update_index() - first,
            global_step: self.trainer.global_step(),
            episodes: last.as_ref().map_or(0, |r| r.episodes),
            best_score: self.best,
            stop,
            wall_s: last.as_ref().map_or(self.wall_offset, |r| r.wall_s),
            last_success_rate: self.rows.iter().rev().find_map(|r| r.stats.success_rate),
            last_return: self.rows.iter().rev().find_map(|r| r.stats.episode_return),
            last,
        })
    }
}

#[cfg(test)]
mod tests {
    use crate::robot::{Posture, Robot, Side};
    use crate::sim::script;
    use crate::synergy::SynergyModel;
    use rand::{Rng, SeedableRng};

    #[test]
    fn truncation_keeps_the_leading_components() {
        let robot = Robot::builtin(Side::Left);
        let lim = robot.finger_limits();
        let (a, b) = (Posture::CShape.angles(), script::power_grasp());
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(2);
        let rows: Vec<[f64; 22]> = (0..200)
            .map(|_| {
                let t: f64 = rng.random();
                std::array::from_fn(|k| {
                    (a[k + 2] + t * (b[k + 2] - a[k + 2]) + rng.random_range(-0.05..0.05))
                        .clamp(lim[k].0, lim[k].1)
                })
            })
            .collect();
        let m5 = SynergyModel::fit(&rows, 5).unwrap();
        let m3 = m5.truncated(3).unwrap();
        assert_eq!(m3.n_components(), 3);
        // The JSON round trip may move a value by one ulp.
        let close = |a: &[f64], b: &[f64]| {
            a.len() == b.len() && a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-12)
        };
        for k in 0..3 {
            assert!(
                close(&m3.components()[k], &m5.components()[k]),
                "component {k}"
            );
        }
        assert!(close(m3.projection_min(), &m5.projection_min()[..3]));
        assert!(close(m3.projection_max(), &m5.projection_max()[..3]));
        assert!(close(m3.eigenvalues(), m5.eigenvalues()));
        let fit3 = SynergyModel::fit(&rows, 3).unwrap();
        for (x, y) in fit3.components().iter().zip(m3.components()) {
            let dot: f64 = x.iter().zip(y).map(|(p, q)| p * q).sum();
            assert!((dot.abs() - 1.0).abs() < 1e-9, "{dot}");
        }
    }
}
