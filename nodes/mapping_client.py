"""A client of the mapping service (``lpa_mapping``) for your own rclpy nodes.

``MappingClient(node)`` wraps ``/lpa_mapping/fit`` and ``/lpa_mapping/transfer``: numpy arrays
in, numpy arrays out, one blocking call each. Rows of ``source`` and ``target`` are
correspondences (row i of each belongs together, thesis §3.1); a fitted model lives in the
service under ``model_id`` and maps any number of new source points into the target domain
(PA: Alg. 1-2, LPA: Alg. 3-5). A refused request raises ``RuntimeError`` with the service's
message.

    mapping = MappingClient(node)
    mapping.fit("pincher->youbot", source, target, method="lpa", n_min=40)
    target_points = mapping.transfer("pincher->youbot", new_source_points)
"""
import numpy as np
import rclpy

from lpa_transfer_interfaces.srv import FitModel, TransferPoints
from lpa_transfer_nodes._ros_util import from_matrix, to_matrix

#: FitModel fields a caller may set (0 or empty: the service's default; see lpa_mapping).
FIT_FIELDS = ("latent_dim", "n_min", "c_min", "k_max", "cluster_dims", "n_init",
              "random_state")


class MappingClient:
    """Blocking calls to a running ``lpa_mapping`` node from ``node`` (an rclpy Node that
    this client spins while it waits; do not spin it elsewhere at the same time)."""

    def __init__(self, node, service="/lpa_mapping", timeout=60.0):
        self.node = node
        self.timeout = float(timeout)
        self._fit = node.create_client(FitModel, f"{service}/fit")
        self._transfer = node.create_client(TransferPoints, f"{service}/transfer")

    def fit(self, model_id, source, target, method="lpa", **fields):
        """Fit ``method`` ('pa' or 'lpa') on the correspondences ``source`` (N, D_s) and
        ``target`` (N, D_t) and keep it as ``model_id``; hyperparameters as keyword
        arguments (:data:`FIT_FIELDS`). Returns the service's answer (``message``,
        ``n_clusters``, ``n_points``, ``training_rmse``)."""
        unknown = sorted(set(fields) - set(FIT_FIELDS))
        if unknown:
            raise ValueError(f"unknown fit fields {unknown}; known: {list(FIT_FIELDS)}")
        request = FitModel.Request(model_id=model_id, method=method,
                                   source=to_matrix(_matrix(source, "source")),
                                   target=to_matrix(_matrix(target, "target")))
        for name, value in fields.items():
            setattr(request, name, list(value) if name == "cluster_dims" else value)
        return self._call(self._fit, request)

    def transfer(self, model_id, source):
        """The target-domain points (N, D_t) of source points (N, D_s) through ``model_id``."""
        request = TransferPoints.Request(model_id=model_id,
                                         source=to_matrix(_matrix(source, "source")))
        return from_matrix(self._call(self._transfer, request).target, "target")

    def _call(self, client, request):
        if not client.wait_for_service(timeout_sec=self.timeout):
            raise RuntimeError(f"{client.srv_name} is not available (is lpa_mapping running "
                               f"on this ROS_DOMAIN_ID?)")
        future = client.call_async(request)
        rclpy.spin_until_future_complete(self.node, future, timeout_sec=self.timeout)
        if not future.done():
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
