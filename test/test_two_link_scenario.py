"""End-to-end run of scenarios/two_link_fk with smoke.toml (thesis §3.6, Fig. 3-6 / 3-8)."""
import csv
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

REPO = Path(__file__).resolve().parents[1]
SCENARIO = REPO / "scenarios" / "two_link_fk"


def read_rows(path):
    with open(path, newline="") as handle:
        reader = csv.DictReader(handle)
        return reader.fieldnames, list(reader)


@pytest.fixture(scope="module")
def smoke_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("two_link_fk")
    env = dict(os.environ, OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1",
               PYTHONPATH=os.pathsep.join(filter(None, [str(REPO), os.environ.get("PYTHONPATH")])))
    result = subprocess.run([sys.executable, str(SCENARIO / "run_two_link_fk.py"), "--config",
                             str(SCENARIO / "smoke.toml"), "--out", str(out)],
                            cwd=out, env=env, capture_output=True, text=True, timeout=120)
    assert result.returncode == 0, result.stderr
    return out, result


def test_outputs_exist_and_are_not_empty(smoke_run):
    out, result = smoke_run
    for name in ("size_sweep.csv", "link_sweep.csv", "fig3_6_mapping_and_model_error.png",
                 "fig3_8_link_sweep.png", "summary.txt", "config_used.toml"):
        assert (out / name).stat().st_size > 0, name
    for name in ("fig3_6_mapping_and_model_error.png", "fig3_8_link_sweep.png"):
        assert (out / name).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert (out / "config_used.toml").read_text() == (SCENARIO / "smoke.toml").read_text()
    assert "LPA/PA" in (out / "summary.txt").read_text()


def test_size_sweep_csv(smoke_run):
    fields, rows = read_rows(smoke_run[0] / "size_sweep.csv")
    assert fields == ["method", "n_train", "run", "mapping_rmse_m", "model_rmse_m",
                      "n_clusters"]
    assert len(rows) == 4 * 2 * 2          # methods x sizes [50, 400] x runs
    assert {r["method"] for r in rows} == {"PA", "LPA", "no_transfer", "ground_truth"}
    assert all(float(r["model_rmse_m"]) > 0 for r in rows)
    assert all(r["mapping_rmse_m"] == "" for r in rows if r["method"] in ("no_transfer",
                                                                            "ground_truth"))
    assert all(int(r["n_clusters"]) == 1 for r in rows if r["method"] == "PA")
    mapping = {m: np.mean([float(r["mapping_rmse_m"]) for r in rows
                           if r["method"] == m and r["n_train"] == "400"]) for m in ("PA", "LPA")}
    assert mapping["LPA"] < mapping["PA"]


def test_link_sweep_csv(smoke_run):
    fields, rows = read_rows(smoke_run[0] / "link_sweep.csv")
    assert fields[:5] == ["method", "target_link1_m", "target_link2_m", "delta_link1_m",
                          "delta_link2_m"]
    assert len(rows) == 2 * 3 * 3 * 1      # methods x 3 x 3 lengths x runs
    assert {float(r["target_link1_m"]) for r in rows} == {0.2, 0.6, 1.0}
    assert all(float(r["delta_link2_m"]) == pytest.approx(float(r["target_link2_m"]) - 0.25)
               for r in rows)


def test_same_seed_same_csv(smoke_run, tmp_path):
    """Reruns with the config's seed reproduce the CSVs byte for byte."""
    out, _ = smoke_run
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(filter(None, [str(REPO),
                                                                   os.environ.get("PYTHONPATH")])))
    subprocess.run([sys.executable, str(SCENARIO / "run_two_link_fk.py"), "--config",
                    str(SCENARIO / "smoke.toml"), "--out", str(tmp_path), "--seed", "0"],
                   env=env, check=True, capture_output=True, timeout=120)
    for name in ("size_sweep.csv", "link_sweep.csv"):
        assert (tmp_path / name).read_bytes() == (out / name).read_bytes()
