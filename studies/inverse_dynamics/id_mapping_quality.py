#!/usr/bin/env python3
"""How well do PA and LPA map held-out inverse-dynamics correspondences (thesis §5.4)?

Usage: ``python -m studies.inverse_dynamics.id_mapping_quality RUN_DIR [SEED]`` on a chapter 5 run
directory
(``scenarios/inverse_dynamics/run.sh``): the pairs ``pairs_<SEED>_*.npz`` (default seed 0)
are split into 6 blocks of consecutive pairs (whole babbling lines), each held out once; the
models are fitted on the rest with the experiment's settings (latent_dim 16, LPA clustered
on the source's (q, q̇), c_min 1e-7) for several n_min, and the held-out target samples are
predicted from their source samples. Printed: the normalised mean squared error (per target
column, divided by its variance; 1 = no better than the mean) in both directions.
"""
import sys
from pathlib import Path

import numpy as np

from lpa_transfer.exploration import load_correspondences
from lpa_transfer.transfer import LocalProcrustesAnalysis, ProcrustesAnalysis

N_FOLDS = 6
N_MINS = (40, 80, 160, 320)


def folds(n_pairs):
    """The N_FOLDS blocks of consecutive pairs, each held out once."""
    return np.array_split(np.arange(n_pairs), N_FOLDS)


def held_out_predictions(make_model, source, target):
    """Every target row predicted by a model fitted on the other blocks (:func:`folds`)."""
    predicted = np.empty_like(target, dtype=np.float64)
    for fold in folds(len(source)):
        train = np.setdiff1d(np.arange(len(source)), fold)
        predicted[fold] = make_model().fit(source[train], target[train]).transfer(source[fold])
    return predicted


def held_out_nmse(make_model, source, target):
    scale = target.var(axis=0)
    predicted = held_out_predictions(make_model, source, target)
    return float(np.mean([np.mean((predicted[fold] - target[fold]) ** 2 / scale)
                          for fold in folds(len(source))]))


def main(argv):
    if len(argv) < 2:
        print(__doc__, file=sys.stderr)
        return 2
    seed = argv[2] if len(argv) > 2 else "0"
    files = sorted(Path(argv[1]).glob(f"pairs_{seed}_*.npz"))
    if not files:
        print(f"no pairs_{seed}_*.npz in {argv[1]}", file=sys.stderr)
        return 2
    sides = [load_correspondences(path) for path in files]
    first, second = (np.vstack([side[k] for side in sides]) for k in (0, 1))
    print(f"{len(first)} pairs from {', '.join(p.name for p in files)}; held-out nMSE "
          f"({N_FOLDS} blocks of whole babbling lines)")
    for name, source, target in (("first -> second", first, second),
                                 ("second -> first", second, first)):
        n_joints = source.shape[1] // 4
        row = [f"PA {held_out_nmse(lambda: ProcrustesAnalysis(latent_dim=16), source, target):.3f}"]
        for n_min in N_MINS:
            error = held_out_nmse(lambda: LocalProcrustesAnalysis(
                n_min=n_min, c_min=1e-7, latent_dim=16, cluster_dims=list(range(2 * n_joints)),
                random_state=0), source, target)
            row.append(f"LPA n_min {n_min} {error:.3f}")
        print(f"  {name} ({source.shape[1]}-D -> {target.shape[1]}-D): " + ", ".join(row))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
