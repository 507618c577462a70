"""Online speed of the library's LWPR next to the frozen numpy reference: predict + update
rate for 15 inputs -> 5 outputs, one 2-input update, and the start-up time.

The library's LWPR runs its per-sample update and prediction in compiled kernels
(lpa_transfer/learners/_lwpr_kernels.py, numba); test/oracles/reference_lwpr.py is the numpy
implementation they replaced, kept frozen as the yardstick. Both run here on the same data in
the same process, so the speed-up is measured under the same load. The issue's goals: one
predict + update cycle of the 15-input model within 0.1 ms (>= 10,000 cycles/s), single
thread, after 16,800 training samples, and one 2-input update within 50 µs.

15 -> 5: inverse dynamics of the synthetic 5-link source chain of ``bench/datasets.py`` (thin
rods in a vertical plane, τ from pybullet), inputs (q, q̇, q̈) (15), outputs τ (5). Two data
sets, both seeded:

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
Printed per implementation: median and p95 per cycle (µs), cycles/s (= 1 / median); the
speed-up (ratio of the medians); the receptive fields per output; the online nMSE of the
predictions made before learning (per output, mean); and the largest relative difference
between the two implementations' predictions.

2 inputs: the "cross" function of the LWPR paper with the settings of test/test_lwpr.py,
1,000 samples learned, then ``update(x, y)`` timed on 2,000 more (median and p95, µs).

Start-up: a fresh process imports LWPR and makes its first update and prediction, once with
an empty kernel cache (compiling; NUMBA_CACHE_DIR points to a temporary directory) and once
with the cache that run wrote (what every later process sees).

Hyperparameters (15 -> 5): init_D 30 and init_alpha 0.01 (the thesis' youBot values), other
LWPR defaults; norm_in / norm_out are the standard deviations of the training batch (the
default ``None``). Usage:
``python -m bench.bench_lwpr [--quick] [--cycles N] [--case C] [--no-start]``.
"""
import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_var] = "1"

import argparse  # noqa: E402
import copy  # noqa: E402
import importlib.util  # noqa: E402
import platform  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402
from threadpoolctl import threadpool_limits  # noqa: E402

from bench import datasets  # noqa: E402
from lpa_transfer.learners.lwpr import LWPR  # noqa: E402
from lpa_transfer.robots.planar_chain import babbling_trajectory, inverse_dynamics  # noqa: E402


def _reference_lwpr():
    """The frozen numpy LWPR, kept beside the tests that check the library against it."""
    path = Path(__file__).resolve().parents[1] / "test" / "oracles" / "reference_lwpr.py"
    spec = importlib.util.spec_from_file_location("reference_lwpr", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module.LWPR


ReferenceLWPR = _reference_lwpr()
HYPERPARAMETERS = dict(init_D=30.0, init_alpha=0.01)
#: The 2-input "cross" setting of test/test_lwpr.py.
CROSS = dict(init_D=25.0, init_alpha=250.0, w_gen=0.2, norm_in=1.0)
IMPLEMENTATIONS = (("compiled", LWPR), ("reference", ReferenceLWPR))
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


def summary(seconds):
    """(median µs, p95 µs, cycles/s) of per-cycle times."""
    micro = seconds * 1e6
    return np.median(micro), np.percentile(micro, 95), 1e6 / np.median(micro)


def relative_difference(a, b):
    return float(np.max(np.abs(a - b) / np.maximum(np.abs(b), 1e-300)))


def run_case(name, X, Y, n_train, n_cycles):
    train, online = slice(0, n_train), slice(n_train, n_train + n_cycles)
    models, fit_s = {}, {}
    for label, learner in IMPLEMENTATIONS:
        start = time.perf_counter()
        models[label] = learner(**HYPERPARAMETERS).fit(X[train], Y[train])
        fit_s[label] = time.perf_counter() - start
    counts = {label: model.n_receptive_fields_.tolist() for label, model in models.items()}
    print(f"\n[{name}] fit of {n_train} samples: "
          + ", ".join(f"{label} {s:.2f} s ({s / n_train * 1e6:.0f} µs per sample)"
                      for label, s in fit_s.items())
          + f"; receptive fields per output: {counts['compiled']}"
          + ("" if counts["compiled"] == counts["reference"]
             else f" (reference: {counts['reference']})"))
    print(f"  {'cycle':<32} {'compiled: median   p95  cycles/s':>34}   "
          f"{'reference: median   p95  cycles/s':>35}   speed-up")
    variance = Y[online].var(axis=0)
    predictions, after = {}, {}
    twins = {label: copy.deepcopy(model) for label, model in models.items()}  # same state
    for cycle, fused in (("update(x, y)", True), ("predict(x) + partial_fit(x, y)", False)):
        rates, nmse = [], {}
        for label, model in models.items():
            learner = model if fused else twins[label]
            seconds, predictions[label] = time_cycles(learner, X[online], Y[online], fused)
            nmse[label] = (((predictions[label] - Y[online]) ** 2).mean(axis=0)
                           / variance).mean()
            rates.append(summary(seconds))
            if fused:
                after[label] = learner.n_receptive_fields_.tolist()
        (med, p95, rate), (ref_med, ref_p95, ref_rate) = rates
        print(f"  {cycle:<32} {med:8.1f} µs {p95:6.1f} µs {rate:7.0f}/s   "
              f"{ref_med:9.1f} µs {ref_p95:6.1f} µs {ref_rate:7.0f}/s   {ref_med / med:6.1f}x")
        print(f"  {'':<32} online nMSE {nmse['compiled']:.4f} (reference "
              f"{nmse['reference']:.4f}); predictions differ by <= "
              f"{relative_difference(predictions['compiled'], predictions['reference']):.1e} "
              "relative")
    print(f"  receptive fields per output after the cycles: {after['compiled']}"
          + ("" if after["compiled"] == after["reference"]
             else f" (reference: {after['reference']})"))


def cross_data(n, seed=0):
    """The 2-D cross function of the LWPR paper, with noise (as in test/test_lwpr.py)."""
    rng = np.random.default_rng(seed)
    X = rng.uniform(-1, 1, (n, 2))
    y = np.max([np.exp(-10 * X[:, 0] ** 2), np.exp(-50 * X[:, 1] ** 2),
                1.25 * np.exp(-5 * (X[:, 0] ** 2 + X[:, 1] ** 2))], axis=0)
    return X, y + 0.1 * rng.standard_normal(n)


def run_two_inputs(n_train=1000, n_updates=2000):
    """One update(x, y) of a 2-input model (cross function) after n_train samples."""
    X, y = cross_data(n_train + n_updates)
    print(f"\n[2 inputs: cross function, {n_train} samples learned] update(x, y), "
          f"{n_updates} updates timed one by one")
    results = []
    for label, learner in IMPLEMENTATIONS:
        model = learner(**CROSS).fit(X[:n_train], y[:n_train])
        seconds, _ = time_cycles(model, X[n_train:], y[n_train:, None], fused=True)
        results.append(summary(seconds))
        med, p95, _ = results[-1]
        print(f"  {label:<10} median {med:7.1f} µs  p95 {p95:7.1f} µs  "
              f"(receptive fields: {int(model.n_receptive_fields_[0])})")
    print(f"  speed-up {results[1][0] / results[0][0]:.1f}x")


START = """\
import time
start = time.perf_counter()
import numpy as np
from lpa_transfer.learners.lwpr import LWPR
imported = time.perf_counter()
model = LWPR(init_D=25.0)
model.update(np.zeros(2), 0.5)
model.predict(np.zeros((1, 2)))
print(imported - start, time.perf_counter() - imported)
"""


def run_start():
    """Start-up of a fresh process: import, first update and prediction (compile or load)."""
    print("\n[start-up in a fresh process: import LWPR, first update and predict]")
    with tempfile.TemporaryDirectory() as cache:
        env = dict(os.environ, NUMBA_CACHE_DIR=cache)
        for label in ("empty kernel cache (compiles)", "cached kernels"):
            start = time.perf_counter()
            out = subprocess.run([sys.executable, "-c", START], env=env, check=True,
                                 capture_output=True, text=True).stdout.split()
            wall = time.perf_counter() - start
            print(f"  {label:<30} import {float(out[0]):5.2f} s, first update + predict "
                  f"{float(out[1]):6.2f} s; whole process {wall:6.2f} s")


def print_environment():
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    usable = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    import numba
    print(f"python {platform.python_version()}, numpy {np.__version__}, numba "
          f"{numba.__version__}, {platform.machine()}, {usable} usable CPU(s), load average "
          f"{load:.2f}; threads: "
          + ", ".join(f"{v}={os.environ.get(v)}" for v in
                      ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")))
    print(f"LWPR hyperparameters (15 -> 5): {HYPERPARAMETERS} (other parameters: defaults)")


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--quick", action="store_true",
                        help="smoke run: 2 trials (1,680 samples) of training, 200 cycles")
    parser.add_argument("--cycles", type=int, default=1680, help="online cycles per variant")
    parser.add_argument("--case", choices=("trials", "babbling", "both", "none"),
                        default="both", help="15 -> 5 data set(s) to run")
    parser.add_argument("--no-start", action="store_true",
                        help="skip the start-up measurement (which compiles the kernels once)")
    args = parser.parse_args()
    n_train = 2 * TRIAL_SAMPLES if args.quick else N_TRAIN
    n_cycles = 200 if args.quick else args.cycles
    with threadpool_limits(1):
        print_environment()
        if not args.no_start:
            run_start()
        run_two_inputs()
        if args.case in ("trials", "both"):
            n_trials = -(-(n_train + n_cycles) // TRIAL_SAMPLES)
            run_case("trials: 20 repetitions of one 8.4-s task", *repeated_trials(n_trials),
                     n_train, n_cycles)
        if args.case in ("babbling", "both"):
            run_case("babbling: 168 s without repetition", *babbling(n_train + n_cycles),
                     n_train, n_cycles)
        print(f"\nload average at the end: {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
