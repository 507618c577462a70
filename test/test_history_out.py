"""History stays out of the code: no issue numbers or dates in the library, the nodes, the
scenarios' configs and scripts, tools/, the tests and the Makefile (dated decisions live in
docs/history.md), and the library's module docstrings say what and why in a screenful
(details: docs/library.md)."""
import ast
import re
from pathlib import Path

import pytest
from conftest import ROOT

#: An issue number ("issue 27", "Issue 28 item 3", "issues 4"), a GitHub-style "(#12)", a
#: calendar date (2026-12-03, 2026-12-03/04) or a month and year of the project's time.
HISTORY = re.compile(
    r"\bissues?\s+#?\d+|\(#\d+\)|\b20\d\d-[01]\d-[0-3]\d\b|\b(?:jan|feb|mar|apr|may|jun|jul|aug"
    r"|sep|oct|nov|dec)[a-z]*\.?\s+(?:[0-3]?\d,?\s+)?20[2-9]\d\b|shared/notes/", re.I)
#: The files checked: (folder, file name patterns); reference results are records, not code.
CHECKED = (("lpa_transfer", ("*.py",)),
           ("nodes", ("*.py",)),
           ("scenarios", ("*.py", "*.sh", "*.yaml", "*.toml", "*.xml")),
           ("tools", ("*.py", "*.sh", "*.xml", "*.toml", "*.yaml")),
           ("test", ("*.py", "*.sh", "*.yaml", "*.toml")))
MAX_MODULE_DOCSTRING = 25


#: This file, whose examples of history are the pattern's own test.
NOT_CHECKED = {Path(__file__).resolve()}


def checked_files():
    files = [ROOT / "Makefile"]
    for folder, patterns in CHECKED:
        for pattern in patterns:
            files += [p for p in (ROOT / folder).rglob(pattern)
                      if "reference_results" not in p.parts and "__pycache__" not in p.parts
                      and p.resolve() not in NOT_CHECKED]
    return sorted(set(files))


def history_lines(path):
    """(line number, line) of every line of ``path`` that carries history."""
    lines = path.read_text(encoding="utf-8", errors="replace").splitlines()
    return [(n, line.strip()) for n, line in enumerate(lines, 1) if HISTORY.search(line)]


def test_the_pattern_finds_history_and_passes_citations():
    for line in ("# the thesis' z-up scene (issue 27)", "Issue 28 item 3: markers",
                 "(measured on 2026-12-03)", "the references of 2026-12-03/04", "fixed (#12)",
                 "measured in December 2026", "(shared/notes/ros2-from-pypi.md)"):
        assert HISTORY.search(line), line
    for line in ("Neural Computation 17(12):2602-2634, 2005", "ICRA 2018", "Mar. 2015",
                 "init_alpha 0.001", "key=f'{name} #1'", "max_k_max 2000", "distributed==2026.8.0"):
        assert not HISTORY.search(line), line


def test_no_issue_numbers_or_dates_in_code_configs_and_tools():
    files = checked_files()
    assert len(files) > 100                                     # the walk found the tree
    found = {str(p.relative_to(ROOT)): history_lines(p) for p in files}
    found = {path: lines for path, lines in found.items() if lines}
    assert not found, "history in code or configs (move it to docs/history.md):\n" + "\n".join(
        f"{path}:{n}: {line}" for path, lines in found.items() for n, line in lines)


@pytest.mark.parametrize("path", sorted((ROOT / "lpa_transfer").rglob("*.py")),
                         ids=lambda p: str(p.relative_to(ROOT)))
def test_library_module_docstrings_fit_a_screen(path):
    module = ast.parse(path.read_text(encoding="utf-8"))
    if ast.get_docstring(module) is None:
        return
    first = module.body[0]
    lines = first.end_lineno - first.lineno + 1
    assert lines <= MAX_MODULE_DOCSTRING, (
        f"{path.relative_to(ROOT)}: module docstring of {lines} lines; say what and why in "
        f"about 20 and move the details to docs/library.md")
