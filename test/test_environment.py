"""tools/env.sh: the environment every run script and the tests start from."""
import json
import subprocess
from pathlib import Path

import pytest

from conftest import ROOT

PROBE = """
import json, os, numpy, threadpoolctl
from numpy._core._multiarray_umath import __cpu_features__ as features
blas = [i for i in threadpoolctl.threadpool_info() if i["internal_api"] == "openblas"]
print(json.dumps({"coretype": os.environ.get("OPENBLAS_CORETYPE"),
                  "architectures": sorted({i["architecture"] for i in blas}),
                  "avx512f": bool(features.get("AVX512F"))}))
"""


def _host_has(*flags):
    words = set(Path("/proc/cpuinfo").read_text().split())
    return all(flag in words for flag in flags)


@pytest.mark.skipif(not _host_has("avx2", "fma"), reason="the pin applies to AVX2 + FMA hosts")
def test_env_pins_the_blas_kernels_and_numpy_simd_level():
    """The learners' curves depend on the BLAS kernels' rounding (docs/history.md), so every
    host with AVX2 and FMA runs OpenBLAS's Haswell kernels and numpy's loops up to AVX2."""
    script = f"source {ROOT / 'tools' / 'env.sh'} && python -c '{PROBE}'"
    result = subprocess.run(["bash", "-c", script], capture_output=True, text=True, timeout=60,
                            env={"PATH": "/usr/bin:/bin", "HOME": str(Path.home())})
    assert result.returncode == 0, result.stderr
    probe = json.loads(result.stdout)
    assert probe["coretype"] == "Haswell"          # set, not merely this host's default
    assert probe["architectures"] == ["Haswell"] and not probe["avx512f"]
