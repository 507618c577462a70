"""lpa_mapping: the mapping service — fits PA/LPA transfer models and transfers points.

Run: ``lpa_mapping --ros-args -p model_dir:=/path`` (or ``python -m lpa_transfer_nodes.lpa_mapping``).

Parameter ``model_dir`` (default ``~/.lpa_transfer/models``): where models are persisted, one
``.npz`` per model id (:mod:`lpa_transfer.model_store`); all are reloaded on start, so a
restarted service answers as before.

Services, under the node's name (``/lpa_mapping/...`` by default), types in
``lpa_transfer_interfaces/srv``:

* ``~/fit`` (FitModel): fit a ``"pa"`` or ``"lpa"`` model on the correspondences in the
  request and store it under ``model_id``. ``latent_dim = 0`` and ``k_max = 0`` mean "no
  limit", ``n_min = 0`` and ``n_init = 0`` the library defaults (7 and 3), and an empty
  ``cluster_dims`` means all source dimensions (the library's ``None``);
  PA uses only ``latent_dim``. When ``source`` and ``target`` are both empty, the
  correspondences are read from ``correspondence_file``: a NumPy ``.npz`` with the arrays
  ``source`` (N, D_s) and ``target`` (N, D_t), row i of each in correspondence.
* ``~/transfer`` (TransferPoints): map source points through a stored model.
* ``~/list`` (ListModels), ``~/describe`` (DescribeModel), ``~/delete`` (DeleteModel).

Every bad request (unknown id or method, rows*cols not matching the data, NaN/inf, too few
points, wrong widths) is answered with ``success=false`` and the library's message; any other
error is logged and answered the same way, so the node keeps serving.
"""
import array
import json

from rclpy.node import Node

from lpa_transfer_nodes._ros_util import answering, init_with_stop_event, spin_until_stopped
from lpa_transfer import LocalProcrustesAnalysis
from lpa_transfer.model_store import (ModelStore, load_correspondences, matrix_from_rows,
                                      training_rmse)
from lpa_transfer_interfaces.msg import Matrix
from lpa_transfer_interfaces.srv import (DeleteModel, DescribeModel, FitModel, ListModels,
                                         TransferPoints)


def to_matrix(values):
    """A Matrix message of a 2-D float64 array (fast buffer copy, see the ROS notes)."""
    return Matrix(rows=values.shape[0], cols=values.shape[1],
                  data=array.array("d", values.astype("float64", order="C").tobytes()))


def from_matrix(msg, name):
    return matrix_from_rows(msg.rows, msg.cols, msg.data, name)


LPA_DEFAULTS = LocalProcrustesAnalysis().get_params()


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


class MappingService(Node):
    """Thin ROS adapter over :class:`~lpa_transfer.model_store.ModelStore`."""

    def __init__(self):
        super().__init__("lpa_mapping")
        model_dir = self.declare_parameter("model_dir", "~/.lpa_transfer/models").value
        self.store = ModelStore(model_dir)
        for error in self.store.load_errors:
            self.get_logger().warning(f"skipped a model file: {error}")
        for name, srv_type, handler in (
                ("fit", FitModel, self.fit), ("transfer", TransferPoints, self.transfer),
                ("list", ListModels, self.list), ("describe", DescribeModel, self.describe),
                ("delete", DeleteModel, self.delete)):
            self.create_service(srv_type, f"~/{name}", answering(self, name, handler))
        self.get_logger().info(f"serving {len(self.store.ids())} models from "
                               f"{self.store.directory}: {self.store.ids()}")

    def fit(self, request, response):
        if request.source.data or request.target.data or not request.correspondence_file:
            source = from_matrix(request.source, "source")
            target = from_matrix(request.target, "target")
        else:
            source, target = load_correspondences(request.correspondence_file)
        model = self.store.fit(request.model_id, request.method, source, target,
                               **fit_hyperparameters(request))
        response.n_clusters = int(getattr(model, "n_clusters_", 1))
        response.n_points = int(model.n_correspondences_)
        response.training_rmse = training_rmse(model, source, target)
        message = (f"fitted {request.method} model {request.model_id!r}: "
                   f"{response.n_clusters} local maps from {response.n_points} correspondences")
        self.get_logger().info(message)
        return message

    def transfer(self, request, response):
        target = self.store.transfer(request.model_id, from_matrix(request.source, "source"))
        response.target = to_matrix(target)
        return f"transferred {len(target)} points"

    def list(self, request, response):
        response.model_ids = self.store.ids()
        return f"{len(response.model_ids)} models"

    def describe(self, request, response):
        info = self.store.describe(request.model_id)
        for field in ("method", "source_dim", "target_dim", "n_clusters", "n_points"):
            setattr(response, field, info[field])
        response.hyperparameters_json = json.dumps(info["hyperparameters"])
        return f"model {request.model_id!r}"

    def delete(self, request, response):
        self.store.delete(request.model_id)
        self.get_logger().info(f"deleted model {request.model_id!r}")
        return f"deleted model {request.model_id!r}"


def main(args=None):
    stop = init_with_stop_event(args)
    spin_until_stopped(MappingService(), stop)


if __name__ == "__main__":
    main()
