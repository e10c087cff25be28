"""Random-agent throughput of grasp_rl's vector env, the Python twin of
`grasp bench env` (same environments, same agent: Gaussian continuous actions, lift with
probability 0.15 per step), so the two can be compared.

    python examples/python/throughput.py --envs 20 --threads 2 --seconds 20

`grasp bench env` builds its environments with the MDP's built-in settings (not
base.toml's recipe), the shipped synergy model (5 components), the built-in simulator
config and the `train` objects; `config_toml='name = "bench_env"'` resolves to exactly
that. Prints one JSON line like `grasp --json bench env`'s figures.
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np

import grasp_rl

RANDOM_LIFT_PROB = 0.15  # grasp::env::bench::RANDOM_LIFT_PROB


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--envs", type=int, default=20)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--seconds", type=float, default=20.0)
    ap.add_argument("--objects", default="train")
    ap.add_argument("--seed", type=int, default=0)
    a = ap.parse_args()
    v = grasp_rl.GraspVectorEnv(
        config_toml='name = "bench_env"',
        num_envs=a.envs,
        threads=a.threads,
        objects=a.objects,
        seed=a.seed,
    )
    k = v.single_action_space.shape[0] - 1
    rng = np.random.default_rng(a.seed)
    start = time.perf_counter()
    v.reset(seed=a.seed)
    steps = episodes = 0
    while time.perf_counter() - start < a.seconds:
        act = np.empty((a.envs, k + 1), np.float32)
        act[:, :k] = rng.standard_normal((a.envs, k))
        act[:, k] = np.where(rng.random(a.envs) < RANDOM_LIFT_PROB, 1.0, -1.0)
        _, _, term, trunc, _ = v.step(act)
        steps += a.envs
        episodes += int(np.count_nonzero(term | trunc))
    wall = time.perf_counter() - start
    print(
        json.dumps(
            {
                "envs": a.envs,
                "threads": v.threads,
                "objects": a.objects,
                "env_steps": steps,
                "episodes": episodes,
                "wall_s": round(wall, 3),
                "env_steps_per_s": steps / wall,
                "episodes_per_s": episodes / wall,
            }
        )
    )


if __name__ == "__main__":
    main()
