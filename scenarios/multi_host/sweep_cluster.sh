#!/usr/bin/env bash
# A sweep (lpa_transfer/sweeps.py) on a Dask cluster whose nodes are "hosts": Linux network
# namespaces joined by a bridge in a fifth, "switch" namespace. Node 1, the head, runs the
# Dask scheduler, a worker and the sweep itself (python -m lpa_transfer.sweeps ... --address
# tcp://10.232.0.1:8786); every other node runs a worker. Each task runs on its worker's host:
# a graph task's nodes discover each other on that host's loopback, in a ROS domain of their
# own, as on a machine of their own; the workers reach the scheduler over the bridge.
# This is how the sweeps run on real machines, one `dask scheduler` and a `dask worker` per
# machine (docs/scenarios.md, "Sweeps"), and how the suite checks that a cluster gives the
# one-machine result (test/test_inverse_dynamics_variants.py); bench/bench_sweep.py times 1 node against 2.
#
# Usage (as root): scenarios/multi_host/sweep_cluster.sh [--nodes N] [--slots S] [--pin]
#                  [--logs DIR] SWEEP ARGUMENTS...
#   e.g. graph ch5 --override scenarios/inverse_dynamics/smoke.yaml --seeds 0 1 --out DIR
#   --nodes: hosts (default 2); --slots: tasks a worker runs at once (default 1); --pin: the
#   worker of node k (and its tasks) on CPU (k-1) mod the CPUs, so that each node has a core
#   of its own; --logs: the scheduler's and workers' logs (default log/sweep_cluster).
# Prints a line per node ("node K: network namespace NS, worker at tcp://ADDRESS"), then the
# sweep's output, and exits with the sweep's status. Without root or network namespaces it
# says so in one line and exits 77 (skip). Everything is removed at the end, also after
# Ctrl-C or a failure.
#
# Network safety: the hosts have addresses on 10.232.0.0/24 only, no default route and no
# route out; the bridge is in the switch namespace, attached to no interface of this
# machine's own namespace, so nothing of the cluster can leave the namespaces made here.
set -uo pipefail
HERE=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
ROOT=$(cd "$HERE/../.." && pwd)
if [ "$(id -u)" != 0 ] || ! ip netns list >/dev/null 2>&1; then
    echo "skipped: network namespaces need root and iproute2's ip netns" >&2; exit 77
fi
NODES=2 SLOTS=1 PIN=0 LOGS=$ROOT/log/sweep_cluster
while [ $# -gt 0 ]; do
    case $1 in
        --nodes) NODES=$2; shift 2 ;;
        --slots) SLOTS=$2; shift 2 ;;
        --pin) PIN=1; shift ;;
        --logs) LOGS=$2; shift 2 ;;
        *) break ;;
    esac
done
if ! [[ $NODES =~ ^[1-9][0-9]?$ && $SLOTS =~ ^[1-9][0-9]*$ ]] || [ $# = 0 ]; then
    echo "usage: $0 [--nodes N] [--slots S] [--pin] [--logs DIR] SWEEP ARGUMENTS..." >&2; exit 2
fi
source "$ROOT/tools/env.sh"
source "$HERE/bridge.sh"
mkdir -p "$LOGS"
PREFIX=lpa$$sw
SWITCH=${PREFIX}br
HEAD=10.232.0.1
PORT=8786
PIDS=()
cleanup() {
    local pid waited ns
    for pid in "${PIDS[@]}"; do kill -TERM "$pid" 2>/dev/null; done
    for pid in "${PIDS[@]}"; do
        waited=0
        while kill -0 "$pid" 2>/dev/null && [ $waited -lt 100 ]; do sleep 0.1; waited=$((waited + 1)); done
        kill -KILL "$pid" 2>/dev/null; wait "$pid" 2>/dev/null
    done
    for ((k = 1; k <= NODES; k++)); do
        ns=$PREFIX$k
        # what this script started in the host and is still there (a task's nodes)
        pids=$(ip netns pids "$ns" 2>/dev/null)
        [ -n "$pids" ] && kill -KILL $pids 2>/dev/null
        ip netns del "$ns" 2>/dev/null
    done
    ip netns del "$SWITCH" 2>/dev/null
}
trap cleanup EXIT
trap 'exit 130' INT TERM
set -e
make_switch "$SWITCH"
for ((k = 1; k <= NODES; k++)); do add_host "$SWITCH" "$PREFIX$k" "10.232.0.$k"; done
set +e
cpus=$(nproc)
ip netns exec "${PREFIX}1" dask scheduler --host "$HEAD" --port $PORT --no-dashboard \
    >"$LOGS/scheduler.log" 2>&1 &
PIDS+=($!)
for ((k = 1; k <= NODES; k++)); do
    pin=()
    [ $PIN = 1 ] && pin=(taskset -c $(((k - 1) % cpus)))
    ip netns exec "$PREFIX$k" "${pin[@]}" dask worker "tcp://$HEAD:$PORT" --host "10.232.0.$k" \
        --nthreads "$SLOTS" --no-nanny --no-dashboard --name "node$k" \
        --local-directory "$LOGS/node$k" >"$LOGS/node$k.log" 2>&1 &
    PIDS+=($!)
    echo "node $k: network namespace $PREFIX$k, worker at tcp://10.232.0.$k${pin:+ on CPU $(((k - 1) % cpus))}"
done
ip netns exec "${PREFIX}1" python -m lpa_transfer.sweeps "$@" --address "tcp://$HEAD:$PORT" \
    --min-workers "$NODES"
CODE=$?
if [ $CODE != 0 ]; then
    echo "the sweep exited with $CODE; the cluster's logs are in $LOGS" >&2
fi
exit $CODE
