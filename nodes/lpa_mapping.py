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

Limits (parameters): one request's work is bounded. A fit of more than ``max_fit_points``
correspondences, with more than ``max_n_init`` initEM restarts (LPA Alg. 5) or a ``k_max``
above ``max_k_max`` is refused, naming the parameter and its value; ``k_max = 0`` means at
most ``max_k_max`` clusters (the same model as an unbounded fit that stays below it). A
transfer through an LPA model (Alg. 4) runs in blocks of about ``transfer_block_elements``
points x clusters (:func:`lpa_transfer.transfer.model_store.transfer_in_blocks`).

Concurrency: the node runs on a MultiThreadedExecutor (``EXECUTOR_THREADS`` threads) with
three callback groups: ``~/fit`` in a mutually exclusive group (one fit at a time),
``~/transfer``, ``~/describe``, ``~/list`` and ``~/delete`` in a reentrant group, the
correspondence topics in a third group. A fit thus runs in its own thread while transfers on
stored models are answered in others, with the same values as when nothing else runs; the
store swaps a refitted model in atomically under its lock, so until the new model is saved
the old one answers. Threads, not a worker process: numpy releases the GIL in its BLAS calls
and array loops, and LPA's fit (Alg. 3, 5) is vectorised (no per-point Python loop), so its
Python holds the GIL only in short stretches. Measured (bench/bench_mapping_limits.py
``--latency``, bench/README.md): transfers answered within the 100 ms p99 goal while a
20,000-point 20-D LPA fit runs; a worker process would add pickling of the correspondences
and the model and a second interpreter for no gain in latency. SIGINT/SIGTERM during a fit:
the node exits without waiting for it (nothing is stored; an interrupted save leaves the old
file, see the model store).

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
from lpa_transfer_nodes.params import declare, describe_use_sim_time
from lpa_transfer_nodes.qos import BATCH_QOS, SAMPLE_QOS
from lpa_transfer_nodes.servers import answering
from lpa_transfer import LocalProcrustesAnalysis
from lpa_transfer.exploration.correspondences import load_correspondences
from lpa_transfer.exploration.correspondences import JOINT_FEATURES
from lpa_transfer.transfer.model_store import METADATA, ModelStore, transfer_in_blocks
from lpa_transfer_interfaces.msg import CorrespondenceBatch, CorrespondenceSample, Matrix
from lpa_transfer_interfaces.srv import (DeleteModel, DescribeModel, FitModel, ListModels,
                                         TransferPoints)


LPA_DEFAULTS = LocalProcrustesAnalysis().get_params()
#: Threads of the node's executor: a fit, the correspondence topics and concurrent transfers.
EXECUTOR_THREADS = 4


def fit_hyperparameters(request):
    """The library's hyperparameters from a FitModel request.

    0 / empty mean None for latent_dim, k_max and cluster_dims, and the library default for
    n_min and n_init (a request that leaves them unset gets a working model). c_min is taken
    as given: 0 is meaningful ("always split", the thesis' advice to control K with n_min).
    """
    latent_dim = request.latent_dim or None
    if request.method != "lpa":
        return dict(latent_dim=latent_dim)
    return dict(latent_dim=latent_dim, n_min=request.n_min or LPA_DEFAULTS["n_min"],
                c_min=request.c_min, k_max=request.k_max or None,
                cluster_dims=list(request.cluster_dims) or None,
                n_init=request.n_init or LPA_DEFAULTS["n_init"],
                random_state=request.random_state)


#: Limits of one request's work: parameter name -> (default, description).
LIMITS = {
    "max_fit_points": (200_000, "most correspondences one fit may use; a fit with more is "
                                "refused"),
    "max_n_init": (20, "most initEM restarts (FitModel n_init) one LPA fit may ask for; more is "
                       "refused"),
    "max_k_max": (2000, "most clusters one LPA fit may create: a larger FitModel k_max is "
                        "refused, k_max = 0 means this many"),
    "transfer_block_elements": (20_000_000, "a transfer through an LPA model runs in blocks of "
                                            "rows of about this many points x clusters, so "
                                            "that its work memory stays bounded"),
}


def limited(hyperparameters, n_points, limits):
    """The hyperparameters of a fit within the service's ``limits`` (parameter -> value):
    ``k_max = None`` (0 in the request) becomes ``max_k_max``; more correspondences than
    ``max_fit_points``, an n_init above ``max_n_init`` or a k_max above ``max_k_max`` is a
    ValueError naming the limit parameter and its value."""
    def refuse(what, name):
        raise ValueError(f"{what} exceeds the limit {name} = {limits[name]} (a parameter of "
                         f"lpa_mapping)")
    if n_points > limits["max_fit_points"]:
        refuse(f"the fit's {n_points} correspondences", "max_fit_points")
    hyperparameters = dict(hyperparameters)
    if "n_init" in hyperparameters:
        if hyperparameters["n_init"] > limits["max_n_init"]:
            refuse(f"n_init = {hyperparameters['n_init']}", "max_n_init")
        if hyperparameters["k_max"] is None:
            hyperparameters["k_max"] = limits["max_k_max"]
        elif hyperparameters["k_max"] > limits["max_k_max"]:
            refuse(f"k_max = {hyperparameters['k_max']}", "max_k_max")
    return hyperparameters


def feature_columns(features, width):
    """Names of the ``width`` columns of samples made of ``features`` (the correspondence
    files' ``features``, in the order ``feature_vector`` concatenates them): a joint feature
    gives one column per joint (``position[0]``, ``position[1]``, ...), any other one column
    (``ee_x``); ``[]`` when ``width`` does not fit them."""
    features = [str(feature) for feature in features]
    joint = [feature for feature in features if feature in JOINT_FEATURES]
    n_joints, rest = divmod(width - (len(features) - len(joint)), max(1, len(joint)))
    if not features or rest or n_joints < (1 if joint else 0) or (not joint and n_joints):
        return []
    names = []
    for feature in features:
        names += ([f"{feature}[{j}]" for j in range(n_joints)] if feature in JOINT_FEATURES
                  else [feature])
    return names


def file_metadata(path, source_dim, target_dim):
    """What a correspondence file says of its robots and columns (its ``source_robot``,
    ``target_robot`` and ``features`` entries, as the collector saves them): metadata for
    the model; ``{}`` for what it does not have."""
    try:
        with np.load(path, allow_pickle=False) as archive:
            entries = {key: archive[key] for key in ("source_robot", "target_robot", "features")
                       if key in archive.files}
    except (OSError, ValueError):
        return {}
    metadata = {key: str(entries[key]) for key in ("source_robot", "target_robot")
                if key in entries and entries[key].ndim == 0}
    if "features" in entries and entries["features"].ndim == 1:
        metadata["source_features"] = feature_columns(entries["features"], source_dim)
        metadata["target_features"] = feature_columns(entries["features"], target_dim)
    return {key: value for key, value in metadata.items() if value}


class MappingService(Node):
    """Thin ROS adapter over :class:`~lpa_transfer.transfer.model_store.ModelStore`."""

    def __init__(self):
        super().__init__("lpa_mapping")
        model_dir = declare(self, "model_dir", "~/.lpa_transfer/models",
                            "directory where models are persisted, one .npz per model id; all "
                            "are reloaded on start")
        data_dir = declare(self, "data_dir", "",
                           "directory of the correspondence files FitModel's correspondence_file "
                           "may name (relative to it; nothing outside it is read); empty: the "
                           "folder 'correspondences' beside model_dir")
        self.limits = {name: declare(self, name, default, description, range=(1, None))
                       for name, (default, description) in LIMITS.items()}
        describe_use_sim_time(self)
        self.store = ModelStore(model_dir)
        self.data_dir = Path(data_dir or self.store.directory.parent / "correspondences")
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

    def correspondence_path(self, name):
        """The file ``name`` names inside ``data_dir`` (a relative name is taken in it); one
        that resolves outside it (an absolute path, ``..``, a symbolic link) is a ValueError."""
        path = (self.data_dir / name).resolve()
        if not path.is_relative_to(self.data_dir):
            raise ValueError(f"correspondence_file {name!r} is outside the data directory "
                             f"{self.data_dir} (the parameter data_dir): only files in it are "
                             f"read; give a path relative to it")
        return path

    def correspondences(self, request):
        """The request's correspondences, its matrices, else its file, else a received pair,
        as ``(source, target, metadata)``: what the file or the pair says of the robots and
        the columns (:func:`file_metadata`), and where they came from."""
        if request.source.data or request.target.data:
            return (from_matrix(request.source, "source"), from_matrix(request.target, "target"),
                    dict(correspondences="request"))
        if request.correspondence_file:
            path = self.correspondence_path(request.correspondence_file)
            source, target = load_correspondences(path)
            return source, target, dict(file_metadata(path, source.shape[1], target.shape[1]),
                                        correspondences=f"file {path}")
        if request.received_pair:
            source, target, metadata = self.received_correspondences(request.received_pair)
            return source, target, dict(metadata,
                                        correspondences=f"received {request.received_pair}")
        raise ValueError("no correspondences: send source and target, a correspondence_file "
                         "or a received_pair")

    def fit(self, request, response):
        source, target, found = self.correspondences(request)
        hyperparameters = limited(fit_hyperparameters(request), len(source), self.limits)
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
        shape = (len(source), int(model.n_features_out_))
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
