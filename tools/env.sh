# Sourced by the run scripts (after tools/setup.sh): the project venv and a ROS environment
# that stays on this host. Values already set by the caller win.
_lpa_root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
# shellcheck disable=SC1091
source "$_lpa_root/.venv/bin/activate"
# ament_index (package share dirs, .msg files) looks only on AMENT_PREFIX_PATH.
case ":${AMENT_PREFIX_PATH:-}:" in
    *":$VIRTUAL_ENV:"*) ;;
    *) export AMENT_PREFIX_PATH="$VIRTUAL_ENV${AMENT_PREFIX_PATH:+:$AMENT_PREFIX_PATH}" ;;
esac
# Default discovery multicasts off the host.
export ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST
export ROS_DOMAIN_ID=${ROS_DOMAIN_ID:-42}
export ROS_LOG_DIR=${ROS_LOG_DIR:-$_lpa_root/log/ros}
# Thread oversubscription made sklearn 10-25x slower on 2 cores; one BLAS/OpenMP thread each.
export OMP_NUM_THREADS=${OMP_NUM_THREADS:-1}
export OPENBLAS_NUM_THREADS=${OPENBLAS_NUM_THREADS:-1}
export MKL_NUM_THREADS=${MKL_NUM_THREADS:-1}
unset _lpa_root
