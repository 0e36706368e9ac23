"""The paper's numbers (Section IV), for the replication report to print beside ours."""

from __future__ import annotations

import pandas as pd

#: Table I: GMM classification of each target's samples (rows) into clusters (columns).
TABLE_I: dict[str, pd.DataFrame] = {
    "ed": pd.DataFrame(
        [[1, 13, 486], [191, 309, 0], [0, 19, 481]],
        index=pd.Index(
            ["target 1 samples", "target 2 samples", "target 3 samples"], name="classified as →"
        ),
        columns=["unnamed", "target 2", "target 1 and target 3"],
    ),
    "vertex_rms": pd.DataFrame(
        [[197, 0, 303], [2, 497, 1], [151, 0, 349]],
        index=pd.Index(
            ["target 1 samples", "target 2 samples", "target 3 samples"], name="classified as →"
        ),
        columns=["target 1", "target 2", "target 3"],
    ),
    "cd": pd.DataFrame(
        [[472, 8, 20], [0, 499, 1], [3, 1, 496]],
        index=pd.Index(
            ["target 1 samples", "target 2 samples", "target 3 samples"], name="classified as →"
        ),
        columns=["target 1", "target 2", "target 3"],
    ),
}
#: Share of samples in the cluster of their own target alone (from Table I).
TABLE_I_ACCURACY = {"ed": 309 / 1500, "vertex_rms": (197 + 497 + 349) / 1500, "cd": 1467 / 1500}

#: Final (generation 10) CD error, μ ± σ, target 1, empirical metrics (Figs. 11–12) and CD.
EMPIRICAL_T1 = {
    "pca_ed": (0.515, 0.334),
    "std_ed": (0.453, 0.279),
    "mahalanobis": (0.471, 0.275),
    "cd": (0.426, 0.1643),
}
#: PCA of the paper's training set: 9,592 faces of 240 participants, 46 components for 99%.
TRAINING_FACES = 9592
TRAINING_PARTICIPANTS = 240
PCA_COMPONENTS = 46
LOW_COMPONENT = 41  # β_l of Table II: component 41 of 46

#: Figs. 14–17, target 1, CD: final μ ± σ (fixed, protocol), default and three selections.
INIT_DEFAULT = {"fixed": (0.47, 0.162), "protocol": (0.43, 0.164)}
INIT_THREE = {"fixed": (None, 0.176), "protocol": (0.41, 0.152)}

#: Table III: (init, fixed set, target, bias, bins in %).
TABLE_III = [
    ("fixed", 1, "target 1", 1.0, (1.0, 33.3, 53.2, 12.5)),
    ("fixed", 3, "target 1", 0.87, (1.4, 37.6, 53.2, 7.8)),
    ("fixed", 1, "average", 0.57, (29.8, 69.1, 1.1, 0.0)),
    ("fixed", 3, "average", 0.38, (99.0, 1.0, 0.0, 0.0)),
    ("protocol", None, "target 1", 0.74, (2.0, 46.2, 45.3, 6.5)),
    ("protocol", None, "average", 0.55, (6.6, 78.9, 14.4, 0.1)),
]
#: Non-zero activations per initial face of the paper's fixed sets 1 and 3.
FIXED_ACTIVATIONS = {1: 5.2, 3: 19.9}

#: Table IV: target → activation range → (μ0, σ0, μ10, σ10).
TABLE_IV = {
    "target 1": {
        (1, 3): (0.752, 0.370, 0.362, 0.206),
        (3, 8): (0.744, 0.238, 0.430, 0.162),
        (8, 16): (0.737, 0.150, 0.434, 0.130),
    },
    "target 2": {
        (1, 3): (0.557, 0.132, 0.222, 0.075),
        (3, 8): (0.530, 0.129, 0.234, 0.082),
        (8, 16): (0.501, 0.102, 0.265, 0.072),
    },
}

#: Table V: final CD error μ, σ by target complexity (the paper's blendshape counts).
TABLE_V = {
    "target 1": ("1 shape", 0.426, 0.1643),
    "target 3": ("3 shapes", 0.267, 0.0997),
    "target 2": ("12 shapes", 0.237, 0.0760),
    "dense happy": ("125 shapes (users' mean happy)", 0.222, 0.0551),
}
GA_NOISE = (0.2, 0.065)
