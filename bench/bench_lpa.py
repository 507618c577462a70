"""Speed and accuracy of the library's LocalProcrustesAnalysis against the plain ReferenceLPA.

Single-threaded (OMP/OpenBLAS/MKL threads = 1, set before numpy is imported). Cases:

* 2-link §3.6 pair, fit at N = 1000 and N = 5000 (n_min 7, c_min 1e-7, cluster_dims [0, 1],
  n_init 3); accuracy = end-effector mapping RMSE (mm) on 10,000 test correspondences.
* inverse dynamics 20-D -> 16-D (bench/datasets.py), fit on 1464 correspondences (latent_dim
  16, n_min 40 — well above latent_dim + 1 = 17 so that each local 16-D PCA sees enough
  points — c_min 1e-7, clustering in the source state space (q, q̇) = columns 0-9 as in
  §5.4.2, n_init 3); transfer of the 16,800 following source points; accuracy = RMSE (N·m)
  of the transferred target torques against the true ones.

* transfer of 16,800 x 20 -> 16 on several models of that size (``TRANSFER_MODELS``): the
  same inverse-dynamics set-up on other babbling seeds, with responsibilities over 5, 10, 15
  or 20 source columns (q; q, q̇; q, q̇, q̈; all) and 22-25 clusters, each fitted by the
  library and the reference and transferring its seed's 16,800 held-out points. The two
  transfers alternate, ``--transfer-repeats`` times each, so both see the same load; the
  ratio is of their medians, of wall time and of the thread's CPU time (steadier on a
  shared machine: time spent preempted does not count).

Times are medians of ``--repeats`` runs (library) and ``--reference-repeats`` runs
(reference), ``time.perf_counter``. After the table, the goal figures of issue "Speed" item 2,
all from this one run: the transfer time and its ratio to the reference, and the fit ratio at
N = 5000 (``--quick`` fits N = 200 and 5000 once each). The load average is printed before
and after: timings on a shared machine are only comparable at a low load.

``--crossover`` instead measures where the transfer's dense path (all K local maps on every
point) overtakes its sparse path (each map on the points it is responsible for only), as a
function of the share of non-negligible responsibilities: the fitted inverse-dynamics and
2-link models with their covariances scaled up (more spread responsibilities), and random
mixtures of other sizes. ``local_procrustes.dense_share`` is the rule fitted to it.

Usage: ``python -m bench.bench_lpa [--quick | --crossover | --transfer-only]``.
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
from lpa_transfer.transfer import gmm, local_procrustes  # noqa: E402

TWO_LINK = dict(n_min=7, c_min=1e-7, cluster_dims=[0, 1], n_init=3, random_state=0)
INVERSE_DYNAMICS = dict(n_min=40, c_min=1e-7, latent_dim=16, cluster_dims=list(range(10)),
                        n_init=3, random_state=0)
MODELS = {"library": LocalProcrustesAnalysis, "reference": ReferenceLPA}
#: Transfer models of the 16,800 x 20 size: (name, babbling seed of datasets.inverse_dynamics,
#: LPA parameters); the first is the table's 20-D -> 16-D model.
TRANSFER_MODELS = (
    ("seed 0, q q̇ (cols 0-9)", 0, INVERSE_DYNAMICS),
    ("seed 5, q q̇ (cols 0-9)", 5, INVERSE_DYNAMICS),
    ("seed 1, q q̇ q̈ (cols 0-14)", 1, dict(INVERSE_DYNAMICS, cluster_dims=list(range(15)))),
    ("seed 5, q (cols 0-4), n_min 35", 5,
     dict(INVERSE_DYNAMICS, n_min=35, cluster_dims=list(range(5)))),
    ("seed 3, all 20 cols", 3, dict(INVERSE_DYNAMICS, cluster_dims=list(range(20)))),
)


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
    print(f"NPY_ENABLE_CPU_FEATURES={os.environ.get('NPY_ENABLE_CPU_FEATURES')}, "
          f"OPENBLAS_CORETYPE={os.environ.get('OPENBLAS_CORETYPE')}")
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
        if name == "library":
            density = responsibility_density(fitted, held_out)
    pa = ProcrustesAnalysis(latent_dim=16).fit(data["source"], data["target"])
    pa_tau = rmse(pa.transfer(held_out)[:, 12:], true_tau)
    n_train = len(data["source"])
    rows.append((f"20-D -> 16-D fit, N = {n_train}", fit_s, accuracy, "N·m", clusters, pa_tau))
    rows.append((f"20-D -> 16-D transfer, {len(held_out)} points", transfer_s, accuracy,
                 "N·m", clusters, pa_tau))
    return rows, density


def transfer_models(repeats):
    """Transfer time of library and reference on each of ``TRANSFER_MODELS``, alternating:
    rows of (name, K library/reference, library s, reference s, density)."""
    rows = []
    for name, seed, params in TRANSFER_MODELS:
        data = datasets.inverse_dynamics(seed=seed)
        fitted = {label: model(**params).fit(data["source"], data["target"])
                  for label, model in MODELS.items()}
        source = data["source_held_out"]
        times = {label: [] for label in fitted}
        cpu = {label: [] for label in fitted}
        for _ in range(repeats):
            for label, model in fitted.items():
                start, start_cpu = time.perf_counter(), time.thread_time()
                model.transfer(source)
                times[label].append(time.perf_counter() - start)
                cpu[label].append(time.thread_time() - start_cpu)
        rows.append((name, (fitted["library"].n_clusters_, fitted["reference"].n_clusters_),
                     float(np.median(times["library"])), float(np.median(times["reference"])),
                     float(np.median(cpu["reference"]) / np.median(cpu["library"])),
                     responsibility_density(fitted["library"], source)))
    return rows


def print_transfer_models(rows):
    header = (f"{'transfer 16,800 x 20 -> 16, model':<34} {'K lib/ref':>9} {'library':>9} "
              f"{'reference':>10} {'speed-up':>9} {'CPU':>6} {'clusters/pt':>11} {'path':>6}")
    print("\n" + header + "\n" + "-" * len(header))
    for name, clusters, lib, ref, cpu, (per_point, share, dense_from) in rows:
        path = "dense" if share >= dense_from else "sparse"
        print(f"{name:<34} {clusters[0]:>4}/{clusters[1]:<4} {_duration(lib):>9} "
              f"{_duration(ref):>10} {ref / lib:>8.1f}x {cpu:>5.1f}x {per_point:>11.2f} "
              f"{path:>6}")
    ratios = [ref / lib for _, _, lib, ref, _, _ in rows]
    print(f"transfer on every model: slowest {max(row[2] for row in rows) * 1000:.1f} ms, "
          f"smallest speed-up {min(ratios):.1f}x by wall time, "
          f"{min(row[4] for row in rows):.1f}x by CPU time (goal >= 8x)")


def responsibility_density(model, source):
    """Mean number of clusters per point with γ_k ≥ 1e-17, their share of all (point, k)
    entries, and the share from which the transfer takes its dense path."""
    gamma = model.responsibilities(source)
    kept = np.count_nonzero(gamma >= local_procrustes._NEGLIGIBLE_RESPONSIBILITY)
    return (kept / len(source), kept / gamma.size,
            local_procrustes.dense_share(model.n_features_in_, model.n_features_out_,
                                         model.n_clusters_))


def print_goals(rows, density):
    """The figures of issue "Speed" item 2, from the table's rows."""
    by_case = {case: seconds for case, seconds, *_ in rows}
    transfer = next(seconds for case, seconds in by_case.items() if "transfer" in case)
    lib, ref = transfer["library"], transfer["reference"]
    per_point, share, dense_from = density
    path = "dense" if share >= dense_from else "sparse"
    print(f"\ntransfer 16,800 x 20 -> 16: {lib * 1000:.1f} ms (goal <= 12 ms), reference "
          f"{ref * 1000:.1f} ms: {ref / lib:.1f}x (goal >= 5x); {per_point:.2f} clusters per "
          f"point, share {share:.3f} of entries (dense from {dense_from:.3f}): {path} path")
    fit = by_case.get("2-link fit, N = 5000")
    if fit is not None:
        print(f"fit N = 5000: library {_duration(fit['library'])}, reference "
              f"{_duration(fit['reference'])}: {fit['reference'] / fit['library']:.1f}x")


def crossover(args):
    """Time the dense and the sparse transfer paths over a range of responsibility spreads."""
    print(f"{'model':<28} {'clusters/pt':>11} {'share':>7} {'sparse':>10} {'dense':>10}")
    cases = []
    data = datasets.inverse_dynamics()
    model = LocalProcrustesAnalysis(**INVERSE_DYNAMICS).fit(data["source"], data["target"])
    cases.append(("inverse dynamics K = %d" % model.n_clusters_, model,
                  data["source_held_out"]))
    model = LocalProcrustesAnalysis(**TWO_LINK).fit(*datasets.two_link(5000, seed=0))
    cases.append(("2-link N = 5000, K = %d" % model.n_clusters_, model,
                  datasets.two_link(20_000, seed=12345)[0]))
    for n_clusters, n_in, n_out in args.crossover_sizes:
        cases.append(random_case(n_clusters, n_in, n_out))
    for name, model, source in cases:
        measured = []
        for scale in np.geomspace(1, 1000, 16):
            measured.append(_time_paths(model, source, scale, args.transfer_repeats))
            per_point, share, sparse, dense = measured[-1]
            print(f"{name:<28} {per_point:>11.2f} {share:>7.3f} {_duration(sparse):>10} "
                  f"{_duration(dense):>10}")
            if sparse > 3 * dense or share > 0.999:
                break
        found = _crossing(measured)
        rule = local_procrustes.dense_share(model.n_features_in_, model.n_features_out_,
                                            model.n_clusters_)
        print(f"{name:<28} crossover at share {found}, rule dense_share(D_s = "
              f"{model.n_features_in_}, D_t = {model.n_features_out_}, K = "
              f"{model.n_clusters_}) = {rule:.3f}\n")


def random_case(n_clusters, n_in, n_out, n_cluster_dims=3, seed=0):
    """K equal-weight components at random in [-1, 1]³, narrow at scale 1 (a twentieth of
    their spacing), random local maps D_s -> D_t and uniform source points."""
    rng = np.random.default_rng(seed)
    n_points = max(2000, min(20_000, 4_000_000 // n_clusters))
    model = LocalProcrustesAnalysis()
    model.weights_ = np.full(n_clusters, 1 / n_clusters)
    model.means_ = rng.uniform(-1, 1, (n_clusters, n_cluster_dims))
    spacing = n_clusters ** (-1 / n_cluster_dims)
    model.precisions_cholesky_ = np.tile(np.eye(n_cluster_dims) / (0.05 * spacing),
                                         (n_clusters, 1, 1))
    model.coef_ = rng.normal(size=(n_clusters, n_out, n_in))
    model.intercept_ = rng.normal(size=(n_clusters, n_out))
    model.cluster_dims_ = np.arange(n_cluster_dims)
    model.n_clusters_, model.n_features_in_, model.n_features_out_ = n_clusters, n_in, n_out
    source = rng.uniform(-1, 1, (n_points, max(n_in, n_cluster_dims)))[:, :n_in]
    return f"random K = {n_clusters}, {n_in} -> {n_out}", model, source


def _time_paths(model, source, scale, repeats):
    """(clusters per point, share, sparse s, dense s) with the covariances scaled by scale²."""
    mixture = gmm.Responsibilities(model.weights_, model.means_,
                                   model.precisions_cholesky_ / scale)
    blocks = [(rows, gamma) for rows, gamma, _ in
              mixture.blocks(source[:, model.cluster_dims_])]
    kept = sum(np.count_nonzero(gamma >= local_procrustes._NEGLIGIBLE_RESPONSIBILITY)
               for _, gamma in blocks)
    seconds = [median_time(lambda: local_procrustes.mix_local_maps(
        source, iter(blocks), model.coef_, model.intercept_, path=path), repeats)[0]
        for path in ("sparse", "dense")]
    return (kept / len(source), kept / (len(source) * model.n_clusters_), *seconds)


def _crossing(measured):
    """The share where sparse - dense time changes sign (linear interpolation), as text."""
    for before, after in zip(measured, measured[1:]):
        lead_before, lead_after = before[2] - before[3], after[2] - after[3]
        if lead_before < 0 <= lead_after:
            part = -lead_before / (lead_after - lead_before)
            return f"{before[1] + part * (after[1] - before[1]):.3f}"
    return "not crossed" if measured[-1][2] < measured[-1][3] else "below the first"


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
                        help="smoke run: 2-link N = 200 and 5000, one repeat each")
    parser.add_argument("--crossover", action="store_true",
                        help="time the transfer's dense and sparse paths against the share "
                             "of non-negligible responsibilities, instead of the table")
    parser.add_argument("--repeats", type=int, default=5, help="library fit repeats")
    parser.add_argument("--reference-repeats", type=int, default=3)
    parser.add_argument("--transfer-repeats", type=int, default=7)
    parser.add_argument("--transfer-only", action="store_true",
                        help="only the transfer on every model of TRANSFER_MODELS")
    args = parser.parse_args()
    args.sizes = (1000, 5000)
    if args.quick:
        args.sizes, args.repeats, args.reference_repeats, args.transfer_repeats = \
            (200, 5000), 1, 1, 3
    args.crossover_sizes = ((24, 20, 16), (400, 4, 4), (100, 10, 6), (50, 40, 30),
                            (1776, 20, 16))
    warnings.filterwarnings("ignore", module="sklearn")     # the reference's EM warnings
    with threadpool_limits(1):
        print_environment()
        print("load average (1, 5, 15 min) before: %.2f %.2f %.2f" % os.getloadavg())
        if args.crossover:
            args.transfer_repeats = min(args.transfer_repeats, 3)
            crossover(args)
        elif args.transfer_only:
            print_transfer_models(transfer_models(args.transfer_repeats))
        else:
            ReferenceLPA(**TWO_LINK).fit(*datasets.two_link(100, seed=1))        # warm-up
            LocalProcrustesAnalysis(**TWO_LINK).fit(*datasets.two_link(100, seed=1))
            rows, density = run(args)
            print_table(rows)
            print_goals(rows, density)
            print_transfer_models(transfer_models(args.transfer_repeats))
        print("load average (1, 5, 15 min) after: %.2f %.2f %.2f" % os.getloadavg())


if __name__ == "__main__":
    main()
