"""A client of the mapping service (``lpa_mapping``) for your own rclpy nodes.

``MappingClient(node)`` wraps ``/lpa_mapping/{fit,transfer,describe,list,delete}``: numpy
arrays in, numpy arrays and dicts out, one blocking call each. Rows of ``source`` and
``target`` are correspondences (row i of each belongs together, thesis §3.1); a fitted model
lives in the service under ``model_id`` and maps any number of new source points into the
target domain (PA: Alg. 1-2, LPA: Alg. 3-5). A refused request raises ``RuntimeError`` with
the service's message.

    mapping = MappingClient(node)
    mapping.fit("pincher->youbot", source, target, method="lpa", n_min=40,
                source_robot="pincher", target_robot="youbot")
    target_points = mapping.transfer("pincher->youbot", new_source_points)
    mapping.describe("pincher->youbot")["n_clusters"]
    model_ids, quarantined_ids = mapping.list()
"""
import json
import threading
from collections import namedtuple
from dataclasses import fields

import numpy as np
import rclpy

from lpa_transfer.transfer.fit_spec import FitSpec
from lpa_transfer_interfaces.srv import (DeleteModel, DescribeModel, FitModel, ListModels,
                                         TransferPoints)
from lpa_transfer_nodes.calls import call_service, wait_for_services
from lpa_transfer_nodes.conversions import from_matrix, to_matrix

#: FitModel's hyperparameters a caller may set (0 or empty: the service's default,
#: :class:`~lpa_transfer.transfer.fit_spec.FitSpec`).
FIT_FIELDS = tuple(field.name for field in fields(FitSpec) if field.name != "method")
#: FitModel's metadata, stored with the model (empty: taken from a correspondence file or a
#: received pair where they say it).
METADATA_FIELDS = ("source_robot", "target_robot", "source_features", "target_features")
#: FitModel's other sources of correspondences, when ``source`` and ``target`` are not given.
SOURCE_FIELDS = ("correspondence_file", "received_pair")
#: What :meth:`MappingClient.describe` answers besides ``hyperparameters`` (a dict).
DESCRIBE_FIELDS = ("method", "source_dim", "target_dim", "n_clusters", "n_points",
                   "training_rmse", "source_robot", "target_robot", "source_features",
                   "target_features", "correspondences")
_LISTS = ("cluster_dims", "source_features", "target_features")

#: :meth:`MappingClient.list`'s answer: the served model ids and the ids of the model files
#: the service quarantined at its start (not served).
ModelList = namedtuple("ModelList", ("model_ids", "quarantined_ids"))


class MappingClient:
    """Blocking calls to a running ``lpa_mapping`` node from ``node`` (an rclpy Node that
    this client spins while it waits; do not spin it elsewhere at the same time).

    ``executor``: the executor ``node`` is already in (a job node's own, as the scenario
    experiments have); the client then waits by spinning it, and ``stop`` (a
    threading.Event, e.g. set on SIGINT) ends a wait early."""

    def __init__(self, node, service="/lpa_mapping", timeout=60.0, executor=None, stop=None):
        self.node, self.executor, self.stop = node, executor, stop
        self.timeout = float(timeout)
        self._clients = {name: node.create_client(srv_type, f"{service}/{name}")
                         for name, srv_type in (("fit", FitModel), ("transfer", TransferPoints),
                                                ("describe", DescribeModel),
                                                ("list", ListModels), ("delete", DeleteModel))}

    def fit(self, model_id, source=None, target=None, method="lpa", **fields):
        """Fit ``method`` ('pa' or 'lpa') on the correspondences ``source`` (N, D_s) and
        ``target`` (N, D_t) and keep it as ``model_id``; hyperparameters (:data:`FIT_FIELDS`)
        and metadata (:data:`METADATA_FIELDS`: robot names, one column name per dimension)
        as keyword arguments. Without ``source`` and ``target``, ``correspondence_file`` (in
        the service's data_dir) or ``received_pair`` names the correspondences. Returns the
        service's answer (``message``, ``n_clusters``, ``n_points``, ``training_rmse``)."""
        known = FIT_FIELDS + METADATA_FIELDS + SOURCE_FIELDS
        unknown = sorted(set(fields) - set(known))
        if unknown:
            raise ValueError(f"unknown fit fields {unknown}; known: {list(known)}")
        if (source is None) != (target is None):
            raise ValueError("give both source and target, or neither")
        if source is None and not any(fields.get(name) for name in SOURCE_FIELDS):
            raise ValueError(f"no correspondences: give source and target, or one of "
                             f"{list(SOURCE_FIELDS)}")
        request = FitModel.Request(model_id=model_id, method=method)
        if source is not None:
            request.source = to_matrix(_matrix(source, "source"))
            request.target = to_matrix(_matrix(target, "target"))
        for name, value in fields.items():
            setattr(request, name, list(value) if name in _LISTS else value)
        return self._call("fit", request)

    def transfer(self, model_id, source):
        """The target-domain points (N, D_t) of source points (N, D_s) through ``model_id``."""
        request = TransferPoints.Request(model_id=model_id,
                                         source=to_matrix(_matrix(source, "source")))
        return from_matrix(self._call("transfer", request).target, "target")

    def describe(self, model_id):
        """The model ``model_id`` as a dict: :data:`DESCRIBE_FIELDS` (sizes, the fit's
        training RMSE, the stored robot and column names, where the correspondences came
        from) and ``hyperparameters``, the fit settings (a dict)."""
        answer = self._call("describe", DescribeModel.Request(model_id=model_id))
        info = {name: getattr(answer, name) for name in DESCRIBE_FIELDS}
        for name in ("source_features", "target_features"):
            info[name] = list(info[name])
        info["hyperparameters"] = json.loads(answer.hyperparameters_json)
        return info

    def list(self):
        """The service's models: a :data:`ModelList` ``(model_ids, quarantined_ids)``."""
        answer = self._call("list", ListModels.Request())
        return ModelList(list(answer.model_ids), list(answer.quarantined_ids))

    def delete(self, model_id):
        """Delete the model ``model_id`` (its file too); returns the service's message."""
        return self._call("delete", DeleteModel.Request(model_id=model_id)).message

    def client(self, name):
        """The rclpy client of the service ``name`` (fit, transfer, describe, list, delete),
        e.g. to wait for it with others."""
        return self._clients[name]

    def _call(self, name, request):
        _check_strings(request)
        client = self._clients[name]
        if self.executor is not None:     # a job node's executor: the project's waits
            stop = self.stop or threading.Event()
            wait_for_services([client], self.timeout, stop, self.executor)
            answer = call_service(self.executor, client, request, self.timeout, stop)
        else:
            if not client.wait_for_service(timeout_sec=self.timeout):
                raise RuntimeError(f"{client.srv_name} is not available (is lpa_mapping "
                                   f"running on this ROS_DOMAIN_ID?)")
            future = client.call_async(request)
            rclpy.spin_until_future_complete(self.node, future, timeout_sec=self.timeout)
            if not future.done():
                client.remove_pending_request(future)
                raise RuntimeError(f"{client.srv_name} did not answer within {self.timeout} s")
            answer = future.result()
        if not answer.success:
            raise RuntimeError(f"{client.srv_name} refused the request: {answer.message}")
        return answer


def _matrix(values, name):
    values = np.asarray(values, dtype=np.float64)
    if values.ndim != 2:
        raise ValueError(f"{name} must be a 2-D array (points x dimensions), got shape "
                         f"{values.shape}")
    return values


def _check_strings(request):
    """ValueError for a string field (or a string in a list field) of ``request`` with a NUL
    character: rclpy would cut it there, so "a\\0b" would reach the service as "a" (and
    fitting "a\\0b" would overwrite the model "a")."""
    for field in request.get_fields_and_field_types():
        value = getattr(request, field)
        for text in ([value] if isinstance(value, str) else
                     value if isinstance(value, list) else ()):
            if isinstance(text, str) and "\0" in text:
                raise ValueError(f"{field} {text!r} contains a NUL character, which a ROS 2 "
                                 f"string cannot carry (it would be cut there)")
