"""lpa_mapping: the mapping service — fits PA/LPA transfer models and transfers points.

Run: ``lpa_mapping --ros-args -p model_dir:=/path`` (or
``python -m lpa_transfer_nodes.lpa_mapping``).

A thin ROS adapter over :class:`lpa_transfer.transfer.model_store.ModelStore`. ``~/fit`` fits
a ``"pa"`` or ``"lpa"`` model on correspondences between a source and a target robot (given in
the request, read from a correspondence file inside ``data_dir``, or received on the
``correspondences`` and ``correspondence_batch`` topics) and stores it under a model id;
``~/transfer`` maps source points into the target domain through a stored model; ``~/list``,
``~/describe`` and ``~/delete`` manage the models. Models persist in ``model_dir`` and are reloaded on start, so
a restarted service answers as before. Every bad request is answered with ``success=false``
and the library's message; the node keeps serving.

Limits (parameters, :data:`LIMITS`): one request's work is bounded; a fit beyond them is
refused, naming the parameter; a transfer through an LPA model (Alg. 4) runs in blocks.

Concurrency: a MultiThreadedExecutor (``EXECUTOR_THREADS`` threads), ``~/fit`` in a mutually
exclusive callback group, the other services in a reentrant one and the topics in a third, so
that transfers on stored models are answered, with the same values, while a fit runs; the
store swaps a refitted model in atomically. Threads, not a worker process: numpy releases the
GIL in its BLAS calls and LPA's fit is vectorised (measurements: docs/nodes.md).
SIGINT/SIGTERM during a fit: the node exits without waiting for it (nothing is stored).

From your own node, call it through :class:`lpa_transfer_nodes.mapping_client.MappingClient`.
Parameters, topics, services and FitModel's hyperparameters (latent_dim, n_min, c_min, ...):
docs/nodes.md.
"""
import array
import json
import os
import sys
import threading
from functools import partial
from pathlib import Path

import numpy as np
from rclpy.callback_groups import MutuallyExclusiveCallbackGroup, ReentrantCallbackGroup
from rclpy.executors import MultiThreadedExecutor
from rclpy.node import Node

from lpa_transfer_nodes.conversions import from_matrix
from lpa_transfer_nodes.entry import serve
from lpa_transfer_nodes.params import declare_table, describe_use_sim_time
from lpa_transfer_nodes.qos import BATCH_QOS, SAMPLE_QOS
from lpa_transfer_nodes.servers import answering
from lpa_transfer.exploration.correspondences import read_correspondences
from lpa_transfer.transfer.fit_spec import FitSpec, limited
from lpa_transfer.transfer.model_store import METADATA, ModelStore, transfer_in_blocks
from lpa_transfer.transfer.requests import check_batch, check_transfer, file_inside
from lpa_transfer_interfaces.msg import CorrespondenceBatch, CorrespondenceSample, Matrix
from lpa_transfer_interfaces.srv import (DeleteModel, DescribeModel, FitModel, ListModels,
                                         TransferPoints)


#: Threads of the node's executor: a fit, the correspondence topics and concurrent transfers.
EXECUTOR_THREADS = 4
PARAMETERS = (
    ("model_dir", "~/.lpa_transfer/models", "directory where models are persisted, one .npz "
     "per model id; all are reloaded on start"),
    ("data_dir", "", "directory of the correspondence files FitModel's correspondence_file "
     "may name (relative to it; nothing outside it is read); empty: the folder "
     "'correspondences' beside model_dir"))
#: Limits of one request's work (:func:`lpa_transfer.transfer.fit_spec.limited`).
LIMITS = tuple(row + (dict(range=(1, None)),) for row in (
    ("max_fit_points", 200_000, "most correspondences one fit may use; a fit with more is "
                                "refused"),
    ("max_n_init", 20, "most initEM restarts (FitModel n_init) one LPA fit may ask for; more "
                       "is refused"),
    ("max_k_max", 2000, "most clusters one LPA fit may create: a larger FitModel k_max is "
                        "refused, k_max = 0 means this many"),
    ("transfer_block_elements", 20_000_000, "a transfer through an LPA model runs in blocks "
                                            "of rows of about this many points x clusters, "
                                            "so that its work memory stays bounded"),
    ("max_transfer_mib", 1024, "most memory one transfer may take, in MiB: its answer (points "
     "x target dimensions x 8 bytes) and its work arrays; a larger one is refused before "
     "anything is allocated")))


class MappingService(Node):
    """Thin ROS adapter over :class:`~lpa_transfer.transfer.model_store.ModelStore`."""

    def __init__(self):
        super().__init__("lpa_mapping")
        settings = declare_table(self, PARAMETERS)
        self.limits = declare_table(self, LIMITS)
        describe_use_sim_time(self)
        self.store = ModelStore(settings["model_dir"])
        self.data_dir = Path(settings["data_dir"] or self.store.directory.parent
                             / "correspondences")
        self.data_dir = self.data_dir.expanduser().resolve()
        self.received, self.received_robots, self.received_lock = {}, {}, threading.Lock()
        self.fitting = threading.Event()
        fits, answers, topics = (MutuallyExclusiveCallbackGroup(), ReentrantCallbackGroup(),
                                 MutuallyExclusiveCallbackGroup())
        self.create_subscription(CorrespondenceSample, "correspondences", self.on_sample,
                                 SAMPLE_QOS, callback_group=topics)
        self.create_subscription(CorrespondenceBatch, "correspondence_batch", self.on_batch,
                                 BATCH_QOS, callback_group=topics)
        for error in self.store.load_errors:
            self.get_logger().warning(f"skipped a model file: {error}")
        for name, srv_type, handler, group in (
                ("fit", FitModel, self.fit, fits),
                ("transfer", TransferPoints, self.transfer, answers),
                ("list", ListModels, self.list, answers),
                ("describe", DescribeModel, self.describe, answers),
                ("delete", DeleteModel, self.delete, answers)):
            self.create_service(srv_type, f"~/{name}", answering(self, name, handler),
                                callback_group=group)
        self.get_logger().info(f"serving {len(self.store.ids())} models from "
                               f"{self.store.directory}: {self.store.ids()}")

    def on_sample(self, msg):
        pair = f"{msg.source_robot}->{msg.target_robot}"
        with self.received_lock:
            if msg.index == 0 or pair not in self.received:
                self.received[pair] = {}
                self.received_robots[pair] = (msg.source_robot, msg.target_robot)
            self.received[pair][msg.index] = (np.array(msg.source), np.array(msg.target))

    def on_batch(self, msg):
        try:
            check_batch((msg.source.rows, msg.source.cols), (msg.target.rows, msg.target.cols),
                        self.limits["max_fit_points"])
            rows = zip(from_matrix(msg.source, "source"), from_matrix(msg.target, "target"))
        except ValueError as exc:
            self.get_logger().warning(f"ignoring a correspondence batch: {exc}")
            return
        pair = f"{msg.source_robot}->{msg.target_robot}"
        with self.received_lock:
            self.received[pair] = dict(enumerate(rows))
            self.received_robots[pair] = (msg.source_robot, msg.target_robot)

    def received_correspondences(self, pair):
        """(source, target) arrays of a received pair's correspondences, in index order, and
        the pair's robot names."""
        with self.received_lock:
            if pair not in self.received:
                raise ValueError(f"no correspondences received for the robot pair {pair!r}; "
                                 f"received: {sorted(self.received)}")
            samples = [self.received[pair][index] for index in sorted(self.received[pair])]
            robots = self.received_robots[pair]
        for side, name in enumerate(("source", "target")):
            widths = {len(sample[side]) for sample in samples}
            if len(widths) > 1:
                raise ValueError(f"the {name} samples received for {pair!r} have different "
                                 f"lengths {sorted(widths)}")
        source, target = (np.array([sample[side] for sample in samples]) for side in (0, 1))
        return source, target, dict(source_robot=robots[0], target_robot=robots[1])

    def correspondences(self, request):
        """The request's correspondences, its matrices, else its file (read_correspondences),
        else a received pair, as ``(source, target, metadata)``: what the file or the pair
        says of the robots and the columns, and where they came from."""
        if request.source.data or request.target.data:
            return (from_matrix(request.source, "source"), from_matrix(request.target, "target"),
                    dict(correspondences="request"))
        if request.correspondence_file:
            path = file_inside(self.data_dir, request.correspondence_file)
            pairs = read_correspondences(path)
            said = dict(zip(("source_robot", "target_robot", "source_features",
                             "target_features"),
                            (pairs.source_robot, pairs.target_robot, *pairs.columns())))
            return pairs.source, pairs.target, dict(
                {key: value for key, value in said.items() if value},
                correspondences=f"file {path}")
        if request.received_pair:
            source, target, metadata = self.received_correspondences(request.received_pair)
            return source, target, dict(metadata,
                                        correspondences=f"received {request.received_pair}")
        raise ValueError("no correspondences: send source and target, a correspondence_file "
                         "or a received_pair")

    def fit(self, request, response):
        source, target, found = self.correspondences(request)
        hyperparameters = limited(FitSpec.from_request(request).hyperparameters(), len(source),
                                  self.limits)
        metadata = dict(found, **{key: value for key, value in (
            ("source_robot", request.source_robot), ("target_robot", request.target_robot),
            ("source_features", list(request.source_features)),
            ("target_features", list(request.target_features))) if value})
        self.get_logger().info(f"fitting {request.method} model {request.model_id!r} on "
                               f"{len(source)} correspondences")
        self.fitting.set()
        try:
            model = self.store.fit(request.model_id, request.method, source, target, metadata,
                                   **hyperparameters)
        finally:
            self.fitting.clear()
        response.n_clusters = int(getattr(model, "n_clusters_", 1))
        response.n_points = int(model.n_correspondences_)
        response.training_rmse = self.store.metadata(request.model_id)["training_rmse"]
        message = (f"fitted {request.method} model {request.model_id!r}: "
                   f"{response.n_clusters} local maps from {response.n_points} correspondences")
        self.get_logger().info(message)
        return message

    def transfer(self, request, response):
        """Alg. 4 through a stored model, written straight into the answer's buffer; the
        request's points are let go before the answer is serialised (a huge transfer then
        holds about one copy of each side at a time, bench/bench_mapping_limits.py)."""
        source = from_matrix(request.source, "source")
        model = self.store.get(request.model_id)
        shape = check_transfer(model, source.shape, self.limits["transfer_block_elements"],
                               self.limits["max_transfer_mib"])
        data = array.array("d", [0.0]) * (shape[0] * shape[1])
        target = np.frombuffer(data, dtype=np.float64).reshape(shape)
        transfer_in_blocks(model, source, self.limits["transfer_block_elements"], out=target)
        del source, target                     # the views, so that the buffers can go
        request.source.data = array.array("d")
        response.target = Matrix(rows=shape[0], cols=shape[1], data=data)
        return f"transferred {shape[0]} points"

    def list(self, request, response):
        response.model_ids = self.store.ids()
        response.quarantined_ids = list(self.store.quarantined)
        quarantined = (f"; {len(response.quarantined_ids)} quarantined at start"
                       if response.quarantined_ids else "")
        return f"{len(response.model_ids)} models{quarantined}"

    def describe(self, request, response):
        info = self.store.describe(request.model_id)
        for field in ("method", "source_dim", "target_dim", "n_clusters", "n_points"):
            setattr(response, field, info[field])
        response.hyperparameters_json = json.dumps(info["hyperparameters"])
        for field in METADATA:
            setattr(response, field, info[field])
        return f"model {request.model_id!r}"

    def delete(self, request, response):
        self.store.delete(request.model_id)
        self.get_logger().info(f"deleted model {request.model_id!r}")
        return f"deleted model {request.model_id!r}"


def main(args=None):
    nodes = []
    serve("lpa_mapping", lambda stop: nodes.append(MappingService()) or nodes[0], args,
          executor_class=partial(MultiThreadedExecutor, num_threads=EXECUTOR_THREADS))
    if nodes and nodes[0].fitting.is_set():   # stopped during a fit: do not wait for it
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(0)


if __name__ == "__main__":
    main()
