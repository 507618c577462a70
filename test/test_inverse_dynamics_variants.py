"""Variants of the chapter 5 graph scenario (scenarios/inverse_dynamics/run.sh with the
smoke.yaml override), each its own run and independent of test_inverse_dynamics_scenario.py's
smoke run, so that they run beside it: start noise over two seeds, and a youBot <-> 2-link
pair (5 and 2 joints). Every node a real process over DDS."""
import json

import numpy as np
import pytest

from conftest import ROOT
from lpa_transfer.inverse_dynamics.report import merge
from lpa_transfer_nodes.testing import run_scenario

SCENARIO = ROOT / "scenarios" / "inverse_dynamics"
# over setup.cfg's 300 s: each run takes minutes
pytestmark = [pytest.mark.timeout(600), pytest.mark.slow]


def test_start_noise_gives_every_seed_its_own_run_from_scratch(tmp_path):
    """``start_noise``: every seed starts its runs, learning from scratch included, from its
    own perturbed rest pose, so the scratch curves of two seeds differ; they still learn."""
    share = tmp_path / "noise.yaml"
    share.write_text("experiment:\n  ros__parameters:\n    seeds: [0, 1]\n"
                     "    conditions: [random]\n    start_noise: 0.001\n")
    out = tmp_path / "run"
    result = run_scenario(SCENARIO, out, "config.yaml", timeout=480,
                          overrides=["smoke.yaml", share])
    assert result.returncode == 0, result.stdout + result.stderr
    results = json.loads((out / "results.json").read_text())
    assert results["settings"]["start_noise"] == 0.001 and results["seeds"] == [0, 1]
    for robot in ("youbot", "pincher"):
        scratch = np.asarray(results["curves_m"][f"{robot}/star1/uninitialised"])
        assert scratch.shape == (2, 2) and (scratch[:, 1] < scratch[:, 0]).all()
        assert not np.allclose(scratch[0], scratch[1], rtol=1e-6, atol=0)
    assert "learning from scratch for every seed" in (out / "report.txt").read_text()
    merged, _, experiment = merge([out])        # its own check: scratch differs by seed
    assert experiment.start_noise == 0.001 and len(merged) == 2 * 2


def test_transfer_between_arms_with_5_and_2_joints(tmp_path):
    """youbot_two_link.yaml: the same graph with a planar 2-link arm (2-D task space); the
    conditions that use the pairs and both mappings (the rest is wiring the smoke run
    checks)."""
    share = tmp_path / "transfer.yaml"
    share.write_text("experiment:\n  ros__parameters:\n"
                     "    conditions: [random, transfer-PA, transfer-LPA]\n")
    out = tmp_path / "run"
    result = run_scenario(SCENARIO, out, "youbot_two_link.yaml", timeout=480,
                          overrides=["smoke.yaml", share])
    assert result.returncode == 0, result.stdout + result.stderr
    curves = json.loads((out / "results.json").read_text())["curves_m"]
    for robot in ("youbot", "two_link"):
        for condition in ("uninitialised", "random", "transfer-PA", "transfer-LPA"):
            runs = np.asarray(curves[f"{robot}/star1/{condition}"])
            assert runs.shape == (1, 2) and np.isfinite(runs).all() and (runs > 0).all()
        scratch = curves[f"{robot}/star1/uninitialised"][0]
        assert scratch[1] < scratch[0]
    with np.load(out / "pairs_0_star1.npz") as pairs:      # (q, q̇, q̈, τ) of 5 and 2 joints
        assert pairs["source"].shape == (180, 20) and pairs["target"].shape == (180, 8)
    models = sorted(p.name for p in (out / "models").iterdir())
    assert len(models) == 4
