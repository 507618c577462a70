"""lpa_mapping under load (issue 29 items 2-3): memory of a huge transfer, transfer latency
while a fit runs.

``--memory``: peak memory of a transfer of ``--points`` (default 2,000,000) 20-D points
through a 1776-cluster LPA model (20 -> 16). The model is fitted once (about 80 s on one
core: 40,000 synthetic correspondences, n_min 11, c_min 0, latent_dim 10, k_max 1776, the
first 3 source columns as clustering space) and cached in ``--work``. Measured, each in a
fresh process:

* the library call in process, ``model_store.transfer_in_blocks`` with the service's default
  ``transfer_block_elements`` and unblocked (one ``model.transfer`` call): tracemalloc's peak
  (numpy reports its arrays to tracemalloc) and the process' peak RSS (``ru_maxrss``), each
  beside the bytes of the input and output arrays;
* through the service: a real ``lpa_mapping`` process serving the cached model; its peak RSS
  (``VmHWM`` of /proc/PID/status) before and after the TransferPoints call.

``--latency``: transfer latency while a fit runs (issue 29 item 3, goal: <= 100 ms p99). A
real ``lpa_mapping`` process serves a small LPA model (2000 synthetic correspondences 20-D
-> 16-D, n_min 40, latent_dim 10, cluster_dims 0-9); a client transfers ``--transfer-points``
(default 1000) points through it every 10 ms, first alone, then while the node fits a
20,000-point 20-D LPA model (n_min 40, c_min 1e-7, latent_dim 10, cluster_dims 0-9, n_init
3). Only the transfers sent and answered between the fit's start and end (the node's log
lines, same clock) count as "during the fit"; every answer is compared with the sequential
one. The same in one process without ROS (a fit in a thread, transfers in the main thread)
shows what the GIL alone costs.

Usage (repository root): ``python -m bench.bench_mapping_limits --memory [--points N]``
(about 12 min on one core, the first time 1.5 min more for the model),
``python -m bench.bench_mapping_limits --latency [--transfer-points N]`` (about 1 min).
"""
import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_var] = "1"

import argparse  # noqa: E402
import json  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
import tracemalloc  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

from lpa_transfer import LocalProcrustesAnalysis  # noqa: E402
from lpa_transfer.transfer.model_io import load_model  # noqa: E402
from lpa_transfer.transfer.model_store import file_name, transfer_in_blocks  # noqa: E402

MIB = 2 ** 20
MODEL_ID = "bench/k1776"
BIG_LPA = dict(n_min=11, c_min=0.0, latent_dim=10, k_max=1776, cluster_dims=[0, 1, 2])
#: lpa_mapping's default transfer_block_elements (nodes/lpa_mapping.py LIMITS).
DEFAULT_BLOCK_ELEMENTS = 20_000_000


def synthetic(n, seed, n_source=20, n_target=16):
    """``n`` correspondences of a smooth non-linear 20-D -> 16-D map, source uniform in
    [-1, 1]^20 (the same map for every seed: its weights are drawn with seed 0)."""
    weights = np.random.default_rng(0).normal(size=(n_source, n_target)) / np.sqrt(n_source)
    rng = np.random.default_rng([seed, 1])
    source = rng.uniform(-1, 1, (n, n_source))
    target = np.sin(3 * source @ weights) + 0.01 * rng.normal(size=(n, n_target))
    return source, target


def source_points(n, seed, n_source=20):
    """``n`` source points of :func:`synthetic` alone (no target to compute and hold)."""
    return np.random.default_rng([seed, 1]).uniform(-1, 1, (n, n_source))


def big_model(work):
    """The 1776-cluster model, as a model file in ``work/models`` (fitted once)."""
    path = Path(work) / "models" / file_name(MODEL_ID)
    if not path.exists():
        path.parent.mkdir(parents=True, exist_ok=True)
        start = time.perf_counter()
        model = LocalProcrustesAnalysis(**BIG_LPA).fit(*synthetic(40_000, seed=1))
        model.save(path)
        print(f"fitted the model: {model.n_clusters_} clusters in "
              f"{time.perf_counter() - start:.0f} s -> {path}", flush=True)
    return path


def in_process(model_path, n_points, block_elements):
    """Child: one transfer in this process; prints a JSON line of its memory figures."""
    model = load_model(model_path)
    source = source_points(n_points, seed=2)
    rss_before = vm_hwm(os.getpid())
    tracemalloc.start()
    start = time.perf_counter()
    out = transfer_in_blocks(model, source, block_elements)
    seconds = time.perf_counter() - start
    _, peak = tracemalloc.get_traced_memory()
    rss_after = vm_hwm(os.getpid())
    print(json.dumps(dict(seconds=seconds, traced_peak=peak, input=source.nbytes,
                          output=out.nbytes, rss_before=rss_before, rss_after=rss_after,
                          clusters=int(model.n_clusters_))))


def vm_hwm(pid):
    """Peak resident set size of process ``pid`` in bytes (VmHWM)."""
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith("VmHWM:"):
            return int(line.split()[1]) * 1024
    raise RuntimeError(f"no VmHWM for {pid}")


def through_service(work, n_points):
    """Peak RSS of a real lpa_mapping process around one TransferPoints of ``n_points``."""
    import rclpy
    from rclpy.executors import SingleThreadedExecutor

    from lpa_transfer_interfaces.srv import TransferPoints
    from bench.ros_harness import NodeProcess, call_service, ros_params, unique_domain_id
    from lpa_transfer_nodes.conversions import from_matrix, to_matrix

    domain_id = unique_domain_id()
    node = NodeProcess("lpa_mapping", domain_id, Path(work) / "log",
                       ros_params(model_dir=Path(work) / "models"))
    context = rclpy.Context()
    rclpy.init(context=context, domain_id=domain_id)
    client_node = rclpy.create_node("bench_limits_client", context=context)
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(client_node)
    try:
        client = client_node.create_client(TransferPoints, "/lpa_mapping/transfer")
        small = TransferPoints.Request(model_id=MODEL_ID, source=to_matrix(
            source_points(10, seed=3)))
        assert call_service(executor, client, small, timeout=120).success, node.log()
        before = vm_hwm(node.process.pid)
        source = source_points(n_points, seed=2)
        request = TransferPoints.Request(model_id=MODEL_ID, source=to_matrix(source))
        start = time.perf_counter()
        answer = call_service(executor, client, request, timeout=3600)
        seconds = time.perf_counter() - start
        assert answer.success, answer.message + node.log()
        after = vm_hwm(node.process.pid)
        target = from_matrix(answer.target, "target")
        return dict(seconds=seconds, rss_before=before, rss_after=after, input=source.nbytes,
                    output=target.nbytes)
    finally:
        executor.shutdown()
        client_node.destroy_node()
        rclpy.shutdown(context=context)
        node.stop()


def memory(args):
    work = Path(args.work)
    model_path = big_model(work)
    print(f"transfer of {args.points:,} points 20-D -> 16-D through {model_path.name} "
          f"(load average before: {os.getloadavg()[0]:.2f})", flush=True)
    cases = ((f"blocked ({DEFAULT_BLOCK_ELEMENTS:,} elements)", DEFAULT_BLOCK_ELEMENTS),
             ("one call", None))
    for label, block_elements in cases if not args.no_in_process else ():
        run = subprocess.run(
            [sys.executable, "-m", "bench.bench_mapping_limits", "--child", str(model_path),
             str(args.points), str(block_elements)], capture_output=True, text=True,
            check=True)
        figures = json.loads(run.stdout.strip().splitlines()[-1])
        work_bytes = figures["traced_peak"] - figures["output"]
        print(f"  in process, {label:<30} {figures['seconds']:6.0f} s; tracemalloc peak "
              f"{figures['traced_peak'] / MIB:5.0f} MiB = output {figures['output'] / MIB:.0f} "
              f"MiB + {work_bytes / MIB:.1f} MiB work (the {figures['input'] / MIB:.0f} MiB "
              f"input was made before); peak RSS {figures['rss_before'] / MIB:.0f} -> "
              f"{figures['rss_after'] / MIB:.0f} MiB (K = {figures['clusters']})", flush=True)
    if not args.no_service:
        figures = through_service(work, args.points)
        arrays = figures["input"] + figures["output"]
        print(f"  through lpa_mapping (default limits)  {figures['seconds']:6.0f} s; "
              f"peak RSS {figures['rss_before'] / MIB:.0f} -> "
              f"{figures['rss_after'] / MIB:.0f} MiB, +"
              f"{(figures['rss_after'] - figures['rss_before']) / MIB:.0f} MiB = "
              f"{(figures['rss_after'] - figures['rss_before']) / arrays:.2f} x the request's "
              f"and answer's arrays ({arrays / MIB:.0f} MiB)", flush=True)
    print(f"load average after: {os.getloadavg()[0]:.2f}")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--memory", action="store_true")
    parser.add_argument("--latency", action="store_true")
    parser.add_argument("--points", type=int, default=2_000_000,
                        help="--memory: points of the transfer")
    parser.add_argument("--transfer-points", type=int, default=1000,
                        help="--latency: points of each transfer")
    parser.add_argument("--no-service", action="store_true",
                        help="--memory: only the in-process figures")
    parser.add_argument("--no-in-process", action="store_true",
                        help="--memory: only the service's figures")
    parser.add_argument("--work", default=Path(tempfile.gettempdir()) / "bench_mapping_limits",
                        help="where the big model is cached and the node logs go")
    parser.add_argument("--child", nargs=3, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child:
        model_path, n_points, block_elements = args.child
        in_process(model_path, int(n_points),
                   None if block_elements == "None" else int(block_elements))
        return
    if args.memory:
        memory(args)
    if args.latency:
        latency(args)
    if not (args.memory or args.latency):
        parser.error("say --memory and/or --latency")


SMALL_LPA = dict(n_min=40, c_min=1e-7, latent_dim=10, cluster_dims=list(range(10)))
LONG_LPA = dict(SMALL_LPA, n_init=3)


def percentiles(seconds):
    ms = 1000 * np.asarray(seconds)
    return (f"n {len(ms):4d}  median {np.median(ms):6.1f}  p90 {np.percentile(ms, 90):6.1f}  "
            f"p99 {np.percentile(ms, 99):6.1f}  max {ms.max():6.1f} ms")


def log_time(log, text):
    """The ROS log timestamp (s) of the first line containing ``text``."""
    for line in log.splitlines():
        if text in line:
            return float(line.split("] [", 2)[1])
    raise RuntimeError(f"no log line with {text!r}")


def latency_in_process(source, target, query, small):
    """A fit in a thread, transfers every 10 ms in this one: latencies during the fit."""
    import threading

    done = threading.Event()

    def fit():
        LocalProcrustesAnalysis(**LONG_LPA).fit(source, target)
        done.set()

    expected = small.transfer(query)
    worker = threading.Thread(target=fit)
    worker.start()
    seconds, same = [], True
    while not done.is_set():
        start = time.perf_counter()
        same &= np.array_equal(small.transfer(query), expected)
        seconds.append(time.perf_counter() - start)
        time.sleep(0.01)
    worker.join()
    return seconds, same


def latency(args):
    import rclpy
    from rclpy.executors import SingleThreadedExecutor

    from lpa_transfer_interfaces.srv import FitModel, TransferPoints
    from bench.ros_harness import NodeProcess, call_service, ros_params, unique_domain_id
    from lpa_transfer_nodes.conversions import from_matrix, to_matrix

    work = Path(tempfile.mkdtemp(prefix="bench_mapping_latency_"))
    small_data, long_data = synthetic(2000, seed=4), synthetic(20_000, seed=5)
    query = source_points(args.transfer_points, seed=6)
    print(f"transfers of {len(query)} points 20-D -> 16-D every 10 ms, while a fit of "
          f"{len(long_data[0]):,} correspondences runs (load average before: "
          f"{os.getloadavg()[0]:.2f})", flush=True)
    small = LocalProcrustesAnalysis(**SMALL_LPA).fit(*small_data)
    seconds, same = latency_in_process(*long_data, query, small)
    print(f"  in process, fit in a thread:    {percentiles(seconds)}; same values: {same}",
          flush=True)
    domain_id = unique_domain_id()
    node = NodeProcess("lpa_mapping", domain_id, work / "log", ros_params(model_dir=work / "m"))
    context = rclpy.Context()
    rclpy.init(context=context, domain_id=domain_id)
    client_node = rclpy.create_node("bench_latency_client", context=context)
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(client_node)
    try:
        fit_client = client_node.create_client(FitModel, "/lpa_mapping/fit")
        transfer_client = client_node.create_client(TransferPoints, "/lpa_mapping/transfer")
        answer = call_service(executor, fit_client, FitModel.Request(
            model_id="small", method="lpa", source=to_matrix(small_data[0]),
            target=to_matrix(small_data[1]), **SMALL_LPA), timeout=120)
        assert answer.success, answer.message + node.log()

        def transfer():
            sent = time.time()
            start = time.perf_counter()
            result = call_service(executor, transfer_client, TransferPoints.Request(
                model_id="small", source=to_matrix(query)), timeout=60)
            elapsed = time.perf_counter() - start
            assert result.success, result.message
            return sent, elapsed, time.time(), from_matrix(result.target, "target")

        expected = transfer()[3]
        alone = []
        for _ in range(100):
            alone.append(transfer()[1])
            time.sleep(0.01)
        print(f"  service, nothing else running:  {percentiles(alone)}", flush=True)
        pending = fit_client.call_async(FitModel.Request(
            model_id="long", method="lpa", source=to_matrix(long_data[0]),
            target=to_matrix(long_data[1]), **LONG_LPA))
        calls = []
        while not pending.done():
            sent, elapsed, answered, values = transfer()
            calls.append((sent, elapsed, answered, np.array_equal(values, expected)))
            deadline = time.monotonic() + 0.01
            while time.monotonic() < deadline and not pending.done():
                executor.spin_once(timeout_sec=0.005)
        assert pending.result().success, pending.result().message + node.log()
        log = node.log()
        begin, end = (log_time(log, "fitting lpa model 'long'"),
                      log_time(log, "fitted lpa model 'long'"))
        during = [call for call in calls if begin <= call[0] and call[2] <= end]
        print(f"  service, during the fit ({end - begin:.1f} s): "
              f"{percentiles([call[1] for call in during])}; same values: "
              f"{all(call[3] for call in during)} (all {len(calls)} calls: "
              f"{all(call[3] for call in calls)})", flush=True)
        p99 = 1000 * np.percentile([call[1] for call in during], 99)
        print(f"goal <= 100 ms p99 during the fit: {'met' if p99 <= 100 else 'NOT met'} "
              f"({p99:.1f} ms); load average after: {os.getloadavg()[0]:.2f}")
    finally:
        executor.shutdown()
        client_node.destroy_node()
        rclpy.shutdown(context=context)
        node.stop()


if __name__ == "__main__":
    main()
