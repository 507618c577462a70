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
# Fast DDS: shared memory with larger segments and UDP on loopback only (the profile says why).
# A caller that chose its transports (FASTDDS_BUILTIN_TRANSPORTS, as the multi-host scenario
# does for its UDP-only namespaces) or its own profile keeps them.
if [ -z "${FASTDDS_BUILTIN_TRANSPORTS:-}" ]; then
    export FASTRTPS_DEFAULT_PROFILES_FILE=${FASTRTPS_DEFAULT_PROFILES_FILE:-$_lpa_root/tools/fastdds_localhost.xml}
fi
export ROS_LOG_DIR=${ROS_LOG_DIR:-$_lpa_root/log/ros}
# Thread oversubscription made sklearn 10-25x slower on 2 cores; one BLAS/OpenMP thread each.
export OMP_NUM_THREADS=${OMP_NUM_THREADS:-1}
export OPENBLAS_NUM_THREADS=${OPENBLAS_NUM_THREADS:-1}
export MKL_NUM_THREADS=${MKL_NUM_THREADS:-1}
# OpenBLAS picks its kernels by CPU, and their rounding differs: a learner trial gave 5.18 mm
# with the Haswell kernels and 5.72 mm with the Prescott ones. The
# online learners amplify such differences, so pin one kernel set (AVX2 + FMA, which most
# x86-64 hosts have) for results that repeat from one machine to the next; numpy's own SIMD
# loops likewise stop at AVX2 (an AVX-512 host would dispatch others).
if grep -qw avx2 /proc/cpuinfo 2>/dev/null && grep -qw fma /proc/cpuinfo 2>/dev/null; then
    export OPENBLAS_CORETYPE=${OPENBLAS_CORETYPE:-Haswell}
    _avx2_level="SSSE3 SSE41 POPCNT SSE42 AVX F16C FMA3 AVX2"
    export NPY_ENABLE_CPU_FEATURES=${NPY_ENABLE_CPU_FEATURES:-$_avx2_level}
    unset _avx2_level
fi
unset _lpa_root
