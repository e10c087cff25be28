//! Training on the procedural object stream ([`crate::objects::stream`]): each
//! environment builds a fresh stream object every `reuse` episodes, its index drawn from
//! the episode's seed, so a run is reproducible and never sees the same object twice in
//! practice (indices are drawn from 2^32 - 2^20 values).
//!
//! Indices below 2^20 are never drawn: the finite `procedural` set that evaluation uses
//! (the first objects of stream seed 0) stays out of training.
//!
//! Building an object costs its convex decomposition (VHACD for non-convex meshes,
//! computed in memory, nothing cached on disk); `reuse` spreads that cost over several
//! episodes (`grasp bench env --objects procedural` measures it).

use crate::objects::sets::BuildContext;
use crate::objects::stream::{name, stream_prepared};
use crate::sim::ObjectSpec;
use rand::Rng;
use serde::{Deserialize, Serialize};

/// Smallest index the training stream draws.
pub const FIRST_TRAINING_INDEX: u64 = 1 << 20;

/// Draws rejected (objects that fail to build) before an environment keeps its object.
const MAX_TRIES: usize = 4;

/// Settings of the training stream.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct StreamConfig {
    /// Stream seed of the objects.
    pub seed: u64,
    /// Episodes each environment runs on one object before it builds the next.
    pub reuse: usize,
}

impl Default for StreamConfig {
    fn default() -> Self {
        StreamConfig { seed: 0, reuse: 4 }
    }
}

/// One environment's view of the stream.
#[derive(Debug, Clone)]
pub struct ObjectStream {
    cfg: StreamConfig,
    episodes: usize,
    ctx: BuildContext,
}

impl ObjectStream {
    /// A stream with `cfg` (`reuse` of 0 counts as 1).
    pub fn new(cfg: StreamConfig) -> Self {
        ObjectStream {
            cfg,
            episodes: 0,
            ctx: BuildContext::uncached(),
        }
    }

    /// Object `index` of the stream, ready for the simulator.
    pub fn object(&self, index: u64) -> Result<(String, ObjectSpec), String> {
        let name = name(self.cfg.seed, index);
        let o = stream_prepared(self.cfg.seed, index)
            .and_then(|p| p.finish(&self.ctx))
            .map_err(|e| format!("{name}: {e}"))?;
        let s = ObjectSpec::from_object(&o).map_err(|e| format!("{name}: {e}"))?;
        Ok((name, s))
    }

    /// The object an environment starts on before its first reset draws one (the first
    /// index training may draw): `GraspEnv::new` needs an object to build its simulator.
    pub fn first_object(&self) -> Result<(String, ObjectSpec), String> {
        self.object(FIRST_TRAINING_INDEX)
    }

    /// Called at each episode's reset: every `reuse` episodes, a new object whose index is
    /// drawn from `rng`; `None` while the current object is kept (or when no draw built).
    pub fn next(&mut self, rng: &mut impl Rng) -> Option<(String, ObjectSpec)> {
        let due = self.episodes.is_multiple_of(self.cfg.reuse.max(1));
        self.episodes += 1;
        if !due {
            return None;
        }
        (0..MAX_TRIES).find_map(|_| {
            let index = rng.random_range(FIRST_TRAINING_INDEX..1u64 << 32);
            self.object(index).ok()
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    #[test]
    fn a_new_object_every_reuse_episodes_and_the_same_from_the_same_seed() {
        let mut s = ObjectStream::new(StreamConfig { seed: 0, reuse: 2 });
        let mut rng = ChaCha8Rng::seed_from_u64(4);
        let first = s.next(&mut rng).expect("a first object");
        assert!(s.next(&mut rng).is_none());
        let second = s.next(&mut rng).expect("a new object after 2 episodes");
        assert_ne!(first.0, second.0);
        let idx = crate::objects::stream::parse_name(&first.0).unwrap().1;
        assert!(idx >= FIRST_TRAINING_INDEX);
        let mut again = ObjectStream::new(StreamConfig { seed: 0, reuse: 2 });
        let repeat = again.next(&mut ChaCha8Rng::seed_from_u64(4)).unwrap();
        assert_eq!(repeat.0, first.0);
        // Rebuilt parts are new storage (ConvexParts compares by identity): compare values.
        assert_eq!(repeat.1.mass, first.1.mass);
        assert_eq!(repeat.1.friction, first.1.friction);
        assert_eq!(repeat.1.shape.half_extents(), first.1.shape.half_extents());
    }
}
