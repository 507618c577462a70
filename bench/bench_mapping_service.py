"""Round-trip time of the lpa_mapping service's TransferPoints for 16,800 points of 20-D.

Starts the mapping node as its own process (a fresh ROS domain and model directory), fits the
inverse-dynamics LPA model through ``~/fit`` (bench/datasets.py: 1464 correspondences,
latent_dim 16, n_min 40, c_min 1e-7, cluster_dims 0-9, as in bench_lpa.py), then calls
``~/transfer`` with the 16,800 held-out source points ``--calls`` times. Printed, as medians:

* end to end: build the request Matrix, call, wait for the answer, read the (16,800 x 16)
  result back into NumPy — what a client sees;
* client build / client read: the request's ``array.array`` copy and ``np.frombuffer`` alone;
* node's handler: the transfer callback's own time (Matrix -> NumPy, transfer, NumPy ->
  Matrix), from the node's debug log;
* library transfer: ``model.transfer`` in this process on the model file the service saved;
* CDR (de)serialisation of request and response (``rclpy.serialization``), an estimate of the
  copying rclpy does on both sides.
The rest of end to end is DDS transport and the executors. Goal (issue 3): < 100 ms.

Usage: ``python -m bench.bench_mapping_service [--calls 15]`` (from the repository root).
"""
import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_var] = "1"

import argparse  # noqa: E402
import re  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
from bench import datasets  # noqa: E402
from bench.bench_lpa import INVERSE_DYNAMICS  # noqa: E402
from lpa_transfer import load_model  # noqa: E402
from lpa_transfer.transfer.model_store import file_name  # noqa: E402
from bench.ros_harness import NodeProcess, call_service, ros_params, unique_domain_id  # noqa: E402

import rclpy  # noqa: E402
from rclpy.executors import SingleThreadedExecutor  # noqa: E402
from rclpy.serialization import deserialize_message, serialize_message  # noqa: E402

from lpa_transfer_nodes.conversions import from_matrix, to_matrix  # noqa: E402
from lpa_transfer_interfaces.srv import FitModel, TransferPoints  # noqa: E402

MODEL_ID = "youbot->pincher/inverse-dynamics"


def median_ms(function, calls):
    times = []
    for _ in range(calls):
        start = time.perf_counter()
        function()
        times.append(time.perf_counter() - start)
    return 1000 * float(np.median(times)), 1000 * float(np.percentile(times, 90))


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--calls", type=int, default=15)
    calls = parser.parse_args().calls
    data = datasets.inverse_dynamics()
    held_out = np.ascontiguousarray(data["source_held_out"])
    work = Path(tempfile.mkdtemp(prefix="bench_mapping_"))
    domain_id = unique_domain_id()
    node = NodeProcess("lpa_mapping", domain_id, work / "log",
                       ros_params(model_dir=work / "m") + ["--log-level", "lpa_mapping:=debug"])
    context = rclpy.Context()
    rclpy.init(context=context, domain_id=domain_id)
    client_node = rclpy.create_node("bench_mapping_client", context=context)
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(client_node)
    try:
        fit_client = client_node.create_client(FitModel, "/lpa_mapping/fit")
        transfer_client = client_node.create_client(TransferPoints, "/lpa_mapping/transfer")
        fit_request = FitModel.Request(
            model_id=MODEL_ID, method="lpa", source=to_matrix(data["source"]),
            target=to_matrix(data["target"]), **INVERSE_DYNAMICS)
        start = time.perf_counter()
        answer = call_service(executor, fit_client, fit_request, timeout=120)
        fit_ms = 1000 * (time.perf_counter() - start)
        assert answer.success, answer.message + node.log()

        def round_trip():
            request = TransferPoints.Request(model_id=MODEL_ID, source=to_matrix(held_out))
            result = call_service(executor, transfer_client, request)
            assert result.success, result.message
            return from_matrix(result.target, "target")

        expected = round_trip()                          # warm-up, and the value to check
        end_to_end = median_ms(round_trip, calls)
        model = load_model(work / "m" / file_name(MODEL_ID))
        assert np.array_equal(model.transfer(held_out), expected)
        request = TransferPoints.Request(model_id=MODEL_ID, source=to_matrix(held_out))
        response = TransferPoints.Response(success=True, target=to_matrix(expected))
        handled = [float(ms) for ms in re.findall(r"transfer handled in ([\d.]+) ms", node.log())]
        figures = {
            "end to end (build, call, read)": end_to_end,
            "node's transfer handler (its debug log)": (
                float(np.median(handled[1:])), float(np.percentile(handled[1:], 90))),
            "client build of the request Matrix": median_ms(lambda: to_matrix(held_out), calls),
            "client read of the result": median_ms(lambda: from_matrix(response.target, "target"), calls),
            "library transfer in process": median_ms(lambda: model.transfer(held_out), calls),
            "CDR serialise + deserialise request": median_ms(lambda: deserialize_message(
                serialize_message(request), TransferPoints.Request), calls),
            "CDR serialise + deserialise response": median_ms(lambda: deserialize_message(
                serialize_message(response), TransferPoints.Response), calls),
        }
    finally:
        executor.shutdown()
        client_node.destroy_node()
        rclpy.shutdown(context=context)
        node.stop()
    print(f"TransferPoints, {held_out.shape[0]} x {held_out.shape[1]} -> "
          f"{expected.shape[0]} x {expected.shape[1]}, {calls} calls "
          f"(model: {answer.n_clusters} local maps; fit through the service {fit_ms:.0f} ms)")
    for name, (median, p90) in figures.items():
        print(f"  {name:<40} median {median:7.1f} ms   p90 {p90:7.1f} ms")
    print(f"goal < 100 ms end to end: {'met' if end_to_end[0] < 100 else 'NOT met'}")


if __name__ == "__main__":
    main()
