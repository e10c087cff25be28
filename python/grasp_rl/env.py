"""``GraspEnv``: one Shadow-hand grasping environment as a ``gymnasium.Env``.

An episode: the object is drawn from the config's set and placed by the curriculum
(eq. 6), the hand closes along the human-like trajectory until a fingertip touches
(stage 1, inside ``reset``), then each ``step`` applies one 0.2 s control step of synergy
and wrist increments, or lifts and judges the grasp, which ends the episode
(``terminated``). After ``max_steps`` control steps the hand lifts (``at_max_steps =
"lift"``, the built-in setting) or the episode fails. Episodes are never truncated.
"""

from __future__ import annotations

import os
from typing import Any

import gymnasium as gym
import numpy as np

from . import _core
from .actions import action_space, encode, observation_space


def _path(config: str | os.PathLike | None) -> str | None:
    return None if config is None else os.fspath(config)


class GraspEnv(gym.Env):
    """The grasping MDP of ``grasp train`` for one hand.

    Args:
        config: a training config file (``configs/quick.toml``, ``configs/gru_m1_pca5.toml``,
            ...), resolved as ``grasp train`` resolves it: modality, history, synergy model
            and components, simulator config, action scales, curriculum, randomisation and
            the object set. ``None``: the built-in defaults (``configs/base.toml``, embedded).
        objects: overrides the config's object set: ``train``, ``unseen``, ``all``,
            ``primitives``, ``procedural`` (the endless stream), a folder of OBJ/STL files,
            a manifest, or comma-separated names.
        difficulty: a fixed curriculum level r_s in [0, 1] (the curriculum off), as
            ``grasp eval --difficulty``; ``None`` keeps the config's curriculum.
        action_format: ``"box"`` (flat, last entry > 0 lifts) or ``"dict"``; see
            :mod:`grasp_rl.actions`.
        config_toml: config text instead of a file (e.g. ``Policy.config_toml``).

    Seeding: ``reset(seed=s)`` reseeds the environment and empties the curriculum window,
    so it always gives the same episode; ``reset()`` continues the seed sequence and the
    curriculum. ``reset(options={"scene_seed": n})`` runs the scene of episode seed ``n``
    exactly (the one ``run_baseline(which, n)`` and ``grasp eval`` use for that seed).

    ``info`` keys: ``curriculum_level`` (r_s of eq. 6 that placed this episode's object),
    ``object`` (its name), ``physics_failure`` (the simulation failed and the episode was
    cut short: the learner should not bootstrap from it); at the end of an episode also
    ``success`` and ``is_success`` (the object was held after the lift) and ``summary``
    (the summary: object, success, steps, episode_return, lifted, physics_failure,
    touched_in_stage1, thumb_contact_at_lift, grip_effort, object_height: the object's
    lowest point above the table when the lift was judged, in_hand: it touched the hand then,
    object_turn: how far it turned during the lift, rad).
    """

    metadata = {"render_modes": []}

    def __init__(
        self,
        config: str | os.PathLike | None = None,
        objects: str | None = None,
        difficulty: float | None = None,
        action_format: str = "box",
        config_toml: str | None = None,
        render_mode: str | None = None,
    ) -> None:
        if render_mode is not None:
            raise ValueError(f"render_mode {render_mode!r}: GraspEnv does not render")
        self.action_format = action_format
        self._core = _core.CoreEnv(
            config=_path(config), objects=objects, difficulty=difficulty, config_toml=config_toml
        )
        self.observation_space = observation_space(self._core.obs_dim)
        self.action_space = action_space(self._core.continuous, action_format)

    @property
    def config_toml(self) -> str:
        """The resolved training config (TOML, every default filled in)."""
        return self._core.config_toml

    @property
    def object_names(self) -> list[str]:
        """The objects episodes are drawn from."""
        return self._core.object_names

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[np.ndarray, dict[str, Any]]:
        super().reset(seed=seed)
        options = options or {}
        unknown = set(options) - {"scene_seed"}
        if unknown:
            raise ValueError(f"unknown reset options {sorted(unknown)}: expected 'scene_seed'")
        scene = options.get("scene_seed")
        if scene is None:
            scene = int(self.np_random.integers(0, 2**63))
        elif not isinstance(scene, (int, np.integer)) or scene < 0:
            raise ValueError(f"scene_seed must be a non-negative int, got {scene!r}")
        raw = self._core.reset(int(scene), seed is not None)
        obs = np.frombuffer(raw, dtype=np.float32).copy()
        return obs, {
            "curriculum_level": self._core.curriculum_level,
            "object": self._core.episode_object,
        }

    def step(self, action: Any) -> tuple[np.ndarray, float, bool, bool, dict[str, Any]]:
        raw = encode(action, self._core.continuous, self.action_format, None)
        obs, reward, terminated, truncated, success, failure, summary = self._core.step(raw)
        info: dict[str, Any] = {
            "curriculum_level": self._core.curriculum_level,
            "object": self._core.episode_object,
            "physics_failure": failure,
        }
        if success is not None:
            info["success"] = success
            info["is_success"] = success
        if summary is not None:
            info["summary"] = summary
        return (
            np.frombuffer(obs, dtype=np.float32).copy(),
            float(reward),
            terminated,
            truncated,
            info,
        )

    def run_baseline(self, which: int, scene_seed: int) -> dict[str, Any]:
        """Runs scripted baseline ``which`` (1: all fingers close in position mode; 2: the
        same, FF, MF and RF stop at contact) on the scene of ``scene_seed`` and returns the
        episode summary. ``reset(options={"scene_seed": scene_seed})`` gives a policy the
        same object and start pose. Ends the current episode."""
        return self._core.run_baseline(int(which), int(scene_seed))
