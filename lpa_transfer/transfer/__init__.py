"""The transfer model: domain mappings fitted on correspondences of a source and a target robot.

PA with PCA (thesis §3.2, Alg. 1-2) and LPA (§3.3-3.5, Alg. 3-5) with its Gaussian mixture and
initEM; the versioned model file format and a directory of models keyed by id. The core of the
package: it imports nothing from the robot, exploration or chapter subpackages.
"""
from lpa_transfer.transfer.local_procrustes import LocalProcrustesAnalysis
from lpa_transfer.transfer.model_io import load_model
from lpa_transfer.transfer.procrustes import ProcrustesAnalysis

__all__ = ["ProcrustesAnalysis", "LocalProcrustesAnalysis", "load_model"]
