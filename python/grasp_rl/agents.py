"""Agents to compare against: a trained checkpoint acting on observations, and the
scripted baselines (which act inside the simulator, see ``GraspEnv.run_baseline``)."""

from __future__ import annotations

import os
from typing import Any

import numpy as np

from . import _core


class Policy:
    """A checkpoint trained by ``grasp train`` (a ``checkpoints/latest`` or ``best``
    folder), acting as ``grasp eval`` runs it: observations normalised with the statistics
    saved in the checkpoint, the GRU state carried across steps (call :meth:`reset` at each
    episode start), the distribution's mode (or, with ``stochastic``, a seeded sample).

    :meth:`act` returns a flat action for ``GraspEnv(action_format="box")``: the
    continuous components, then the lift entry (1.0 lifts, -1.0 does not). Build the
    environment the policy was trained for with ``GraspEnv(config_toml=policy.config_toml)``.
    """

    def __init__(self, path: str | os.PathLike, stochastic: bool = False, seed: int = 0):
        self._core = _core.CorePolicy(os.fspath(path), stochastic, seed)

    @classmethod
    def shipped(cls, stochastic: bool = False, seed: int = 0) -> "Policy":
        """The shipped policy ``assets/policies/fig5_gru_m3_pca8`` (embedded in the module; ``grasp run``'s default)."""
        p = cls.__new__(cls)
        p._core = _core.CorePolicy.shipped(stochastic, seed)
        return p

    @property
    def obs_dim(self) -> int:
        return self._core.obs_dim

    @property
    def config_toml(self) -> str:
        """The training config saved beside the checkpoint."""
        return self._core.config_toml

    def reset(self) -> None:
        """Forget the recurrent state (call at the start of every episode)."""
        self._core.reset()

    def act(self, obs: Any) -> np.ndarray:
        """The action for one observation (shape ``(obs_dim,)``)."""
        x = np.asarray(obs)
        if x.dtype.kind not in "fiu":
            raise TypeError(f"the observation has dtype {x.dtype}: expected real numbers")
        if x.shape != (self.obs_dim,):
            raise ValueError(f"the observation has shape {x.shape}, expected ({self.obs_dim},)")
        raw = self._core.act(np.ascontiguousarray(x, dtype=np.float32).tobytes())
        return np.frombuffer(raw, dtype=np.float32).copy()


def run_episode(env, agent: Policy, scene_seed: int) -> dict[str, Any]:
    """Runs ``agent`` for one episode on the scene of ``scene_seed`` in ``env`` (a
    :class:`GraspEnv` with the box action format) and returns the episode summary, as
    ``env.run_baseline(which, scene_seed)`` does for a baseline."""
    agent.reset()
    obs, _ = env.reset(options={"scene_seed": scene_seed})
    while True:
        obs, _, terminated, truncated, info = env.step(agent.act(obs))
        if terminated or truncated:
            return info["summary"]
