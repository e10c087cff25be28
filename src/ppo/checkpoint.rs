//! Checkpoint files: one safetensors file, `checkpoint.safetensors`, written atomically.
//!
//! Tensors:
//! - the policy's parameters under their own names (`gru.weight_ih_l0`, `critic.weight`,
//!   ...), f32: the file loads as a plain state dict elsewhere;
//! - Adam's moments, `optim.exp_avg.<param>` and `optim.exp_avg_sq.<param>`, f32;
//! - normaliser statistics `obs_rms.{mean,var,count}` and `ret_rms.{mean,var,count}`, f64.
//!
//! The header's metadata key `grasp.ppo` holds a JSON [`TrainerState`]: the format tag and
//! version, the whole [`PpoConfig`], the environment shapes, the update index, the global
//! step, Adam's step count and the states of the two training RNGs.

use super::config::PpoConfig;
use super::normalize::RunningMeanStd;
use super::PpoError;
use crate::env::api::ActionSpec;
use crate::policy::{build_policy, ActorCritic, Params};
use candle_core::{Device, Tensor};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use safetensors::tensor::{Dtype, SafeTensors, TensorView};
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// File name of the checkpoint inside its directory.
pub const CHECKPOINT_FILE: &str = "checkpoint.safetensors";
/// Format tag stored in the metadata.
pub const FORMAT: &str = "grasp-ppo-checkpoint";
/// Format version.
pub const VERSION: u32 = 1;
/// Metadata key of the JSON state.
pub const META_KEY: &str = "grasp.ppo";
/// Prefix of Adam's first moments.
pub const EXP_AVG: &str = "optim.exp_avg.";
/// Prefix of Adam's second moments.
pub const EXP_AVG_SQ: &str = "optim.exp_avg_sq.";

/// The state of a ChaCha8 generator: seed (hex), stream and word position.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RngState {
    /// The 32-byte seed as 64 hex digits.
    pub seed: String,
    /// The stream.
    pub stream: u64,
    /// The word position (a u128, as a decimal string).
    pub word_pos: String,
}

impl RngState {
    /// Captures `rng`'s exact position.
    pub fn capture(rng: &ChaCha8Rng) -> Self {
        Self {
            seed: rng.get_seed().iter().map(|b| format!("{b:02x}")).collect(),
            stream: rng.get_stream(),
            word_pos: rng.get_word_pos().to_string(),
        }
    }

    /// Rebuilds the generator; `path` names the file in errors.
    pub fn restore(&self, path: &Path) -> Result<ChaCha8Rng, PpoError> {
        let bad = |m: &str| PpoError::CheckpointFormat {
            path: path.to_path_buf(),
            message: format!("invalid RNG state: {m}"),
        };
        if self.seed.len() != 64 || !self.seed.is_ascii() {
            return Err(bad("the seed must be 64 hex digits"));
        }
        let mut seed = [0u8; 32];
        for (i, s) in seed.iter_mut().enumerate() {
            *s = u8::from_str_radix(&self.seed[2 * i..2 * i + 2], 16)
                .map_err(|_| bad("the seed must be 64 hex digits"))?;
        }
        let pos: u128 = self
            .word_pos
            .parse()
            .map_err(|_| bad("word_pos is not an integer"))?;
        let mut rng = ChaCha8Rng::from_seed(seed);
        rng.set_stream(self.stream);
        rng.set_word_pos(pos);
        Ok(rng)
    }
}

/// The JSON metadata of a checkpoint.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TrainerState {
    /// Always [`FORMAT`].
    pub format: String,
    /// Always [`VERSION`].
    pub version: u32,
    /// The training configuration.
    pub config: PpoConfig,
    /// Observation length of the environments.
    pub obs_dim: usize,
    /// Action shape of the environments.
    pub action_spec: ActionSpec,
    /// Updates done.
    pub update: u64,
    /// Transitions collected.
    pub global_step: u64,
    /// Adam's step count.
    pub adam_step: u64,
    /// State of the action-sampling RNG.
    pub rng_act: RngState,
    /// State of the minibatch-shuffling RNG.
    pub rng_mb: RngState,
}

/// Tensor values as stored.
#[derive(Debug, Clone, PartialEq)]
pub enum RawData {
    /// 32-bit floats.
    F32(Vec<f32>),
    /// 64-bit floats.
    F64(Vec<f64>),
}

/// A named tensor as stored in the file.
#[derive(Debug, Clone, PartialEq)]
pub struct RawTensor {
    /// Its name.
    pub name: String,
    /// Its shape.
    pub shape: Vec<usize>,
    /// Its values, row-major.
    pub data: RawData,
}

impl RawTensor {
    /// Copies an f32 candle tensor.
    pub fn from_f32(name: &str, t: &Tensor) -> Result<Self, PpoError> {
        Ok(Self {
            name: name.to_string(),
            shape: t.dims().to_vec(),
            data: RawData::F32(t.flatten_all()?.to_vec1::<f32>()?),
        })
    }

    fn bytes(&self) -> (Dtype, Vec<u8>) {
        match &self.data {
            RawData::F32(v) => (Dtype::F32, v.iter().flat_map(|x| x.to_le_bytes()).collect()),
            RawData::F64(v) => (Dtype::F64, v.iter().flat_map(|x| x.to_le_bytes()).collect()),
        }
    }
}

/// The tensors `prefix.mean`, `prefix.var`, `prefix.count` of running statistics.
pub fn rms_tensors(prefix: &str, r: &RunningMeanStd) -> Vec<RawTensor> {
    vec![
        RawTensor {
            name: format!("{prefix}.mean"),
            shape: vec![r.dim()],
            data: RawData::F64(r.mean.clone()),
        },
        RawTensor {
            name: format!("{prefix}.var"),
            shape: vec![r.dim()],
            data: RawData::F64(r.var.clone()),
        },
        RawTensor {
            name: format!("{prefix}.count"),
            shape: vec![1],
            data: RawData::F64(vec![r.count]),
        },
    ]
}

/// Serialises `tensors` with `state` as metadata and writes them atomically to `path`.
pub fn write_checkpoint(
    path: &Path,
    state: &TrainerState,
    tensors: &[RawTensor],
) -> Result<(), PpoError> {
    let fmt_err = |message: String| PpoError::CheckpointFormat {
        path: path.to_path_buf(),
        message,
    };
    let json = serde_json::to_string(state).map_err(|e| fmt_err(e.to_string()))?;
    let encoded: Vec<(String, Dtype, Vec<u8>, Vec<usize>)> = tensors
        .iter()
        .map(|t| {
            let (dt, b) = t.bytes();
            (t.name.clone(), dt, b, t.shape.clone())
        })
        .collect();
    let mut views = Vec::with_capacity(encoded.len());
    for (name, dt, b, shape) in &encoded {
        let v = TensorView::new(*dt, shape.clone(), b).map_err(|e| fmt_err(e.to_string()))?;
        views.push((name.clone(), v));
    }
    let mut meta = HashMap::new();
    meta.insert(META_KEY.to_string(), json);
    let bytes = safetensors::serialize(views, Some(meta)).map_err(|e| fmt_err(e.to_string()))?;
    crate::util::fsx::write_atomic(path, &bytes)?;
    Ok(())
}

/// A checkpoint read back from disk.
#[derive(Debug, Clone)]
pub struct Checkpoint {
    /// The file it came from.
    pub path: PathBuf,
    /// Its metadata.
    pub state: TrainerState,
    /// Its tensors by name.
    pub tensors: HashMap<String, RawTensor>,
}

/// Reads and checks the checkpoint file at `path`: a missing file, a corrupt file, missing
/// or invalid metadata and non-finite values are errors naming the file.
pub fn read_checkpoint(path: &Path) -> Result<Checkpoint, PpoError> {
    let bytes = crate::util::fsx::read_bounded(path, crate::util::fsx::limits::WEIGHTS).map_err(
        |source| PpoError::CheckpointIo {
            path: path.to_path_buf(),
            source,
        },
    )?;
    let fmt_err = |message: String| PpoError::CheckpointFormat {
        path: path.to_path_buf(),
        message,
    };
    let (_, meta) = SafeTensors::read_metadata(&bytes)
        .map_err(|e| fmt_err(format!("not a valid safetensors file ({e})")))?;
    let json = meta
        .metadata()
        .as_ref()
        .and_then(|m| m.get(META_KEY))
        .ok_or_else(|| {
            fmt_err(format!(
                "no `{META_KEY}` metadata: not a grasp PPO checkpoint"
            ))
        })?;
    let state: TrainerState =
        serde_json::from_str(json).map_err(|e| fmt_err(format!("invalid metadata: {e}")))?;
    if state.format != FORMAT || state.version != VERSION {
        return Err(fmt_err(format!(
            "format {} version {} is not {FORMAT} version {VERSION}",
            state.format, state.version
        )));
    }
    // The stored training config is input too: out-of-range settings (a corrupted
    // policy setting would otherwise surface from the network builder, unnamed).
    state
        .config
        .validate()
        .map_err(|e| fmt_err(format!("stored training config: {e}")))?;
    let st = SafeTensors::deserialize(&bytes)
        .map_err(|e| fmt_err(format!("not a valid safetensors file ({e})")))?;
    let mut tensors = HashMap::new();
    for (name, view) in st.iter() {
        let data = match view.dtype() {
            Dtype::F32 => RawData::F32(
                view.data()
                    .chunks_exact(4)
                    .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
                    .collect(),
            ),
            Dtype::F64 => RawData::F64(
                view.data()
                    .chunks_exact(8)
                    .map(|c| {
                        let mut a = [0u8; 8];
                        a.copy_from_slice(c);
                        f64::from_le_bytes(a)
                    })
                    .collect(),
            ),
            other => {
                return Err(fmt_err(format!(
                    "tensor `{name}` has dtype {other:?}, expected F32 or F64"
                )))
            }
        };
        let finite = match &data {
            RawData::F32(v) => v.iter().all(|x| x.is_finite()),
            RawData::F64(v) => v.iter().all(|x| x.is_finite()),
        };
        if !finite {
            return Err(fmt_err(format!("tensor `{name}` holds non-finite values")));
        }
        tensors.insert(
            name.to_string(),
            RawTensor {
                name: name.to_string(),
                shape: view.shape().to_vec(),
                data,
            },
        );
    }
    Ok(Checkpoint {
        path: path.to_path_buf(),
        state,
        tensors,
    })
}

/// The training config stored in the checkpoint in directory `dir`.
pub fn read_checkpoint_config(dir: &Path) -> Result<PpoConfig, PpoError> {
    Ok(read_checkpoint(&dir.join(CHECKPOINT_FILE))?.state.config)
}

impl Checkpoint {
    fn raw(&self, name: &str, shape: &[usize]) -> Result<&RawTensor, PpoError> {
        let t = self
            .tensors
            .get(name)
            .ok_or_else(|| PpoError::CheckpointFormat {
                path: self.path.clone(),
                message: format!("tensor `{name}` is missing"),
            })?;
        if t.shape != shape {
            return Err(PpoError::CheckpointShape {
                path: self.path.clone(),
                name: name.to_string(),
                expected: shape.to_vec(),
                found: t.shape.clone(),
            });
        }
        Ok(t)
    }

    /// The f32 tensor `name`, which must have shape `shape`.
    pub fn f32_tensor(&self, name: &str, shape: &[usize]) -> Result<Tensor, PpoError> {
        match &self.raw(name, shape)?.data {
            RawData::F32(v) => Ok(Tensor::from_vec(v.clone(), shape, &Device::Cpu)?),
            RawData::F64(_) => Err(PpoError::CheckpointFormat {
                path: self.path.clone(),
                message: format!("tensor `{name}` is F64, expected F32"),
            }),
        }
    }

    fn f64_values(&self, name: &str, shape: &[usize]) -> Result<Vec<f64>, PpoError> {
        match &self.raw(name, shape)?.data {
            RawData::F64(v) => Ok(v.clone()),
            RawData::F32(_) => Err(PpoError::CheckpointFormat {
                path: self.path.clone(),
                message: format!("tensor `{name}` is F32, expected F64"),
            }),
        }
    }

    /// Running statistics `prefix.{mean,var,count}` of dimension `dim`.
    pub fn rms(&self, prefix: &str, dim: usize) -> Result<RunningMeanStd, PpoError> {
        let mean = self.f64_values(&format!("{prefix}.mean"), &[dim])?;
        let var = self.f64_values(&format!("{prefix}.var"), &[dim])?;
        let count = self.f64_values(&format!("{prefix}.count"), &[1])?[0];
        if var.iter().any(|&v| v < 0.0) || count <= 0.0 {
            return Err(PpoError::CheckpointFormat {
                path: self.path.clone(),
                message: format!("`{prefix}` has a negative variance or a non-positive count"),
            });
        }
        Ok(RunningMeanStd { mean, var, count })
    }

    /// The values of every parameter of `params`, checked for presence and shape. Any other
    /// tensor outside the optimiser and normaliser namespaces is an error (a different
    /// architecture).
    pub fn policy_tensors(&self, params: &Params) -> Result<HashMap<String, Tensor>, PpoError> {
        let mut out = HashMap::new();
        for (name, v) in params.vars() {
            out.insert(name.clone(), self.f32_tensor(name, v.dims())?);
        }
        let mut extra: Vec<&str> = self
            .tensors
            .keys()
            .map(|s| s.as_str())
            .filter(|n| {
                !n.starts_with("optim.")
                    && !n.starts_with("obs_rms.")
                    && !n.starts_with("ret_rms.")
                    && !params.vars().contains_key(*n)
            })
            .collect();
        if !extra.is_empty() {
            extra.sort_unstable();
            return Err(PpoError::CheckpointMismatch {
                path: self.path.clone(),
                message: format!("unexpected parameters {extra:?} (a different network?)"),
            });
        }
        Ok(out)
    }
}

/// A trained policy loaded for acting (evaluation, deployment).
pub struct LoadedPolicy {
    /// The network with the checkpoint's weights.
    pub policy: Box<dyn ActorCritic>,
    /// The observation statistics it was trained with (`None` without `norm_obs`).
    pub obs_rms: Option<RunningMeanStd>,
    /// The training configuration.
    pub config: PpoConfig,
    /// Observation clip used with `obs_rms`.
    pub obs_clip: f64,
}

impl LoadedPolicy {
    /// Normalises raw observations as during training.
    pub fn normalize(&self, raw: &[f32]) -> Vec<f32> {
        match &self.obs_rms {
            Some(r) => r.normalize(raw, self.obs_clip),
            None => raw.to_vec(),
        }
    }
}

/// Loads the policy (and its observation normaliser) stored in the checkpoint in `dir`.
pub fn load_policy(dir: &Path) -> Result<LoadedPolicy, PpoError> {
    let ck = read_checkpoint(&dir.join(CHECKPOINT_FILE))?;
    let st = &ck.state;
    let policy = build_policy(&st.config.policy, st.obs_dim, st.action_spec, 0)?;
    let weights = ck.policy_tensors(policy.params())?;
    for (name, v) in policy.params().vars() {
        if let Some(t) = weights.get(name) {
            v.set(t)?;
        }
    }
    let obs_rms = if st.config.norm_obs {
        Some(ck.rms("obs_rms", st.obs_dim)?)
    } else {
        None
    };
    Ok(LoadedPolicy {
        policy,
        obs_rms,
        obs_clip: st.config.obs_clip,
        config: st.config.clone(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::Rng;

    /// The shipped checkpoint's bytes with the stored training config edited by `edit`.
    fn with_edited_config(edit: impl Fn(&mut serde_json::Value)) -> Vec<u8> {
        let path = Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("assets/policies/quick_gru_m3_pca5")
            .join(CHECKPOINT_FILE);
        let bytes = std::fs::read(path).unwrap();
        let n = u64::from_le_bytes(bytes[..8].try_into().unwrap()) as usize;
        let mut header: serde_json::Value = serde_json::from_slice(&bytes[8..8 + n]).unwrap();
        let meta = &mut header["__metadata__"][META_KEY];
        let mut state: serde_json::Value = serde_json::from_str(meta.as_str().unwrap()).unwrap();
        edit(&mut state["config"]);
        *meta = serde_json::Value::String(state.to_string());
        let header = serde_json::to_vec(&header).unwrap();
        let mut out = (header.len() as u64).to_le_bytes().to_vec();
        out.extend_from_slice(&header);
        out.extend_from_slice(&bytes[8 + n..]);
        out
    }

    #[test]
    fn an_out_of_range_stored_config_is_an_error_naming_the_file() {
        // Found by tests/fuzz_parsers.rs: a corrupted `init_lift_bias` surfaced from the
        // network builder without the file's name.
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join(CHECKPOINT_FILE);
        std::fs::write(&path, with_edited_config(|_| {})).unwrap();
        assert!(read_checkpoint(&path).is_ok(), "the unedited copy loads");
        std::fs::write(
            &path,
            with_edited_config(|c| c["policy"]["init_lift_bias"] = (-1.0e5).into()),
        )
        .unwrap();
        let text = read_checkpoint(&path).err().unwrap().to_string();
        assert!(text.contains(CHECKPOINT_FILE), "{text}");
        assert!(text.contains("init_lift_bias"), "{text}");
        std::fs::write(&path, with_edited_config(|c| c["gamma"] = 3.0.into())).unwrap();
        let text = load_policy(dir.path()).err().unwrap().to_string();
        assert!(
            text.contains(CHECKPOINT_FILE) && text.contains("gamma"),
            "{text}"
        );
    }

    #[test]
    fn rng_state_round_trips_exactly() {
        let mut a = ChaCha8Rng::seed_from_u64(77);
        a.set_stream(5);
        for _ in 0..13 {
            let _: u32 = a.random();
        }
        let s = RngState::capture(&a);
        let mut b = s.restore(Path::new("x")).unwrap();
        for _ in 0..10 {
            assert_eq!(a.random::<u64>(), b.random::<u64>());
        }
        let bad = RngState {
            seed: "zz".into(),
            ..s
        };
        assert!(bad.restore(Path::new("x")).is_err());
    }
}
