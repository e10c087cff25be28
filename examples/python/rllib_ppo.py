"""Ray RLlib PPO on grasp_rl, rollouts spread over several worker processes.

    pip install ./python "ray[rllib]" torch
    python examples/python/rllib_ppo.py --workers 2 --envs-per-worker 2 --iterations 3

Each RLlib env runner is its own process holding `--envs-per-worker` grasp_rl.GraspEnv
instances (one simulator each); the learner runs in the driver. On one machine the
workers share its cores; on a Ray cluster the same script, started on the head node with
`ray.init(address="auto")` (`--address auto`), places the env runners on the cluster's
nodes: only `--workers` changes. The environment is the config's (`--config`, default the
built-in configs/base.toml recipe), PPO's hyperparameters are taken from its [ppo] table.

The config is read once, here, and its resolved text (`config_toml`) travels in the env
config, so no node needs the file (a relative path would be resolved in each worker's
own directory). `grasp_rl` must be installed on every node of the cluster. Python 3.9
and 3.10 need `pip install tomli` (3.11+ has tomllib).
"""

from __future__ import annotations

import argparse
import json
import time

try:
    import tomllib  # Python 3.11+
except ModuleNotFoundError:  # Python 3.9, 3.10 (pyproject: >= 3.9)
    import tomli as tomllib

import grasp_rl


def make_env(env_config: dict):
    import grasp_rl  # imported in each worker process

    # The config's text, not its path: the worker may run on another node.
    return grasp_rl.GraspEnv(
        config_toml=env_config["config_toml"],
        objects=env_config.get("objects"),
        difficulty=env_config.get("difficulty"),
    )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--config", default=None, help="a grasp training config (default: built-in)")
    ap.add_argument("--objects", default=None)
    ap.add_argument("--workers", type=int, default=2, help="env-runner processes")
    ap.add_argument("--envs-per-worker", type=int, default=2)
    ap.add_argument("--rollout", type=int, default=64, help="steps per env per iteration")
    ap.add_argument("--iterations", type=int, default=3)
    ap.add_argument("--address", default=None, help="a Ray cluster ('auto' on a head node)")
    a = ap.parse_args()

    import ray
    from ray.rllib.algorithms.ppo import PPOConfig
    from ray.tune.registry import register_env

    # Resolved here (base files merged, checked): the workers get this text.
    config_toml = grasp_rl.GraspEnv(config=a.config, objects="box_sugar").config_toml
    cfg = tomllib.loads(config_toml)
    ppo = cfg["ppo"]
    ray.init(address=a.address, include_dashboard=False, log_to_driver=False)
    register_env("grasp_rl", make_env)
    batch = a.workers * a.envs_per_worker * a.rollout
    config = (
        PPOConfig()
        .environment("grasp_rl", env_config={"config_toml": config_toml, "objects": a.objects})
        .env_runners(
            num_env_runners=a.workers,
            num_envs_per_env_runner=a.envs_per_worker,
            num_cpus_per_env_runner=1,
            rollout_fragment_length=a.rollout,
        )
        .learners(num_learners=0)
        .training(
            lr=ppo["learning_rate"],
            gamma=ppo["gamma"],
            lambda_=ppo["gae_lambda"],
            clip_param=ppo["clip_coef"],
            vf_loss_coeff=ppo["vf_coef"],
            entropy_coeff=ppo["ent_coef"],
            grad_clip=ppo["max_grad_norm"],
            train_batch_size_per_learner=batch,
            minibatch_size=batch // ppo["num_minibatches"],
            num_epochs=ppo["update_epochs"],
        )
        .debugging(seed=cfg["seed"])
    )
    algo = config.build_algo()
    t0 = time.time()
    for i in range(1, a.iterations + 1):
        r = algo.train()
        er = r.get("env_runners", {})
        print(
            json.dumps(
                {
                    "iteration": i,
                    "env_steps": er.get("num_env_steps_sampled_lifetime"),
                    "episodes": er.get("num_episodes_lifetime"),
                    "episode_return_mean": er.get("episode_return_mean"),
                    "episode_len_mean": er.get("episode_len_mean"),
                    "wall_s": round(time.time() - t0, 1),
                }
            ),
            flush=True,
        )
    algo.stop()
    ray.shutdown()


if __name__ == "__main__":
    main()
