#!/usr/bin/env python3
"""Pools the tables of this folder: per agent, set and path (the robot path on the sim
and mujoco backends, `grasp eval --pregrasp antipodal` in Rapier) the successes over
scene seeds 0-2, the trial errors by kind, and exact McNemar tests on paired trials
(the same object, trial index and scene seed). Usage: summary.py [PREFIX_OF_MUJOCO_FILES] [--per-object]"""
import json, math, re, sys, collections, pathlib

HERE = pathlib.Path(__file__).parent
ARGS = [a for a in sys.argv[1:] if not a.startswith("--")]
MJ = ARGS[0] if ARGS else "mujoco_v2"
PATHS = {"robot path, Rapier": "sim", "robot path, MuJoCo": MJ, "grasp eval, Rapier": "eval"}
SETS = ["unseen", "novel"]
SEEDS = [0, 1, 2]
NAMES = {"assets/policies/fig5_gru_m3_pca8": "8-synergy agent (default)",
         "Baseline 1": "baseline 1", "Baseline 2": "baseline 2"}


def mcnemar(b, c):
    n = b + c
    if n == 0:
        return 1.0
    k = min(b, c)
    p = 2 * sum(math.comb(n, i) for i in range(k + 1)) / 2 ** n
    return min(1.0, p)


def load(prefix, s, seed):
    f = HERE / f"{prefix}_{s}_seed{seed}.json"
    return {a["agent"]: a for a in json.load(open(f))} if f.exists() else None


def outcomes(prefix, s, agent):
    out = {}
    for seed in SEEDS:
        d = load(prefix, s, seed)
        if d is None or agent not in d:
            return None
        for o in d[agent]["objects"]:
            for t, ok in enumerate(o["outcomes"]):
                out[(seed, o["object"], t)] = ok
    return out


def errors(prefix, s, agent):
    c = collections.Counter()
    for seed in SEEDS:
        d = load(prefix, s, seed)
        if d is None or agent not in d:
            continue
        for e in d[agent].get("trial_errors", []):
            m = re.search(r"joint (\w+) at [-\d.]+ rad is outside its limits", e["reason"])
            c[f"{m.group(1)} past its limit" if m else e["reason"][:70]] += 1
    return c


for s in ([] if "--per-object" in sys.argv else SETS):
    print(f"\n## {s}\n")
    print("| agent | " + " | ".join(PATHS) + " |")
    print("|---|" + "---|" * len(PATHS))
    for agent, name in NAMES.items():
        cells = []
        for p in PATHS.values():
            o = outcomes(p, s, agent)
            if o is None:
                cells.append("-")
                continue
            k, n = sum(o.values()), len(o)
            fails = sum(load(p, s, seed)[agent]["physics_failures"] for seed in SEEDS)
            cells.append(f"{100 * k / n:.1f} % ({k}/{n}, {fails} physics failures)")
        print(f"| {name} | " + " | ".join(cells) + " |")
    print()
    for agent, name in NAMES.items():
        for (la, pa), (lb, pb) in [(("Rapier robot path", "sim"), ("MuJoCo robot path", MJ)),
                                   (("Rapier eval", "eval"), ("Rapier robot path", "sim")),
                                   (("Rapier eval", "eval"), ("MuJoCo robot path", MJ))]:
            a, b = outcomes(pa, s, agent), outcomes(pb, s, agent)
            if a is None or b is None:
                continue
            only_a = sum(1 for k in a if a[k] and not b[k])
            only_b = sum(1 for k in a if b[k] and not a[k])
            print(f"- {name}: {la} vs {lb}: only the first {only_a}, only the second "
                  f"{only_b}, exact McNemar p = {mcnemar(only_a, only_b):.3g}")
    for agent, name in NAMES.items():
        e = errors(MJ, s, agent)
        if e:
            print(f"- {name}, MuJoCo trial errors: " + ", ".join(f"{k} {v}" for k, v in e.most_common()))
        e = errors("sim", s, agent)
        if e:
            print(f"- {name}, Rapier robot-path trial errors: " + ", ".join(f"{k} {v}" for k, v in e.most_common()))
    # The agents against each other in MuJoCo.
    pol = outcomes(MJ, s, "assets/policies/fig5_gru_m3_pca8")
    for b in ["Baseline 1", "Baseline 2"]:
        o = outcomes(MJ, s, b)
        if pol is None or o is None:
            continue
        x = sum(1 for k in pol if pol[k] and not o[k])
        y = sum(1 for k in pol if o[k] and not pol[k])
        print(f"- MuJoCo: 8-synergy agent vs {NAMES[b]}: {x} vs {y}, p = {mcnemar(x, y):.3g}")


def per_object(s):
    """Per-object successes over seeds 0-2 (30 trials), agent by agent, path by path."""
    cols = [("Rapier eval", "eval"), ("Rapier robot", "sim"), ("MuJoCo v1", "mujoco_v1"), ("MuJoCo", MJ)]
    agents = list(NAMES)
    head = ["object"] + [f"{NAMES[a].split(' (')[0]}: {c}" for a in agents for c, _ in cols]
    rows = collections.OrderedDict()
    for a in agents:
        for _, p in cols:
            for seed in SEEDS:
                d = load(p, s, seed)
                for o in d[a]["objects"]:
                    r = rows.setdefault(o["object"], collections.Counter())
                    r[(a, p)] += o["successes"]
    print(f"\n### {s}: successes of 30 trials per object (scene seeds 0-2)\n")
    print("| " + " | ".join(head) + " |")
    print("|---|" + "---:|" * (len(head) - 1))
    for name, r in rows.items():
        print(f"| {name} | " + " | ".join(str(r[(a, p)]) for a in agents for _, p in cols) + " |")


if "--per-object" in sys.argv:
    for s in SETS:
        per_object(s)
