"""The README's library example runs as printed and its transfer is as good as it says."""
import re
import subprocess
import sys

from conftest import ROOT


def test_the_readme_library_example_fits_and_transfers_with_pa_and_lpa(tmp_path):
    section = (ROOT / "README.md").read_text().split("\n## The library\n", 1)[1]
    code = section.split("```python\n", 1)[1].split("```", 1)[0]   # its first python block
    assert len(code.splitlines()) <= 20
    run = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, capture_output=True,
                         text=True, timeout=120)
    assert run.returncode == 0, run.stdout + run.stderr
    errors = dict(re.findall(r"(\w+): mean task-space error ([0-9.]+) mm", run.stdout))
    assert set(errors) == {"ProcrustesAnalysis", "LocalProcrustesAnalysis"}, run.stdout
    # the README: about 50 mm for PA, a few mm for LPA
    assert 30 < float(errors["ProcrustesAnalysis"]) < 80, run.stdout
    assert float(errors["LocalProcrustesAnalysis"]) < 10, run.stdout
    assert (tmp_path / "model.npz").exists()
