"""grasp_rl: the Shadow-hand grasping environment of the ``grasp`` crate (Rapier physics,
in Rust) for Python RL stacks.

* :class:`GraspEnv`: one environment, a ``gymnasium.Env``;
* :class:`GraspVectorEnv`: a config's environments stepped in parallel by Rust threads, a
  ``gymnasium.vector.VectorEnv``;
* :class:`Policy`: a checkpoint of ``grasp train`` (or the shipped one) acting on
  observations; :meth:`GraspEnv.run_baseline` runs the scripted baselines.

Importing registers ``grasp/ShadowGrasp-v0`` (``gymnasium.make`` gives a :class:`GraspEnv`,
``gymnasium.make_vec(..., vectorization_mode="vector_entry_point")`` a
:class:`GraspVectorEnv`), with the built-in defaults unless keyword arguments say
otherwise.
"""

import gymnasium

from . import _core
from .actions import action_space, observation_space
from .agents import Policy, run_episode
from .env import GraspEnv
from .vector import GraspVectorEnv

__version__ = _core.__version__

ENV_ID = "grasp/ShadowGrasp-v0"

__all__ = [
    "ENV_ID",
    "GraspEnv",
    "GraspVectorEnv",
    "Policy",
    "action_space",
    "builtin_config_toml",
    "observation_space",
    "run_episode",
]

builtin_config_toml = _core.builtin_config_toml

if ENV_ID not in gymnasium.registry:
    gymnasium.register(
        id=ENV_ID,
        entry_point="grasp_rl.env:GraspEnv",
        vector_entry_point="grasp_rl.vector:GraspVectorEnv",
    )
