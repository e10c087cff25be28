//! The one simulator config every agent of an evaluation runs in: one physics for all
//! agents keeps them comparable.

use super::EvalError;
use crate::sim::SimConfig;
use std::path::Path;

/// A simulator config file's name in messages: its path, or "the built-in one".
fn label(p: Option<&Path>) -> String {
    p.map_or("the built-in one".to_string(), |p| p.display().to_string())
}

/// The simulator config of an evaluation whose checkpoints were trained with `trained`
/// (checkpoint folder, its simulator config file; `None`: the built-in one):
/// - `flag` (`--sim-config`: its path and config) when given, with a warning for each
///   checkpoint trained with another;
/// - else the one the checkpoints were trained with: refused when they differ, and the
///   built-in one, with a warning, for a file that cannot be read here;
/// - else the built-in one.
///
/// `warn` receives each warning. The second value says where a config other than the
/// built-in one came from, when the checkpoints chose it.
pub fn common_sim_config(
    flag: Option<(&Path, SimConfig)>,
    trained: &[(&Path, Option<&Path>)],
    warn: &mut dyn FnMut(String),
) -> Result<(SimConfig, Option<String>), EvalError> {
    if let Some((p, cfg)) = flag {
        for (dir, t) in trained {
            if !SimConfig::load_or_default(*t).is_ok_and(|c| c == cfg) {
                warn(format!(
                    "checkpoint {} was trained with simulator config {}; evaluating it with \
                     --sim-config {}",
                    dir.display(),
                    label(*t),
                    p.display()
                ));
            }
        }
        return Ok((cfg, None));
    }
    let mut chosen: Option<(SimConfig, Option<&Path>, &Path)> = None;
    for (dir, t) in trained {
        let cfg = match SimConfig::load_or_default(*t) {
            Ok(c) => c,
            Err(e) => {
                warn(format!(
                    "checkpoint {} was trained with simulator config {}, which cannot be \
                     read here ({e:#}): evaluating with the built-in one (pass --sim-config \
                     to choose)",
                    dir.display(),
                    label(*t)
                ));
                SimConfig::default()
            }
        };
        match &chosen {
            None => chosen = Some((cfg, *t, dir)),
            Some((c, first, first_dir)) if *c != cfg => {
                return Err(EvalError::Physics(format!(
                    "checkpoints {} and {} were trained with different simulator configs ({} \
                     and {}): pass --sim-config to evaluate them in one",
                    first_dir.display(),
                    dir.display(),
                    label(*first),
                    label(*t)
                )))
            }
            Some(_) => {}
        }
    }
    Ok(match chosen {
        Some((cfg, t, dir)) if cfg != SimConfig::default() => {
            let note = format!(
                "simulator config: {}, as checkpoint {} was trained with",
                label(t),
                dir.display()
            );
            (cfg, Some(note))
        }
        Some((cfg, _, _)) => (cfg, None),
        None => (SimConfig::default(), None),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_flag_wins_and_differing_trained_configs_are_refused() {
        let dir = tempfile::tempdir().unwrap();
        let other =
            Path::new(env!("CARGO_MANIFEST_DIR")).join("configs/levers/sim_rapier_rows.toml");
        let other_cfg = SimConfig::load_or_default(Some(&other)).unwrap();
        assert_ne!(other_cfg, SimConfig::default());
        let (a, b) = (Path::new("ck_a"), Path::new("ck_b"));
        let mut warnings = Vec::new();
        // No checkpoint: the built-in one, silently.
        let (c, note) = common_sim_config(None, &[], &mut |w| warnings.push(w)).unwrap();
        assert_eq!((c, note), (SimConfig::default(), None));
        // One trained with another file: that one, with a note naming it.
        let (c, note) =
            common_sim_config(None, &[(a, Some(&other))], &mut |w| warnings.push(w)).unwrap();
        assert_eq!(c, other_cfg);
        assert!(note.unwrap().contains("sim_rapier_rows.toml"));
        // Two that differ: refused, naming both.
        let e = common_sim_config(None, &[(a, Some(&other)), (b, None)], &mut |w| {
            warnings.push(w)
        })
        .unwrap_err()
        .to_string();
        assert!(
            e.contains("ck_a") && e.contains("ck_b") && e.contains("--sim-config"),
            "{e}"
        );
        assert!(warnings.is_empty());
        // The flag: a warning for the checkpoint trained with another.
        let (c, _) = common_sim_config(
            Some((Path::new("flag.toml"), SimConfig::default())),
            &[(a, Some(&other)), (b, None)],
            &mut |w| warnings.push(w),
        )
        .unwrap();
        assert_eq!(c, SimConfig::default());
        assert_eq!(warnings.len(), 1);
        assert!(warnings[0].contains("ck_a") && warnings[0].contains("flag.toml"));
        // A file that cannot be read: the built-in one, with a warning.
        warnings.clear();
        let missing = dir.path().join("missing.toml");
        let (c, _) =
            common_sim_config(None, &[(a, Some(&missing))], &mut |w| warnings.push(w)).unwrap();
        assert_eq!(c, SimConfig::default());
        assert!(warnings[0].contains("cannot be read here"), "{warnings:?}");
    }
}
