"""stable-baselines3 PPO on grasp_rl, set up like `grasp train --config configs/quick.toml`.

    pip install ./python stable-baselines3
    python examples/python/sb3_ppo.py --config configs/quick.toml --minutes 10 \
        --out docs/results/python_2026_12/sb3_quick.csv

The environments are those of the config (objects, modality, synergies, curriculum), one
`grasp_rl.GraspEnv` per `num_envs` in SB3's DummyVecEnv (stepped one after another on one
thread), with SB3's VecNormalize in place of the crate's observation and reward
normalisation, and PPO's hyperparameters taken from the config's [ppo] table. The policy
is SB3's MLP (SB3 has no GRU; sb3-contrib's RecurrentPPO has an LSTM): [policy]
mlp_hidden x 2, log std initialised to [policy] init_log_std. The lift is the last entry
of the flat Box action (> 0 lifts).

Writes one CSV row per rollout: transitions, episodes, training success rate of the
episodes that ended in the rollout, mean return and length, curriculum level, wall time.

Runs from any directory: `--config` and `--out` are taken from the directory it is started
in (the default config is the repository's configs/quick.toml), then it works in the
repository root, where the paths inside the configs (synergy model, simulator config,
base files) are rooted, as for `grasp train`. Python 3.9 and 3.10 need
`pip install tomli` (3.11+ has tomllib).
"""

from __future__ import annotations

import argparse
import csv
import os
import time
from pathlib import Path

try:
    import tomllib  # Python 3.11+
except ModuleNotFoundError:  # Python 3.9, 3.10 (pyproject: >= 3.9)
    import tomli as tomllib

import numpy as np

import grasp_rl

# examples/python/sb3_ppo.py -> the repository root.
REPO = Path(__file__).resolve().parents[2]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--config", default=str(REPO / "configs" / "quick.toml"))
    ap.add_argument("--minutes", type=float, default=10.0, help="wall-clock budget")
    ap.add_argument("--timesteps", type=int, default=None, help="default: the config's")
    ap.add_argument("--seed", type=int, default=None, help="default: the config's")
    ap.add_argument("--out", default="sb3_ppo.csv")
    a = ap.parse_args()
    # The user's paths from where the script was started; the configs' own paths from
    # the repository root.
    a.config = str(Path(a.config).resolve())
    a.out = str(Path(a.out).resolve())
    os.chdir(REPO)

    import torch
    from stable_baselines3 import PPO
    from stable_baselines3.common.callbacks import BaseCallback
    from stable_baselines3.common.vec_env import DummyVecEnv, VecNormalize

    torch.set_num_threads(1)
    cfg = tomllib.loads(grasp_rl.GraspEnv(config=a.config, objects="box_sugar").config_toml)
    ppo, pol = cfg["ppo"], cfg["policy"]
    n = cfg["num_envs"]
    seed = cfg["seed"] if a.seed is None else a.seed
    venv = DummyVecEnv([lambda: grasp_rl.GraspEnv(config=a.config) for _ in range(n)])
    venv.seed(seed)
    venv = VecNormalize(
        venv,
        norm_obs=ppo["norm_obs"],
        norm_reward=ppo["norm_reward"],
        clip_obs=ppo["obs_clip"],
        clip_reward=ppo["reward_clip"],
        gamma=ppo["gamma"],
    )
    batch = n * ppo["num_steps"]
    model = PPO(
        "MlpPolicy",
        venv,
        learning_rate=ppo["learning_rate"],
        n_steps=ppo["num_steps"],
        batch_size=batch // ppo["num_minibatches"],
        n_epochs=ppo["update_epochs"],
        gamma=ppo["gamma"],
        gae_lambda=ppo["gae_lambda"],
        clip_range=ppo["clip_coef"],
        normalize_advantage=ppo["norm_adv"],
        ent_coef=ppo["ent_coef"],
        vf_coef=ppo["vf_coef"],
        max_grad_norm=ppo["max_grad_norm"],
        policy_kwargs=dict(
            net_arch=[pol["mlp_hidden"], pol["mlp_hidden"]],
            log_std_init=pol["init_log_std"],
        ),
        seed=seed,
        device="cpu",
        verbose=0,
    )

    class Log(BaseCallback):
        """One row per rollout, and the wall-clock budget."""

        def __init__(self) -> None:
            super().__init__()
            self.t0 = time.time()
            self.rows: list[dict] = []
            self.succ: list[bool] = []
            self.ret: list[float] = []
            self.len: list[int] = []
            self.level = 0.0

        def _on_step(self) -> bool:
            for info in self.locals["infos"]:
                self.level = info.get("curriculum_level", self.level)
                if "summary" in info:
                    ep = info["summary"]
                    self.succ.append(bool(ep["success"]))
                    self.ret.append(float(ep["episode_return"]))
                    self.len.append(int(ep["steps"]))
            return True

        def _on_rollout_end(self) -> None:
            row = {
                "update": len(self.rows) + 1,
                "global_step": self.num_timesteps,
                "episodes": (self.rows[-1]["episodes"] if self.rows else 0) + len(self.succ),
                "success_rate": float(np.mean(self.succ)) if self.succ else "",
                "episode_return": float(np.mean(self.ret)) if self.ret else "",
                "episode_length": float(np.mean(self.len)) if self.len else "",
                "curriculum_level": self.level,
                "wall_s": round(time.time() - self.t0, 1),
            }
            self.rows.append(row)
            self.succ, self.ret, self.len = [], [], []
            print(
                f"update {row['update']:>3}  steps {row['global_step']:>6}  "
                f"success {row['success_rate'] if row['success_rate'] == '' else round(row['success_rate'], 3)}  "
                f"wall {row['wall_s']} s",
                flush=True,
            )
            tmp = a.out + ".tmp"
            with open(tmp, "w", newline="") as f:
                w = csv.DictWriter(f, fieldnames=list(row))
                w.writeheader()
                w.writerows(self.rows)
            os.replace(tmp, a.out)
            if time.time() - self.t0 >= a.minutes * 60:
                self.model._grasp_budget_spent = True

        def _on_rollout_start(self) -> None:
            pass

    log = Log()

    class Budget(BaseCallback):
        def _on_step(self) -> bool:
            return not getattr(self.model, "_grasp_budget_spent", False)

    total = a.timesteps or cfg["total_timesteps"]
    model.learn(total_timesteps=total, callback=[log, Budget()])
    last = [r for r in log.rows if r["success_rate"] != ""][-10:]
    print(
        f"done: {log.rows[-1]['global_step']} transitions in {log.rows[-1]['wall_s']} s, "
        f"training success over the last {len(last)} updates "
        f"{np.mean([r['success_rate'] for r in last]):.3f}"
    )


if __name__ == "__main__":
    main()
