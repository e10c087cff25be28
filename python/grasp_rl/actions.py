"""The action and observation spaces of the grasping MDP and the encoding of actions for
the Rust core.

An action is ``k + 2`` continuous values and the lift decision rho, where ``k`` is the
number of synergy components (5 in the built-in config):

* ``action_format="box"`` (default, what stable-baselines3 and RLlib need):
  ``Box(-1, 1, (k + 3,), float32)``. Entries ``0..k`` are the synergy increments (eq. 2,
  in units of ``eps_scale`` standard deviations of each component), entries ``k`` and
  ``k + 1`` the two wrist increments (units of ``wrist_scale`` radians), and the last entry
  is the lift bit: the hand lifts (and the episode ends) when it is ``> 0``.
* ``action_format="dict"``: ``Dict(continuous=Box(-1, 1, (k + 2,)), lift=Discrete(2))``.

Continuous values outside [-1, 1] are clipped by the environment, as in ``grasp train``,
whose Gaussian policy samples unbounded values. Actions must be finite real numbers of
the right shape: anything else raises ``ValueError`` (shape, NaN, missing key) or
``TypeError`` (a non-numeric dtype).

Observations are ``Box(-inf, inf, (obs_dim,), float32)``: ``<a_{k-1}, phi, tau, theta>``
stacked over ``history`` frames (M3 with 5 synergies and 3 frames: 168 values); see the
docs/python.md.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from gymnasium import spaces

FORMATS = ("box", "dict")


def observation_space(obs_dim: int) -> spaces.Box:
    """The observation space: unbounded float32 vectors of length ``obs_dim``."""
    return spaces.Box(-np.inf, np.inf, (obs_dim,), np.float32)


def action_space(continuous: int, action_format: str) -> spaces.Space:
    """The action space for ``continuous`` components (synergies + 2 wrist) and the lift."""
    if action_format == "box":
        return spaces.Box(-1.0, 1.0, (continuous + 1,), np.float32)
    if action_format == "dict":
        return spaces.Dict(
            {
                "continuous": spaces.Box(-1.0, 1.0, (continuous,), np.float32),
                "lift": spaces.Discrete(2),
            }
        )
    raise ValueError(f"action_format {action_format!r}: expected one of {FORMATS}")


def _real_array(x: Any, what: str) -> np.ndarray:
    try:
        a = np.asarray(x)
    except Exception as e:  # ragged lists and the like
        raise ValueError(f"{what} is not an array of numbers: {e}") from None
    if a.dtype.kind not in "fiub":
        raise TypeError(f"{what} has dtype {a.dtype}: expected real numbers (float or int)")
    return a


def encode(action: Any, continuous: int, action_format: str, num_envs: int | None) -> bytes:
    """``action`` (one, or ``num_envs`` stacked) as the float32 rows the core reads:
    ``continuous`` values then the lift entry (> 0 lifts). Raises on a wrong shape, dtype or
    a non-finite value, naming it."""
    width = continuous + 1
    lead = () if num_envs is None else (num_envs,)
    if action_format == "dict":
        if not isinstance(action, dict) or set(action) != {"continuous", "lift"}:
            keys = sorted(action) if isinstance(action, dict) else type(action).__name__
            raise ValueError(
                f"a dict action needs exactly the keys 'continuous' and 'lift', got {keys}"
            )
        cont = _real_array(action["continuous"], "action['continuous']")
        lift = _real_array(action["lift"], "action['lift']")
        if cont.shape != lead + (continuous,):
            raise ValueError(
                f"action['continuous'] has shape {cont.shape}, expected {lead + (continuous,)}"
            )
        if lift.shape != lead:
            raise ValueError(f"action['lift'] has shape {lift.shape}, expected {lead}")
        if not np.all((lift == 0) | (lift == 1)):
            raise ValueError(f"action['lift'] must be 0 or 1, got {lift}")
        flat = np.concatenate(
            [
                cont.astype(np.float32).reshape(lead + (continuous,)),
                np.where(lift > 0, 1.0, -1.0).astype(np.float32).reshape(lead + (1,)),
            ],
            axis=-1,
        )
    else:
        flat = _real_array(action, "the action")
        if flat.shape != lead + (width,):
            raise ValueError(
                f"the action has shape {flat.shape}, expected {lead + (width,)} "
                f"({continuous} continuous components and the lift entry"
                + (f", for each of {num_envs} environments)" if num_envs else ")")
            )
    flat = np.ascontiguousarray(flat, dtype=np.float32)
    if not np.all(np.isfinite(flat)):
        bad = np.argwhere(~np.isfinite(flat))[0]
        raise ValueError(f"the action has a non-finite value at index {tuple(int(i) for i in bad)}")
    return flat.tobytes()
