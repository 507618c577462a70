#!/usr/bin/env bash
# The one set-up path: builds the project-local venv .venv with the pinned requirements, the
# interface package msg_schemas/ and the project itself (editable).
# Each step runs only when its inputs changed (hash stamps in .venv/.stamps), so a second run
# does nothing and takes well under a second.
set -euo pipefail

ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
VENV=$ROOT/.venv
STAMPS=$VENV/.stamps
BUILD=$VENV/build/msg_schemas
cd "$ROOT"
# One set-up at a time (parallel `make test` runs share the venv).
mkdir -p build && exec 9>build/.setup.lock && flock 9

say() { echo "setup: $*"; }

# Short hash of stdin.
digest() { sha256sum | cut -d' ' -f1; }

# up_to_date STEP HASH: true when STEP last completed with inputs of this HASH.
up_to_date() { [[ -f $STAMPS/$1 && $(<"$STAMPS/$1") == "$2" ]]; }
mark_done() { mkdir -p "$STAMPS" && echo "$2" >"$STAMPS/$1"; }

did_something=
pip_install() { "$VENV/bin/python" -m pip install --disable-pip-version-check -q "$@"; }

# 1. Build tools for msg_schemas/. Present on the dev machines; kept for a bare Debian.
missing=()
for tool in cmake ninja g++; do command -v "$tool" >/dev/null || missing+=("$tool"); done
if ((${#missing[@]})); then
    say "installing build tools (missing: ${missing[*]})"
    sudo_cmd=$([[ $(id -u) == 0 ]] || echo sudo)
    $sudo_cmd apt-get update -qq
    $sudo_cmd env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq cmake ninja-build g++
    did_something=1
fi

# 2. The venv (PYTHON picks another interpreter; the pins are checked with 3.11).
if [[ ! -x $VENV/bin/python ]]; then
    say "creating $VENV"
    "${PYTHON:-python3}" -m venv "$VENV"
    did_something=1
fi

# 3. Pinned requirements (the ROS wheels, the scientific stack, test tools).
# requirements/constraints/build.txt pins the build environments of source-only packages
# (pip applies PIP_CONSTRAINT to those too).
req_hash=$(sha256sum requirements/*.txt requirements/constraints/build.txt | digest)
if ! up_to_date requirements "$req_hash"; then
    say "installing requirements/*.txt (about 2-3 min on a fresh venv)"
    PIP_CONSTRAINT=$ROOT/requirements/constraints/build.txt \
        pip_install $(printf -- '-r %s ' requirements/*.txt)
    mark_done requirements "$req_hash"
    did_something=1
fi

# 4. pip (re)writes the ROS wheels' CMake files with the wheel builder's include paths.
if grep -qs /opt/python/ "$VENV"/share/*/cmake/*__rosidl_generator_pyExport.cmake; then
    "$VENV/bin/python" tools/patch_ros_cmake.py "$VENV"
    did_something=1
fi

# 5. The interface packages, built against (and installed into) the venv prefix:
# lpa_transfer_interfaces (msg_schemas/) and the standard tf2_msgs/TFMessage
# (msg_schemas/tf2_msgs/: the ROS index has no tf2_msgs wheel). Rebuilt when their sources or
# the requirements change; the previous install is removed first so that a deleted .msg does
# not linger.
msg_hash=$( (echo "$req_hash"; find msg_schemas -type f | sort | xargs sha256sum) | digest)
if ! up_to_date msg_schemas "$msg_hash"; then
    for source in msg_schemas/tf2_msgs msg_schemas; do
        build=$VENV/build/$(basename "$source")
        say "building $source (about 30 s)"
        log=$build.log
        mkdir -p "$build"
        [[ -f $build/install_manifest.txt ]] && xargs rm -f <"$build/install_manifest.txt"
        if ! (
            export VIRTUAL_ENV=$VENV PATH=$VENV/bin:$PATH AMENT_PREFIX_PATH=$VENV
            cmake -S "$source" -B "$build" -G Ninja -DCMAKE_INSTALL_PREFIX="$VENV" \
                -DCMAKE_BUILD_TYPE=Release -DBUILD_TESTING=OFF -DPython3_EXECUTABLE="$VENV/bin/python"
            cmake --build "$build"
            cmake --install "$build"
        ) >"$log" 2>&1; then
            tail -n 40 "$log"
            say "$source build failed; full log: $log"
            exit 1
        fi
    done
    mark_done msg_schemas "$msg_hash"
    did_something=1
fi

# 6. The project itself, editable, so library edits need no reinstall. Reinstalled when the
# packaging files or this script change, or a node module gains/loses main() (console scripts).
proj_hash=$( (sha256sum setup.py setup.cfg package.xml tools/setup.sh; grep -l '^def main' nodes/*.py 2>/dev/null || true) \
    | digest)
if ! up_to_date project "$proj_hash"; then
    say "installing lpa_transfer (editable)"
    # No build isolation: use the venv's pinned setuptools instead of fetching one each time.
    pip_install --no-deps --no-build-isolation -e .
    # Editable (PEP 660) installs skip data_files: link them instead, so ament_index finds the
    # package and edits under scenarios/ show through without a reinstall.
    share=$VENV/share/lpa_transfer index=$VENV/share/ament_index/resource_index/packages
    mkdir -p "$share" "$index"
    ln -sfn "$ROOT/package.xml" "$share/package.xml"
    ln -sfn "$ROOT/scenarios" "$share/scenarios"
    ln -sfn "$ROOT/resource/lpa_transfer" "$index/lpa_transfer"
    mark_done project "$proj_hash"
    did_something=1
fi

# 7. The compiled kernels (numba) of LWPR, of LPA's mixture fit (initEM, EM) and of the
# smoothing splines' cross-validation (chapter 5's spline correspondences), compiled once
# here and cached on disk next to their modules, so that the first learner or mapping node
# does not stall compiling them. Redone when the kernels or the requirements change.
kernels=(lpa_transfer/learners/_lwpr_kernels.py lpa_transfer/transfer/_em_kernels.py
         lpa_transfer/transfer/_transfer_kernels.py lpa_transfer/inverse_dynamics/_gcv.py)
kernel_hash=$( (echo "$req_hash"; sha256sum "${kernels[@]}") | digest)
if ! up_to_date kernels "$kernel_hash" || ! ls lpa_transfer/learners/__pycache__/_lwpr_kernels*.nbi >/dev/null 2>&1 \
        || ! ls lpa_transfer/transfer/__pycache__/_em_kernels*.nbi >/dev/null 2>&1 \
        || ! ls lpa_transfer/transfer/__pycache__/_transfer_kernels*.nbi >/dev/null 2>&1 \
        || ! ls lpa_transfer/inverse_dynamics/__pycache__/_gcv*.nbi >/dev/null 2>&1; then
    say "compiling the LWPR, LPA (EM, transfer) and spline kernels (numba, about 30 s)"
    OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 "$VENV/bin/python" - <<'PY'
import numpy as np
from lpa_transfer.learners.lwpr import LWPR
rng = np.random.default_rng(0)
for params in ({}, {"meta": True, "diag_only": False}):
    X, Y = rng.uniform(-1, 1, (60, 2)), rng.uniform(-1, 1, (60, 2))
    model = LWPR(**params).fit(X, Y)
    model.partial_fit(X[:5], Y[:5])
    model.update(X[0], Y[0])
    model.predict(X)
    model.predict_with_confidence(X)
from lpa_transfer import LocalProcrustesAnalysis
source = rng.normal(size=(80, 3))
for dims in (None, [0, 1]):       # the clustering columns: all (contiguous) or a view of some
    lpa = LocalProcrustesAnalysis(n_min=7, c_min=1e-7, cluster_dims=dims).fit(source, source[:, :2])
    lpa.transfer(source)
from lpa_transfer.inverse_dynamics._gcv import smoothing_spline
smoothing_spline(rng.normal(size=20), 0.01)
PY
    mark_done kernels "$kernel_hash"
    did_something=1
fi

if [[ -n $did_something ]]; then say "done ($VENV)"; else say "up to date ($VENV)"; fi
