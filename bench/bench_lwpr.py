"""Online speed of the library's LWPR: predict + update rate for 15 inputs -> 5 outputs.

The issue's goal: one predict + update cycle within 1 ms (>= 1 kHz), single thread, after
16,800 training samples. Data: inverse dynamics of the synthetic 5-link source chain of
``bench/datasets.py`` (thin rods in a vertical plane, τ from pybullet), inputs (q, q̇, q̈)
(15), outputs τ (5). Two data sets, both seeded:

* ``trials`` (the thesis' setting, §5.5.3: 16,800 samples = 20 trials of one 8.4-s task at
  100 Hz): one 840-sample babbling segment, repeated 20 times; every trial perturbs the
  states by Gaussian noise of 2 % of each column's standard deviation (trial-to-trial
  tracking differences) and τ is the exact inverse dynamics of the perturbed states.
* ``babbling`` (a stress case): 168 s of non-repeating babbling (``datasets``' 16,800
  held-out samples and the 2,000 after them). Every sample visits new territory, so the
  number of receptive fields keeps growing.

For each: the fit time of the 16,800 samples (``fit``), then ``--cycles`` online cycles on
the samples that follow (2 more trials / the next 16.8 s), timed one by one with
``time.perf_counter``: (a) ``update(x, y)``, which returns the prediction made before
learning (the control-loop step), and (b) ``predict(x)`` followed by ``partial_fit(x, y)``
(on a copy of the trained model, so both see the same new samples).
Printed: median and p95 per cycle (µs), cycles/s (= 1 / median), the receptive fields per
output, and the online nMSE of the predictions made before learning (per output, mean).

Hyperparameters: init_D 30 and init_alpha 0.01 (the thesis' youBot values), other LWPR
defaults; norm_in / norm_out are the standard deviations of the training batch (the
default ``None``). Usage: ``python -m bench.bench_lwpr [--quick] [--cycles N]``.
"""
import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_var] = "1"

import argparse  # noqa: E402
import copy  # noqa: E402
import platform  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402
from threadpoolctl import threadpool_limits  # noqa: E402

from bench import datasets  # noqa: E402
from lpa_transfer.learners.lwpr import LWPR  # noqa: E402
from lpa_transfer.robots.planar_chain import babbling_trajectory, inverse_dynamics  # noqa: E402

HYPERPARAMETERS = dict(init_D=30.0, init_alpha=0.01)
N_TRAIN, TRIAL_SAMPLES, TRIAL_NOISE = 16_800, 840, 0.02


def repeated_trials(n_trials, seed=0):
    """(X (n_trials·840, 15), τ (n_trials·840, 5)): one 8.4-s task, perturbed per trial."""
    lengths, masses = datasets.SOURCE_CHAIN
    q, qd, qdd = babbling_trajectory(len(lengths), np.arange(TRIAL_SAMPLES) / datasets.RATE_HZ,
                                     seed)
    task = np.hstack((q, qd, qdd))
    rng = np.random.default_rng([seed, 2])
    X = np.vstack([task + TRIAL_NOISE * task.std(axis=0) * rng.standard_normal(task.shape)
                   for _ in range(n_trials)])
    n = len(lengths)
    return X, inverse_dynamics(lengths, masses, X[:, :n], X[:, n:2 * n], X[:, 2 * n:])


def babbling(n_samples, seed=0):
    """(X (n, 15), τ (n, 5)) of non-repeating babbling (bench/datasets.py, noise-free)."""
    z = datasets._babbling_points(datasets.SOURCE_CHAIN, n_samples, seed)
    n_inputs = 3 * len(datasets.SOURCE_CHAIN[0])
    return z[:, :n_inputs], z[:, n_inputs:]


def time_cycles(model, X, Y, fused):
    """Per-cycle wall times (s) and the predictions made before learning each sample."""
    seconds, predictions = np.empty(len(X)), np.empty_like(Y)
    for i, (x, y) in enumerate(zip(X, Y)):
        start = time.perf_counter()
        if fused:
            predictions[i] = model.update(x, y)
        else:
            predictions[i] = model.predict(x[None])[0]
            model.partial_fit(x, y)
        seconds[i] = time.perf_counter() - start
    return seconds, predictions


def run_case(name, X, Y, n_train, n_cycles):
    train, online = slice(0, n_train), slice(n_train, n_train + n_cycles)
    start = time.perf_counter()
    model = LWPR(**HYPERPARAMETERS).fit(X[train], Y[train])
    fit_s = time.perf_counter() - start
    print(f"\n[{name}] fit of {n_train} samples: {fit_s:.1f} s "
          f"({fit_s / n_train * 1e6:.0f} µs per sample); receptive fields per output: "
          f"{model.n_receptive_fields_.tolist()}")
    variance = Y[online].var(axis=0)
    twin = copy.deepcopy(model)                   # both variants start from the same state
    for label, fused, learner in (("update(x, y)", True, model),
                                  ("predict(x) + partial_fit(x, y)", False, twin)):
        seconds, predictions = time_cycles(learner, X[online], Y[online], fused)
        micro = seconds * 1e6
        nmse = ((predictions - Y[online]) ** 2).mean(axis=0) / variance
        print(f"  {label:<32} median {np.median(micro):6.0f} µs  p95 "
              f"{np.percentile(micro, 95):6.0f} µs  -> {1e6 / np.median(micro):6.0f} cycles/s "
              f"(mean {len(micro) / seconds.sum():.0f}/s)  online nMSE {nmse.mean():.4f}")
    print(f"  receptive fields per output after the cycles: {model.n_receptive_fields_.tolist()}")


def print_environment():
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    usable = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    print(f"python {platform.python_version()}, numpy {np.__version__}, {platform.machine()}, "
          f"{usable} usable CPU(s), load average {load:.2f}; threads: "
          + ", ".join(f"{v}={os.environ.get(v)}" for v in
                      ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")))
    print(f"LWPR hyperparameters: {HYPERPARAMETERS} (other parameters: defaults)")


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--quick", action="store_true",
                        help="smoke run: 2 trials (1,680 samples) of training, 200 cycles")
    parser.add_argument("--cycles", type=int, default=1680, help="online cycles per variant")
    parser.add_argument("--case", choices=("trials", "babbling", "both"), default="both")
    args = parser.parse_args()
    n_train = 2 * TRIAL_SAMPLES if args.quick else N_TRAIN
    n_cycles = 200 if args.quick else args.cycles
    with threadpool_limits(1):
        print_environment()
        if args.case in ("trials", "both"):
            n_trials = -(-(n_train + n_cycles) // TRIAL_SAMPLES)
            run_case("trials: 20 repetitions of one 8.4-s task", *repeated_trials(n_trials),
                     n_train, n_cycles)
        if args.case in ("babbling", "both"):
            run_case("babbling: 168 s without repetition", *babbling(n_train + n_cycles),
                     n_train, n_cycles)


if __name__ == "__main__":
    main()
