"""The README's client example runs as printed against a real lpa_mapping node (its own
process, its own ROS domain), and its transfer is as good as the README says."""
import re
import subprocess
import sys

from conftest import ROOT
from ros_harness import NodeProcess, ros_env, ros_params, unique_domain_id


def readme_example():
    """The first python block after the README's 'Call the mapping service' heading."""
    text = (ROOT / "README.md").read_text()
    start = text.index("Call the mapping service from your node")
    return re.search(r"```python\n(.*?)```", text[start:], re.S).group(1)


def test_the_readme_client_example_fits_and_transfers_through_the_service(tmp_path):
    code = readme_example()
    assert len(code.splitlines()) <= 25
    assert "_ros_util" not in code and "lpa_transfer_nodes._" not in code   # public code only
    domain_id = unique_domain_id()
    args = ros_params(model_dir=str(tmp_path / "models"))
    with NodeProcess("lpa_mapping", domain_id, tmp_path, args):
        run = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, capture_output=True,
                             text=True, timeout=120, env=ros_env(domain_id, tmp_path))
    assert run.returncode == 0, run.stdout + run.stderr
    errors = [float(v) for v in re.findall(r"error ([0-9.]+) mm", run.stdout)]
    assert len(errors) == 1 and errors[0] < 10.0, run.stdout   # the README promises a few mm
    assert (tmp_path / "models").exists()
