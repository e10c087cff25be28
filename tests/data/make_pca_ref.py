#!/usr/bin/env python3
"""Regenerates the scikit-learn reference fixture for the PCA agreement test.

Usage (needs numpy and scikit-learn; the Rust tests never run this script, they only
read the two committed files it writes):

    python3 tests/data/make_pca_ref.py

Writes, next to this script:
- pca_ref_input.csv: 200 postures x 22 finger joints (radians, lh_ names in the synergy
  order FF(4), MF(4), RF(4), LF(5), TH(5)) plus an ignored "object" column. The data are
  a feasible mid-range posture plus 5 latent factors with distinct scales plus per-joint
  noise with distinct scales, so every eigenvalue is well separated and the components
  are well conditioned.
- pca_ref_sklearn.json: sklearn.decomposition.PCA (svd_solver="full", all 22
  components) fitted on those rows: explained_variance_, explained_variance_ratio_,
  mean_ and abs(components_) (signs are arbitrary in both implementations).

Floats are written with repr(), the shortest round-trip form, so Rust reads the exact
same numbers.
"""
import json
import os

import numpy as np
import sklearn
from sklearn.decomposition import PCA

# Finger joint limits (lower, upper) of the Shadow hand, shared/ROBOT.md, synergy order.
J4 = (-0.3491, 0.3491)
J3 = (-0.2618, 1.5708)
J21 = (0.0, 1.5708)
LIMITS = (
    [J4, J3, J21, J21] * 3
    + [(0.0, 0.7854), J4, J3, J21, J21]
    + [(-1.0472, 1.0472), (0.0, 1.2217), (-0.2094, 0.2094), (-0.6981, 0.6981), (-0.2618, 1.5708)]
)
NAMES = (
    [f"lh_{f}J{j}" for f in ("FF", "MF", "RF") for j in (4, 3, 2, 1)]
    + [f"lh_LFJ{j}" for j in (5, 4, 3, 2, 1)]
    + [f"lh_THJ{j}" for j in (5, 4, 3, 2, 1)]
)
assert len(LIMITS) == 22 and len(NAMES) == 22

rng = np.random.default_rng(20220405)
lo = np.array([l for l, _ in LIMITS])
hi = np.array([h for _, h in LIMITS])
centre = 0.5 * (lo + hi)
half = 0.5 * (hi - lo)

n, d, k = 200, 22, 5
loadings = rng.normal(size=(k, d))
loadings /= np.linalg.norm(loadings, axis=1, keepdims=True)
scales = np.array([0.5, 0.3, 0.2, 0.12, 0.07])
factors = rng.normal(size=(n, k)) * scales
noise_scales = np.linspace(0.004, 0.03, d)
# a * tanh(z / a) keeps every value strictly inside the limits (a = 0.9 of the half range)
# while leaving small deviations nearly linear.
a = 0.9 * half
x = centre + a * np.tanh((factors @ loadings + rng.normal(size=(n, d)) * noise_scales) / a)
assert np.all(x > lo) and np.all(x < hi)

here = os.path.dirname(os.path.abspath(__file__))
objects = ["mug", "ball", "box", "can"]
with open(os.path.join(here, "pca_ref_input.csv"), "w") as f:
    f.write(",".join(NAMES + ["object"]) + "\n")
    for i, row in enumerate(x):
        f.write(",".join(repr(float(v)) for v in row) + "," + objects[i % 4] + "\n")

pca = PCA(n_components=d, svd_solver="full").fit(x)
ref = {
    "generator": "tests/data/make_pca_ref.py",
    "sklearn_version": sklearn.__version__,
    "numpy_version": np.__version__,
    "n_samples": n,
    "explained_variance": [float(v) for v in pca.explained_variance_],
    "explained_variance_ratio": [float(v) for v in pca.explained_variance_ratio_],
    "mean": [float(v) for v in pca.mean_],
    "abs_components": [[float(abs(v)) for v in row] for row in pca.components_],
}
with open(os.path.join(here, "pca_ref_sklearn.json"), "w") as f:
    json.dump(ref, f, indent=1)
    f.write("\n")
print("eigenvalues:", pca.explained_variance_)
print("min gap:", np.min(-np.diff(pca.explained_variance_)))
