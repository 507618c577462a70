"""Point the ROS wheels' exported CMake include dirs at this interpreter's headers.

The ros-jazzy-* wheels were built in a manylinux container, so every
``share/<pkg>/cmake/*__rosidl_generator_pyExport.cmake`` names that container's Python and
numpy headers (``/opt/python/cp311-cp311/...``). ``find_package`` of such a message package
(std_msgs for msg_schemas/) then fails. Any Python or numpy include dir found there is
rewritten to ``sysconfig`` / ``numpy.get_include()`` of the interpreter running this script,
so a second run, or a run after a numpy change, is safe.

Usage: python tools/patch_ros_cmake.py PREFIX   (the venv that holds the wheels)
"""
import re
import sys
import sysconfig
from pathlib import Path

import numpy

INCLUDE_DIRS = re.compile(r'(INTERFACE_INCLUDE_DIRECTORIES ")([^"]*)(")')
REPLACEMENTS = [
    (re.compile(r"/include/python3\.\d+$"), sysconfig.get_paths()["include"]),
    (re.compile(r"/numpy/(_?core/)?include$"), numpy.get_include()),
]


def fix_dir(path):
    for pattern, replacement in REPLACEMENTS:
        if pattern.search(path):
            return replacement
    return path


def patch_text(text):
    return INCLUDE_DIRS.sub(
        lambda m: m[1] + ";".join(map(fix_dir, m[2].split(";"))) + m[3], text)


def main(prefix):
    changed = 0
    for path in sorted(Path(prefix, "share").glob("*/cmake/*__rosidl_generator_pyExport.cmake")):
        old = path.read_text()
        new = patch_text(old)
        if new != old:
            path.write_text(new)
            changed += 1
    if changed:
        print(f"patched the include dirs of {changed} ROS CMake export files")


if __name__ == "__main__":
    main(sys.argv[1])
