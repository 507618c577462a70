#!/usr/bin/env bash
# The node graph over three network "hosts": Linux network namespaces joined by a bridge that
# lives in a fourth, "switch" namespace. robots: the two robot_sims; mapping:
# lpa_mapping; learners: the collector, the evaluation and the recorder. The 2-link graph
# scenario (scenarios/two_link_graph/run.sh), or with --scenario inverse_dynamics the default
# demo's graph, runs unchanged, each node on its host.
#
# Usage (as root): scenarios/multi_host/run.sh [--scenario inverse_dynamics]
#                  [--link-down HOST AFTER SECONDS | --kill-map]
#                  [the scenario's run.sh arguments...]
#   e.g. --config scenarios/two_link_graph/smoke.yaml --out runs/multi_host
#   --scenario inverse_dynamics --override scenarios/inverse_dynamics/demo.yaml: the default
#   demo's graph (robots: youbot_sim, pincher_sim; mapping: lpa_mapping; learners: the
#   recorder, the learners, the babbling collectors and the experiment)
#   --scenario mapping_round_trip: bench/mapping_round_trip.sh, lpa_mapping on the mapping
#   host and a client measuring discovery time and round trips on the learners' host
#   --link-down rob 0.2 2: the robots host's link goes down 0.2 s after the collector logged
#   that it started babbling (discovery is done by then: the fault lands mid-collection), for
#   2 s (a fault; hosts: rob, map, lrn).
#   --kill-map: once the collector's model is fitted, every process of the mapping host is
#   killed (SIGKILL, a crash); the evaluation then stops with a clear error naming the service
#   it waited for, and the scenario fails. The script then restarts the host's lpa_mapping on
#   the same model directory (it restores its models from disk) and the robot_sims, re-runs the
#   evaluation against them into DIR/rerun, and exits with the re-run's status.
# Leaves topology.txt in the run directory: each host's routes, this machine's own links, and
# the bytes each bridge port carried.
# Without root or network namespaces it says so in one line and exits 77 (skip).
#
# Network safety: the namespaces get addresses on 10.231.0.0/24 only, no default route and
# no route out; the bridge is in the switch namespace, attached to no interface of this
# machine's own namespace, so no packet of the run can leave the namespaces made here. DDS
# discovers over that subnet (ROS_AUTOMATIC_DISCOVERY_RANGE=SUBNET: multicast on the bridge,
# routed there by a 224.0.0.0/4 route on each host's own interface), and uses UDP only
# (FASTDDS_BUILTIN_TRANSPORTS=UDPv4, without tools/env.sh's loopback-only profile: shared
# memory would join processes on one machine behind the network's back). Everything is
# removed at the end, after Ctrl-C or a failure.
set -uo pipefail
HERE=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
ROOT=$(cd "$HERE/../.." && pwd)
if [ "$(id -u)" != 0 ] || ! ip netns list >/dev/null 2>&1; then
    echo "skipped: network namespaces need root and iproute2's ip netns" >&2; exit 77
fi
LINK_DOWN=() SCENARIO=two_link_graph KILL_MAP=0
if [ "${1:-}" = --scenario ]; then SCENARIO=$2; shift 2; fi
if [ "${1:-}" = --link-down ]; then LINK_DOWN=("$2" "$3" "$4"); shift 4; fi
if [ "${1:-}" = --kill-map ]; then KILL_MAP=1; shift; fi
case "$SCENARIO" in
    two_link_graph|inverse_dynamics) SCRIPT=$ROOT/scenarios/$SCENARIO/run.sh ;;
    mapping_round_trip) SCRIPT=$ROOT/bench/mapping_round_trip.sh ;;
    *) echo "error: --scenario must be two_link_graph, inverse_dynamics or" \
            "mapping_round_trip, got '$SCENARIO'" >&2
       exit 2 ;;
esac
if { [ ${#LINK_DOWN[@]} = 3 ] || [ $KILL_MAP = 1 ]; } && [ "$SCENARIO" != two_link_graph ]; then
    echo "error: --link-down and --kill-map are for the two_link_graph scenario (they wait for" \
         "its collector)" >&2
    exit 2
fi
source "$HERE/bridge.sh"
PREFIX=lpa$$
SWITCH=${PREFIX}sw
declare -A ADDRESS=([rob]=10.231.0.1 [map]=10.231.0.2 [lrn]=10.231.0.3)
TOPOLOGY=$(mktemp)
cleanup() {
    if [ -n "${OUT:-}" ] && [ -d "$OUT" ]; then
        { echo "== bridge ports (bytes each carried)"; ip -n "$SWITCH" -s -o link show; } >>"$TOPOLOGY"
        cp "$TOPOLOGY" "$OUT/topology.txt"
    fi
    [ -n "${FAULT:-}" ] && kill "$FAULT" 2>/dev/null
    for host in "${!ADDRESS[@]}"; do ip netns del "$PREFIX$host" 2>/dev/null; done
    ip netns del "$SWITCH" 2>/dev/null
    rm -f "$TOPOLOGY"
}
trap cleanup EXIT
trap 'exit 130' INT TERM
set -e
make_switch "$SWITCH"
for host in "${!ADDRESS[@]}"; do
    ns=$PREFIX$host
    add_host "$SWITCH" "$ns" "${ADDRESS[$host]}"
    ip -n "$ns" route add 224.0.0.0/4 dev eth0       # multicast discovery, on the bridge only
    { echo "== $ns routes"; ip -n "$ns" route show; } >>"$TOPOLOGY"
done
{ echo "== root namespace links"; ip -o link show; } >>"$TOPOLOGY"
set +e

if [ "$SCENARIO" = two_link_graph ]; then
    export LPA_HOSTS="source_sim=${PREFIX}rob target_sim=${PREFIX}rob lpa_mapping=${PREFIX}map
        recorder=${PREFIX}lrn correspondence_collector=${PREFIX}lrn
        transfer_evaluation=${PREFIX}lrn"
else    # every other node (learners, collectors, experiment) on the learners' host
    export LPA_HOSTS="*_sim=${PREFIX}rob lpa_mapping=${PREFIX}map *=${PREFIX}lrn"
fi
export LPA_HOST_ENV="-u FASTRTPS_DEFAULT_PROFILES_FILE ROS_AUTOMATIC_DISCOVERY_RANGE=SUBNET FASTDDS_BUILTIN_TRANSPORTS=UDPv4"
OUT=$(python3 - "$ROOT" "$SCENARIO" "$@" <<'PY'
import os, sys
root, scenario, args = sys.argv[1], sys.argv[2], sys.argv[3:]
print(os.path.realpath(args[args.index("--out") + 1]) if "--out" in args
      else os.path.join(root, "runs", scenario))
PY
)
if [ ${#LINK_DOWN[@]} = 3 ]; then
    (until grep -qs babbling "$OUT/logs/correspondence_collector.log"; do sleep 0.02; done
     sleep "${LINK_DOWN[1]}"; ip -n "$PREFIX${LINK_DOWN[0]}" link set eth0 down
     echo "[$(date +%T)] fault: host ${LINK_DOWN[0]} link down for ${LINK_DOWN[2]} s" >&2
     sleep "${LINK_DOWN[2]}"; ip -n "$PREFIX${LINK_DOWN[0]}" link set eth0 up
     ip -n "$PREFIX${LINK_DOWN[0]}" route add 224.0.0.0/4 dev eth0 2>/dev/null
     echo "[$(date +%T)] fault: host ${LINK_DOWN[0]} link up again" >&2) &
    FAULT=$!
fi
if [ $KILL_MAP = 1 ]; then
    (until grep -qs "training RMSE" "$OUT/logs/correspondence_collector.log"; do sleep 0.02; done
     pids=$(ip netns pids "${PREFIX}map")
     kill -KILL $pids 2>/dev/null
     echo "[$(date +%T)] fault: host map's processes killed (PIDs" $pids")" >&2) &
    FAULT=$!
fi
bash "$SCRIPT" "$@"
CODE=$?
[ $KILL_MAP = 1 ] || exit $CODE

# --kill-map: restart the mapping host's service on the same model directory, the robots, and
# re-run the evaluation (run.sh has stopped every node by now).
echo "[$(date +%T)] the scenario exited with $CODE; restarting lpa_mapping on host map" >&2
wait "$FAULT"; FAULT=""
mapfile -t PARAMS < <(python3 - "$ROOT" "$@" <<'PY'
import os, sys
root, args = sys.argv[1], sys.argv[2:]
files = [os.path.join(root, "scenarios", "two_link_graph", "config.yaml")]
for flag, value in zip(args, args[1:]):
    if flag == "--config":
        files[0] = os.path.realpath(value)
    elif flag == "--override":
        files.append(os.path.realpath(value))
print("--ros-args")
for path in files:
    print("--params-file"); print(path)
PY
)
RESTARTED=()
restart() {   # restart HOST NAME ARGS...: a node on HOST again, its log logs/NAME_restarted.log
    local host=$1 name=$2; shift 2
    setsid ip netns exec "$PREFIX$host" env $LPA_HOST_ENV "$@" \
        >"$OUT/logs/${name}_restarted.log" 2>&1 &
    RESTARTED+=($!)
}
source "$ROOT/tools/env.sh"
cd "$ROOT"
restart map lpa_mapping python -m lpa_transfer_nodes.lpa_mapping "${PARAMS[@]}" \
    -p "model_dir:=$OUT/models"
for side in source target; do
    restart rob "${side}_sim" python -m lpa_transfer_nodes.robot_sim "${PARAMS[@]}" \
        -r "__ns:=/$side"
done
mkdir -p "$OUT/rerun"
echo "[$(date +%T)] transfer_evaluation (re-run)" >&2
ip netns exec "${PREFIX}lrn" env $LPA_HOST_ENV python \
    "$ROOT/scenarios/two_link_graph/evaluate_transfer.py" "${PARAMS[@]}" \
    -p "output_dir:=$OUT/rerun" -p "correspondence_file:=$OUT/correspondences.npz" \
    >"$OUT/logs/transfer_evaluation_rerun.log" 2>&1
RERUN=$?
for pid in "${RESTARTED[@]}"; do kill -INT "$pid" 2>/dev/null; done
for pid in "${RESTARTED[@]}"; do
    for _ in $(seq 100); do kill -0 "$pid" 2>/dev/null || break; sleep 0.1; done
    kill -KILL "$pid" 2>/dev/null; wait "$pid" 2>/dev/null
done
echo "[$(date +%T)] re-run of the evaluation exited with $RERUN" >&2
exit $RERUN
