//! Training configs for Python: a config file resolved exactly as `grasp train` resolves
//! it (`base` chains, defaults, validation), or the built-in defaults, with a few
//! overrides applied and validated again.

use super::error::config_error;
use crate::env::curriculum::CurriculumConfig;
use crate::train::TrainConfig;
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::path::{Path, PathBuf};

/// The built-in defaults: `configs/base.toml` (the recipe of the shipped policy), embedded.
/// Its synergy model and simulator config are the shipped ones, embedded too.
pub const BUILTIN_CONFIG: &str = include_str!("../../configs/base.toml");

/// The name the built-in config is reported under.
pub const BUILTIN_PATH: &str = "configs/base.toml";

/// What Python may override on top of a config.
#[derive(Debug, Clone, Default)]
pub struct Overrides {
    /// `objects`: `train`, `unseen`, `all`, a folder, a manifest, names, `primitives` or
    /// `procedural`.
    pub objects: Option<String>,
    /// `num_envs` (any count: the learner's constraints on it do not apply).
    pub num_envs: Option<usize>,
    /// `threads` of the environment pool.
    pub threads: Option<usize>,
    /// `seed`.
    pub seed: Option<u64>,
    /// A fixed curriculum level `r_s` in [0, 1] (the curriculum off), as `grasp eval
    /// --difficulty`.
    pub difficulty: Option<f64>,
}

/// The keyword arguments of an environment class (`CoreEnv`, `CoreVecEnv`): `config` (a
/// path) or `config_toml` (text), and the overrides the class takes, `keys`, each `None`
/// when absent. Any other keyword is a `TypeError` naming it and those accepted. Returns
/// the config resolved as [`load`] resolves it.
pub fn load_kwargs(
    kwargs: Option<&Bound<'_, PyDict>>,
    keys: &[&str],
) -> PyResult<(TrainConfig, String)> {
    fn item<'py, T: for<'a> FromPyObject<'a, 'py, Error = PyErr>>(
        kwargs: Option<&Bound<'py, PyDict>>,
        key: &str,
    ) -> PyResult<Option<T>> {
        match kwargs.map(|d| d.get_item(key)).transpose()?.flatten() {
            Some(v) if !v.is_none() => v
                .extract()
                .map(Some)
                .map_err(|e| PyTypeError::new_err(format!("argument '{key}': {e}"))),
            _ => Ok(None),
        }
    }
    if let Some(d) = kwargs {
        for k in d.keys() {
            let k: String = k.extract()?;
            if !(k == "config" || k == "config_toml" || keys.contains(&k.as_str())) {
                return Err(PyTypeError::new_err(format!(
                    "unexpected keyword argument '{k}': expected config, config_toml{}",
                    keys.iter().map(|k| format!(", {k}")).collect::<String>()
                )));
            }
        }
    }
    // Only the class's keys can be present (checked above).
    let o = Overrides {
        objects: item(kwargs, "objects")?,
        num_envs: item(kwargs, "num_envs")?,
        threads: item(kwargs, "threads")?,
        seed: item(kwargs, "seed")?,
        difficulty: item(kwargs, "difficulty")?,
    };
    let config: Option<PathBuf> = item(kwargs, "config")?;
    let config_toml: Option<String> = item(kwargs, "config_toml")?;
    load(config.as_deref(), config_toml.as_deref(), &o)
}

/// Where a config comes from.
#[derive(Debug, Clone, Copy)]
pub enum Source<'a> {
    /// The built-in defaults ([`BUILTIN_CONFIG`]).
    Builtin,
    /// A config file, with its `base` chain.
    File(&'a Path),
    /// Config text without `base` (e.g. the `config.toml` saved beside a checkpoint).
    Text(&'a str),
}

impl<'a> Source<'a> {
    /// The source of the Python arguments `config` (a path) and `config_toml` (text):
    /// at most one of them.
    pub fn of(path: Option<&'a Path>, text: Option<&'a str>) -> PyResult<Source<'a>> {
        match (path, text) {
            (Some(_), Some(_)) => Err(PyValueError::new_err(
                "give either config (a file) or config_toml (its text), not both",
            )),
            (Some(p), None) => Ok(Source::File(p)),
            (None, Some(t)) => Ok(Source::Text(t)),
            (None, None) => Ok(Source::Builtin),
        }
    }
}

/// Loads the config of `source`, applies `o` and validates the result; errors
/// (`ValueError`) name the file and the field.
pub fn resolve(source: Source<'_>, o: &Overrides) -> PyResult<TrainConfig> {
    let (mut cfg, origin) = match source {
        Source::File(p) => (TrainConfig::load(p).map_err(config_error)?, p.to_path_buf()),
        Source::Text(t) => {
            let p = Path::new("config_toml");
            (
                TrainConfig::parse(p, t).map_err(config_error)?,
                p.to_path_buf(),
            )
        }
        Source::Builtin => (
            TrainConfig::parse(Path::new(BUILTIN_PATH), BUILTIN_CONFIG).map_err(config_error)?,
            PathBuf::from(BUILTIN_PATH),
        ),
    };
    if let Some(objects) = &o.objects {
        cfg.objects = objects.clone();
    }
    if o.threads.is_some() {
        cfg.threads = o.threads;
    }
    if let Some(s) = o.seed {
        cfg.seed = s;
    }
    if let Some(d) = o.difficulty {
        if !(0.0..=1.0).contains(&d) {
            return Err(PyValueError::new_err(format!(
                "difficulty must be in [0, 1], got {d}"
            )));
        }
        cfg.env.grasp.curriculum = CurriculumConfig {
            enabled: false,
            fixed_rate: d,
            ..cfg.env.grasp.curriculum.clone()
        };
    }
    cfg.validate(&origin).map_err(config_error)?;
    // Set after the validation: the learner's checks of num_envs (minibatches of whole
    // environment sequences) are not the environments' business.
    if let Some(n) = o.num_envs {
        if n == 0 {
            return Err(PyValueError::new_err("num_envs must be at least 1"));
        }
        cfg.num_envs = n;
    }
    Ok(cfg)
}

/// The config of an environment's Python arguments `config` (a file) and `config_toml`
/// (its text), at most one of them, with the overrides `o`: resolved, validated, and as
/// TOML with every default filled in.
pub fn load(
    config: Option<&Path>,
    config_toml: Option<&str>,
    o: &Overrides,
) -> PyResult<(TrainConfig, String)> {
    let cfg = resolve(Source::of(config, config_toml)?, o)?;
    let toml = cfg.to_toml_string().map_err(config_error)?;
    Ok((cfg, toml))
}

/// The built-in config's TOML text (`configs/base.toml`).
#[pyfunction]
pub fn builtin_config_toml() -> &'static str {
    BUILTIN_CONFIG
}

/// The resolved config of `config` (a path, or None for the built-in defaults) as TOML,
/// every default filled in.
#[pyfunction]
#[pyo3(signature = (config=None))]
pub fn resolved_config_toml(config: Option<PathBuf>) -> PyResult<String> {
    Ok(load(config.as_deref(), None, &Overrides::default())?.1)
}
