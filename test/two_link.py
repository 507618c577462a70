"""The §3.6 robots (thesis Table 3.1) as a test fixture: correspondences by joint angles."""
import numpy as np

from lpa_transfer.kinematics import domain_data, sample_joint_uniform

SOURCE_LINKS, TARGET_LINKS = (0.3, 0.25), (0.6, 0.2)
JOINT_LIMITS = [(0.0, np.pi / 2), (0.0, np.pi)]


def correspondences(n, seed, target_links=TARGET_LINKS):
    q = sample_joint_uniform(n, JOINT_LIMITS, np.random.default_rng(seed))
    return domain_data(q, SOURCE_LINKS), domain_data(q, target_links)


def mapping_rmse_mm(model, source_test, target_test):
    """RMSE (mm) of the transferred end-effector positions (columns 2-3)."""
    error = model.transfer(source_test)[:, 2:] - target_test[:, 2:]
    return 1000 * np.sqrt((error ** 2).sum(axis=1).mean())
