"""Speed and accuracy of the library's LocalProcrustesAnalysis against the plain ReferenceLPA.

Single-threaded (OMP/OpenBLAS/MKL threads = 1, set before numpy is imported). Cases:

* 2-link §3.6 pair, fit at N = 1000 and N = 5000 (n_min 7, c_min 1e-7, cluster_dims [0, 1],
  n_init 3); accuracy = end-effector mapping RMSE (mm) on 10,000 test correspondences.
* inverse dynamics 20-D -> 16-D (bench/datasets.py), fit on 1464 correspondences (latent_dim
  16, n_min 40 — well above latent_dim + 1 = 17 so that each local 16-D PCA sees enough
  points — c_min 1e-7, clustering in the source state space (q, q̇) = columns 0-9 as in
  §5.4.2, n_init 3); transfer of the 16,800 following source points; accuracy = RMSE (N·m)
  of the transferred target torques against the true ones.

Times are medians of ``--repeats`` runs (library) and ``--reference-repeats`` runs
(reference), ``time.perf_counter``. Usage: ``python -m bench.bench_lpa [--quick]``.
"""
import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_var] = "1"

import argparse  # noqa: E402
import platform  # noqa: E402
import time  # noqa: E402
import warnings  # noqa: E402

import numpy as np  # noqa: E402
from threadpoolctl import threadpool_info, threadpool_limits  # noqa: E402

from bench import datasets  # noqa: E402
from bench.reference_lpa import ReferenceLPA  # noqa: E402
from lpa_transfer import LocalProcrustesAnalysis, ProcrustesAnalysis  # noqa: E402

TWO_LINK = dict(n_min=7, c_min=1e-7, cluster_dims=[0, 1], n_init=3, random_state=0)
INVERSE_DYNAMICS = dict(n_min=40, c_min=1e-7, latent_dim=16, cluster_dims=list(range(10)),
                        n_init=3, random_state=0)
MODELS = {"library": LocalProcrustesAnalysis, "reference": ReferenceLPA}


def median_time(function, repeats):
    """Median wall time (s) of ``repeats`` calls and the last call's result."""
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        result = function()
        times.append(time.perf_counter() - start)
    return float(np.median(times)), result


def rmse(predicted, true):
    return float(np.sqrt(((predicted - true) ** 2).sum(axis=1).mean()))


def print_environment():
    print(f"python {platform.python_version()}, numpy {np.__version__}, "
          f"{platform.machine()}, {os.cpu_count()} CPUs")
    print("threads: " + ", ".join(f"{v}={os.environ.get(v)}" for v in
                                  ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS",
                                   "MKL_NUM_THREADS")))
    for pool in threadpool_info():
        print(f"  {pool['internal_api']} {pool.get('version')} ({pool['user_api']}): "
              f"{pool['num_threads']} thread(s)")


def run(args):
    repeats = {"library": args.repeats, "reference": args.reference_repeats}
    rows = []        # (case, {model: seconds}, {model: accuracy}, unit, {model: K})

    source_test, target_test = datasets.two_link(10_000, seed=12345)
    for n in args.sizes:
        source, target = datasets.two_link(n, seed=0)
        seconds, accuracy, clusters = {}, {}, {}
        for name, model in MODELS.items():
            seconds[name], fitted = median_time(
                lambda: model(**TWO_LINK).fit(source, target), repeats[name])
            accuracy[name] = 1000 * rmse(fitted.transfer(source_test)[:, 2:],
                                         target_test[:, 2:])
            clusters[name] = fitted.n_clusters_
        pa = ProcrustesAnalysis().fit(source, target).transfer(source_test)
        rows.append((f"2-link fit, N = {n}", seconds, accuracy, "mm", clusters,
                     1000 * rmse(pa[:, 2:], target_test[:, 2:])))

    data = datasets.inverse_dynamics()
    held_out, true_tau = data["source_held_out"], data["target_held_out"][:, 12:]
    fit_s, transfer_s, accuracy, clusters = {}, {}, {}, {}
    for name, model in MODELS.items():
        fit_s[name], fitted = median_time(
            lambda: model(**INVERSE_DYNAMICS).fit(data["source"], data["target"]),
            repeats[name])
        transfer_s[name], transferred = median_time(lambda: fitted.transfer(held_out),
                                                    args.transfer_repeats)
        accuracy[name] = rmse(transferred[:, 12:], true_tau)
        clusters[name] = fitted.n_clusters_
    pa = ProcrustesAnalysis(latent_dim=16).fit(data["source"], data["target"])
    pa_tau = rmse(pa.transfer(held_out)[:, 12:], true_tau)
    n_train = len(data["source"])
    rows.append((f"20-D -> 16-D fit, N = {n_train}", fit_s, accuracy, "N·m", clusters, pa_tau))
    rows.append((f"20-D -> 16-D transfer, {len(held_out)} points", transfer_s, accuracy,
                 "N·m", clusters, pa_tau))
    return rows


def print_table(rows):
    header = (f"{'case':<36} {'library':>10} {'reference':>10} {'speed-up':>9}   "
              f"{'accuracy library / reference (PA)':<36} {'K lib/ref':>9}")
    print(header + "\n" + "-" * len(header))
    for case, seconds, accuracy, unit, clusters, pa in rows:
        lib, ref = seconds["library"], seconds["reference"]
        acc = (f"{accuracy['library']:.4g} / {accuracy['reference']:.4g} ({pa:.4g}) {unit}")
        print(f"{case:<36} {_duration(lib):>10} {_duration(ref):>10} {ref / lib:>8.1f}x   "
              f"{acc:<36} {clusters['library']:>4}/{clusters['reference']:<4}")


def _duration(seconds):
    return f"{seconds * 1000:.1f} ms" if seconds < 1 else f"{seconds:.2f} s"


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--quick", action="store_true",
                        help="smoke run: 2-link N = 200 and 1000, one repeat each")
    parser.add_argument("--repeats", type=int, default=5, help="library fit repeats")
    parser.add_argument("--reference-repeats", type=int, default=3)
    parser.add_argument("--transfer-repeats", type=int, default=7)
    args = parser.parse_args()
    args.sizes = (1000, 5000)
    if args.quick:
        args.sizes, args.repeats, args.reference_repeats, args.transfer_repeats = \
            (200, 1000), 1, 1, 1
    warnings.filterwarnings("ignore", module="sklearn")     # the reference's EM warnings
    with threadpool_limits(1):
        print_environment()
        ReferenceLPA(**TWO_LINK).fit(*datasets.two_link(100, seed=1))        # warm-up
        LocalProcrustesAnalysis(**TWO_LINK).fit(*datasets.two_link(100, seed=1))
        print_table(run(args))


if __name__ == "__main__":
    main()
