"""``GraspVectorEnv``: the environments of a training config stepped together by the
crate's rayon ``VecEnv`` (the GIL is released while they step), as a
``gymnasium.vector.VectorEnv`` with same-step autoreset.
"""

from __future__ import annotations

import os
from typing import Any

import numpy as np
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space

from . import _core
from .actions import action_space, encode, observation_space
from .env import _path


class GraspVectorEnv(VectorEnv):
    """``num_envs`` grasping environments built exactly as ``grasp train`` builds them.

    Args:
        config, objects, difficulty, action_format, config_toml: as :class:`GraspEnv`.
        num_envs: environments (default: the config's ``num_envs``; 20 built in).
        threads: threads of the environment pool (default: the config's ``threads``, else
            the available cores).
        seed: the base seed of the first ``reset()`` without a seed (default: the
            config's ``seed``).

    Episodes end and restart on the same step (``AutoresetMode.SAME_STEP``): the
    observation returned for an environment whose episode ended is the next episode's
    first; the last one is in ``infos["final_obs"]`` and that step's info in
    ``infos["final_info"]``. Episode ``k`` of environment ``i`` after ``reset(seed=s)``
    has episode seed ``episode_seed(s, i, k)``, as in the Rust ``VecEnv``: results do not
    depend on the thread count. ``reset(seed=s)`` also empties the curriculum windows.

    ``infos`` (arrays with gymnasium's ``_key`` masks): ``curriculum_level`` (float),
    ``object`` (str: the object of each environment's episode in progress, the next one's
    where an episode ended), ``physics_failure`` (bool), ``success`` and ``is_success``
    (bool, valid where ``infos["_success"]``: the environments whose episode ended),
    ``summary`` (the ended episodes' summary dicts, as :class:`GraspEnv`'s), and with
    ended episodes ``final_obs``, ``final_info`` (``object``: the ended episode's,
    ``success``, ``is_success``, ``physics_failure``, ``summary``) and ``episode``
    (``r``: return, ``l``: steps, as gymnasium's RecordEpisodeStatistics).
    """

    metadata = {"autoreset_mode": AutoresetMode.SAME_STEP, "render_modes": []}

    def __init__(
        self,
        config: str | os.PathLike | None = None,
        num_envs: int | None = None,
        threads: int | None = None,
        seed: int | None = None,
        objects: str | None = None,
        difficulty: float | None = None,
        action_format: str = "box",
        config_toml: str | None = None,
        render_mode: str | None = None,
    ) -> None:
        if render_mode is not None:
            raise ValueError(f"render_mode {render_mode!r}: GraspVectorEnv does not render")
        self.action_format = action_format
        self._core = _core.CoreVecEnv(
            config=_path(config),
            objects=objects,
            num_envs=num_envs,
            threads=threads,
            seed=seed,
            difficulty=difficulty,
            config_toml=config_toml,
        )
        self.num_envs = self._core.num_envs
        self.single_observation_space = observation_space(self._core.obs_dim)
        self.single_action_space = action_space(self._core.continuous, action_format)
        self.observation_space = batch_space(self.single_observation_space, self.num_envs)
        self.action_space = batch_space(self.single_action_space, self.num_envs)
        self._resets = 0
        self._started = False

    @property
    def config_toml(self) -> str:
        """The resolved training config (TOML)."""
        return self._core.config_toml

    @property
    def threads(self) -> int:
        """Threads of the environment pool."""
        return self._core.threads

    def _levels(self, raw: bytes | None = None) -> np.ndarray:
        return np.frombuffer(
            raw if raw is not None else self._core.curriculum_levels(), dtype=np.float64
        ).copy()

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[np.ndarray, dict[str, Any]]:
        if options:
            raise ValueError(f"unknown reset options {sorted(options)}: GraspVectorEnv takes none")
        if seed is not None and not isinstance(seed, (int, np.integer)):
            raise ValueError(
                f"seed must be one int (the base seed of every environment), got {seed!r}"
            )
        if seed is not None:
            if seed < 0:
                raise ValueError(f"seed must be non-negative, got {seed}")
            super().reset(seed=int(seed))
            base = int(seed)
        elif self._resets == 0:
            base = self._core.seed
        else:
            ss = np.random.SeedSequence([self._core.seed, self._resets])
            base = int(ss.generate_state(1, np.uint64)[0])
        self._resets += 1
        raw = self._core.reset(base, seed is not None)
        self._started = True
        obs = np.frombuffer(raw, dtype=np.float32).reshape(self.num_envs, -1).copy()
        return obs, {
            "curriculum_level": self._levels(),
            "_curriculum_level": np.ones(self.num_envs, bool),
            "object": self._objects(),
            "_object": np.ones(self.num_envs, bool),
        }

    def _objects(self) -> np.ndarray:
        out = np.empty(self.num_envs, dtype=object)
        out[:] = self._core.episode_objects()
        return out

    def step(
        self, actions: Any
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, dict[str, Any]]:
        if not self._started:
            raise RuntimeError("step() before reset(): call reset() first")
        raw = encode(actions, self._core.continuous, self.action_format, self.num_envs)
        (obs, rew, term, trunc, succ, fail, ended), levels = self._core.step(raw)
        n = self.num_envs
        obs = np.frombuffer(obs, dtype=np.float32).reshape(n, -1).copy()
        rewards = np.frombuffer(rew, dtype=np.float32).astype(np.float64)
        terminated = np.frombuffer(term, dtype=np.uint8).astype(bool)
        truncated = np.frombuffer(trunc, dtype=np.uint8).astype(bool)
        success = np.frombuffer(succ, dtype=np.int8)
        failure = np.frombuffer(fail, dtype=np.uint8).astype(bool)
        all_envs = np.ones(n, bool)
        infos: dict[str, Any] = {
            "curriculum_level": self._levels(levels),
            "_curriculum_level": all_envs,
            "object": self._objects(),
            "_object": all_envs.copy(),
            "physics_failure": failure,
            "_physics_failure": all_envs.copy(),
            "success": success == 1,
            "_success": success >= 0,
            "is_success": success == 1,
            "_is_success": success >= 0,
        }
        if ended:
            done = np.zeros(n, bool)
            final_obs = np.full(n, None, dtype=object)
            summary = np.full(n, None, dtype=object)
            ended_object = np.full(n, None, dtype=object)
            ret = np.zeros(n)
            length = np.zeros(n, dtype=np.int64)
            for i, last, rec in ended:
                done[i] = True
                final_obs[i] = np.frombuffer(last, dtype=np.float32).copy()
                ret[i] = rec.get("episode_return", 0.0)
                length[i] = rec.get("steps", 0)
                summary[i] = rec.get("summary")
                if summary[i] is not None:
                    ended_object[i] = summary[i]["object"]
            infos["summary"] = summary
            infos["_summary"] = done.copy()
            infos["final_obs"] = final_obs
            infos["_final_obs"] = done
            infos["final_info"] = {
                "object": ended_object,
                "_object": done.copy(),
                "success": success == 1,
                "_success": done & (success >= 0),
                "is_success": success == 1,
                "_is_success": done & (success >= 0),
                "physics_failure": failure,
                "_physics_failure": done.copy(),
                "summary": summary,
                "_summary": done.copy(),
            }
            infos["_final_info"] = done.copy()
            infos["episode"] = {"r": ret, "l": length, "_r": done.copy(), "_l": done.copy()}
            infos["_episode"] = done.copy()
        return obs, rewards, terminated, truncated, infos
