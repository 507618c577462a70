"""Time laws of point-to-point motions: where along a segment a robot is at each sample."""
import numpy as np


def minimum_jerk(n_samples):
    """s(τ) at τ = 1/n, 2/n, …, 1 (the leg's start excluded, its end included)."""
    tau = np.arange(1, n_samples + 1) / n_samples
    return 10 * tau ** 3 - 15 * tau ** 4 + 6 * tau ** 5
