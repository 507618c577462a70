"""The package's architecture, checked on the source: which subpackage may import which, and
the ROS layer's shape (no node imports another; short modules, functions and constructors).

The transfer core imports no robot or chapter code; the robot, learner, evaluation and
recording layers import only the core and themselves; exploration builds on those; a thesis
chapter may use everything below it but no other chapter; the library never imports rclpy or
the nodes; nothing edits sys.path.
"""
import ast
import subprocess
import sys
from pathlib import Path

import pytest

from conftest import ROOT

LIBRARY = ROOT / "lpa_transfer"
CHAPTERS = {"illustrative_example", "lfd", "inverse_dynamics", "goal_babbling"}
BASE = {"_validation", "_lazy", "_estimator"}   # root modules that import no other library part
# subpackage -> the lpa_transfer subpackages it may import (besides itself)
ALLOWED = {
    "_validation": set(),
    "_lazy": set(),
    "_estimator": set(),
    "transfer": BASE,
    "robots": BASE,
    "learners": BASE,
    "evaluation": BASE,
    "recording": {"_lazy"},                 # its __init__ exports lazily
    "exploration": BASE | {"robots", "learners"},
    **{chapter: BASE | {"transfer", "robots", "learners", "evaluation", "recording",
                        "exploration"} for chapter in CHAPTERS},
}


def imported_modules(path):
    """Every module an ``import`` or ``from ... import`` in ``path`` names (nested ones too),
    relative imports resolved against the file's package."""
    package = path.relative_to(ROOT).with_suffix("").parts[:-1]
    names = []
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            names += [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                parent = package[:len(package) - node.level + 1]
                base = ".".join(parent + ((base,) if base else ()))
            names.append(base)
            names += [f"{base}.{alias.name}" for alias in node.names]
    return names


def subpackage_of(module):
    """'lpa_transfer.robots.kinematics' -> 'robots'; None outside the library or at its root."""
    parts = module.split(".")
    return parts[1] if parts[0] == "lpa_transfer" and len(parts) > 1 else None


LIBRARY_FILES = sorted(LIBRARY.rglob("*.py"))


@pytest.mark.parametrize("path", [p for p in LIBRARY_FILES if p.parent != LIBRARY
                                  or p.stem in BASE],
                         ids=lambda p: str(p.relative_to(LIBRARY)))
def test_each_subpackage_imports_only_the_layers_below_it(path):
    own = path.relative_to(LIBRARY).parts[0].removesuffix(".py")
    used = {subpackage_of(m) for m in imported_modules(path)} - {None, own}
    # 'lpa_transfer.transfer.procrustes' names 'transfer'; a bare module of the root counts too
    used = {u for u in used if (LIBRARY / u).is_dir() or (LIBRARY / f"{u}.py").exists()}
    assert used <= ALLOWED[own], f"{path.relative_to(ROOT)} imports {sorted(used - ALLOWED[own])}"


@pytest.mark.parametrize("path", LIBRARY_FILES, ids=lambda p: str(p.relative_to(LIBRARY)))
def test_the_library_imports_neither_rclpy_nor_the_nodes(path):
    roots = {m.split(".")[0] for m in imported_modules(path)}
    assert not roots & {"rclpy", "lpa_transfer_nodes", "lpa_transfer_interfaces"}, path


def test_importing_every_library_module_loads_no_rclpy():
    code = ("import importlib, pkgutil, sys, lpa_transfer\n"
            "for m in pkgutil.walk_packages(lpa_transfer.__path__, 'lpa_transfer.'):\n"
            "    importlib.import_module(m.name)\n"
            "print(sorted(k for k in sys.modules if k.split('.')[0] in "
            "('rclpy', 'lpa_transfer_nodes')))\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout
    assert out.strip() == "[]"


def test_nothing_edits_sys_path():
    offenders = []
    for path in ROOT.glob("**/*.py"):
        if ".venv" in path.parts or "build" in path.parts:
            continue
        for node in ast.walk(ast.parse(path.read_text(), str(path))):
            if isinstance(node, ast.Attribute) and node.attr == "path" \
                    and isinstance(node.value, ast.Name) and node.value.id == "sys":
                offenders.append(str(path.relative_to(ROOT)))
    assert offenders == []


def test_the_package_root_offers_the_transfer_models_and_lwpr():
    from lpa_transfer import LWPR, LocalProcrustesAnalysis, ProcrustesAnalysis
    from lpa_transfer.learners.lwpr import LWPR as FromLearners
    assert LWPR is FromLearners
    for model in (ProcrustesAnalysis, LocalProcrustesAnalysis):
        assert callable(model.fit) and callable(model.transfer)


SUBPACKAGES = sorted(path.parent.name for path in LIBRARY.glob("*/__init__.py"))


@pytest.mark.parametrize("name", SUBPACKAGES)
def test_each_subpackage_exports_its_public_names_lazily(name):
    """Each subpackage names its public API in ``__all__`` (imported on first use), and every
    name resolves to what its module defines, not to a submodule of the same name."""
    code = ("import importlib, sys, types\n"
            f"package = importlib.import_module('lpa_transfer.{name}')\n"
            "loaded = sorted(k for k in sys.modules if k.startswith('lpa_transfer.'))\n"
            "assert package.__all__, 'no __all__'\n"
            "for export in package.__all__:\n"
            "    value = getattr(package, export)\n"
            "    assert not isinstance(value, types.ModuleType), export\n"
            "print(loaded)\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    # importing the subpackage alone imports none of its modules (only _lazy, at the root)
    assert eval(out.stdout) == sorted({f"lpa_transfer.{name}", "lpa_transfer._lazy"})


def test_no_two_subpackages_export_the_same_name():
    """``from lpa_transfer.<sub> import X`` names one thing: the chapters' parallel names
    (``write_outputs``, ``merge``, ``CONDITIONS``) stay in their modules."""
    import importlib
    owners = {}
    for name in SUBPACKAGES:
        for export in importlib.import_module(f"lpa_transfer.{name}").__all__:
            owners.setdefault(export, []).append(name)
    assert {export: where for export, where in owners.items() if len(where) > 1} == {}


def test_importing_the_robots_loads_no_scikit_learn():
    code = ("import sys, lpa_transfer.robots\n"
            "print(sorted(k for k in sys.modules if k.split('.')[0] in ('sklearn', 'scipy')))\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout
    assert out.strip() == "[]"


def test_no_top_level_function_name_means_two_things_in_the_library():
    """One name, one meaning: a public top-level function or class is defined once, except in
    the chapters' parallel modules (each chapter's ``report.write_outputs`` writes its own
    run's outputs)."""
    seen = {}
    for path in LIBRARY_FILES:
        for node in ast.parse(path.read_text()).body:
            if isinstance(node, (ast.FunctionDef, ast.ClassDef)) \
                    and not node.name.startswith("_"):
                seen.setdefault(node.name, []).append(str(path.relative_to(LIBRARY)))
    def parallel(where):
        return len({Path(w).name for w in where}) == 1 \
            and all(Path(w).parts[0] in CHAPTERS for w in where)

    assert {name: where for name, where in seen.items()
            if len(where) > 1 and not parallel(where)} == {}


# -- the ROS layer (nodes/, the package lpa_transfer_nodes) ---------------------------------
NODES = ROOT / "nodes"
NODE_LAYER_FILES = sorted(NODES.glob("*.py"))
MAX_MODULE_LINES, MAX_FUNCTION_LINES, MAX_CONSTRUCTOR_LINES = 250, 60, 40
#: Modules still above a limit, with the size each may not exceed while it shrinks to it:
#: (module lines, longest constructor).
NOT_YET_WITHIN = {}


def defines_main(path):
    return any(isinstance(node, ast.FunctionDef) and node.name == "main"
               for node in ast.parse(path.read_text(), str(path)).body)


NODE_MODULES = {path.stem for path in NODE_LAYER_FILES if defines_main(path)}


def test_no_private_ros_layer_and_no_test_harness_in_the_installed_package():
    assert not [path.name for path in NODE_LAYER_FILES if path.stem.startswith("_")
                and path.stem != "__init__"]
    assert not (NODES / "testing.py").exists()
    offenders = [str(path.relative_to(ROOT))
                 for folder in ("nodes", "scenarios", "bench", "test")
                 for path in (ROOT / folder).rglob("*.py")
                 if any(m.startswith("lpa_transfer_nodes._") for m in imported_modules(path))]
    assert offenders == []


@pytest.mark.parametrize("path", NODE_LAYER_FILES, ids=lambda p: p.name)
def test_no_node_imports_another_node(path):
    """Nodes share the ROS layer (the modules without main) and the library, never a node."""
    used = {m.split(".")[1] for m in imported_modules(path)
            if m.startswith("lpa_transfer_nodes.") and len(m.split(".")) > 1}
    assert used & NODE_MODULES - {path.stem} == set(), path.name


@pytest.mark.parametrize("path", NODE_LAYER_FILES, ids=lambda p: p.name)
def test_node_layer_modules_functions_and_constructors_are_short(path):
    module_limit, constructor_limit = NOT_YET_WITHIN.get(
        path.name, (MAX_MODULE_LINES, MAX_CONSTRUCTOR_LINES))
    assert len(path.read_text().splitlines()) <= module_limit, path.name
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            size = node.end_lineno - node.lineno + 1
            limit = constructor_limit if node.name == "__init__" else MAX_FUNCTION_LINES
            assert size <= limit, f"{path.name}: {node.name} has {size} lines, more than {limit}"


# -- bench/ (speed only), studies/ (research programs), test/oracles/ ----------------------
BENCH = ROOT / "bench"
STUDIES = ROOT / "studies"
#: bench/'s modules that are not a benchmark of their own: make bench's table, the benchmark
#: data, the plain LPA the library is timed against, the tests' node harness; and the
#: service round trip the multi-host scenario runs (with its shell script)
BENCH_HELPERS = {"__init__", "table", "datasets", "reference_lpa", "ros_harness",
                 "mapping_round_trip"}
MAX_BENCH_LINES, MAX_BENCH_README_LINES = 2000, 200


def test_bench_holds_speed_benchmarks_only():
    others = [path.name for path in BENCH.iterdir()
              if path.name not in ("README.md", "__pycache__")
              and not (path.suffix == ".py" and (path.stem.startswith("bench_")
                                                 or path.stem in BENCH_HELPERS))
              and not (path.suffix == ".sh" and path.stem in BENCH_HELPERS)]
    assert others == [], f"not speed benchmarks (studies/ or test/oracles/?): {others}"


def test_bench_is_small_and_its_readme_is_the_table():
    lines = sum(len(path.read_text().splitlines()) for path in BENCH.iterdir()
                if path.suffix in (".py", ".sh", ".md"))
    assert lines < MAX_BENCH_LINES, f"bench/ has {lines} lines"
    readme = (BENCH / "README.md").read_text()
    assert len(readme.splitlines()) < MAX_BENCH_README_LINES
    assert "## `make bench`: the speed table" in readme


def test_neither_the_library_nor_the_nodes_nor_bench_import_a_study():
    offenders = [str(path.relative_to(ROOT))
                 for folder in ("lpa_transfer", "nodes", "scenarios", "bench")
                 for path in (ROOT / folder).rglob("*.py")
                 if any(m.split(".")[0] == "studies" for m in imported_modules(path))]
    assert offenders == []


def test_every_study_says_its_question_command_and_result_in_its_groups_readme():
    """Each group of studies/ has a README whose table names every study of the group."""
    for group in [path for path in STUDIES.iterdir() if (path / "__init__.py").exists()]:
        readme = (group / "README.md").read_text()
        assert "| study | question | command | result |" in readme, group.name
        missing = [path.stem for path in group.glob("*.py") if path.stem != "__init__"
                   and f"`{path.stem}`" not in readme]
        assert missing == [], f"studies/{group.name}/README.md does not name {missing}"


def test_the_frozen_oracles_sit_beside_the_tests_that_use_them():
    for oracle in (ROOT / "test" / "oracles").glob("*.py"):
        users = [path.name for path in (ROOT / "test").glob("test_*.py")
                 if f"oracles\" / \"{oracle.name}\"" in path.read_text()
                 or f"oracles/{oracle.name}" in path.read_text()]
        assert users, f"no test uses test/oracles/{oracle.name}"
