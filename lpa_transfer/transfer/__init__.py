"""The transfer model: domain mappings fitted on correspondences of a source and a target robot.

PA with PCA (thesis §3.2, Alg. 1-2) and LPA (§3.3-3.5, Alg. 3-5) with its Gaussian mixture and
initEM; the versioned model file format and a directory of models keyed by id. The core of the
package: it imports nothing from the robot, exploration or chapter subpackages.
"""
from lpa_transfer._lazy import lazy_names

#: The public names and their modules, imported on first use (PEP 562), like every
#: subpackage's, so that importing one name does not import the whole package.
_LAZY = {
    **dict.fromkeys(["FitSpec", "limited"], "lpa_transfer.transfer.fit_spec"),
    **dict.fromkeys(["LocalProcrustesAnalysis"], "lpa_transfer.transfer.local_procrustes"),
    **dict.fromkeys(["load_model"], "lpa_transfer.transfer.model_io"),
    **dict.fromkeys(["METADATA", "file_name", "ModelStore", "transfer_in_blocks"],
                    "lpa_transfer.transfer.model_store"),
    **dict.fromkeys(["ProcrustesAnalysis"], "lpa_transfer.transfer.procrustes"),
    **dict.fromkeys(["check_batch", "check_transfer", "file_inside"],
                    "lpa_transfer.transfer.requests"),
}
__all__ = list(_LAZY)
__getattr__, __dir__ = lazy_names(__name__, _LAZY, globals())
