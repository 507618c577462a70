# Shared by the scenarios' run.sh scripts (source it after setting HERE, ROOT, CONFIG, OUT
# and SCENARIO, a name): argument parsing, the run directory, the ROS environment, and
# starting/stopping every node as its own process with its own log.
# Sets PARAMS (--ros-args --params-file CONFIG [--params-file OVERRIDE]...) and CONFIGS (the
# files in that order: later ones override); provides experiment_list, start, step, stop_all.
OVERRIDES=() PROGRESS=0
while [ $# -gt 0 ]; do
    case $1 in
        --progress) PROGRESS=1; shift ;;
        --config) CONFIG=$(realpath "$2"); shift 2 ;;
        --override) OVERRIDES+=("$(realpath "$2")"); shift 2 ;;
        --out) OUT=$(realpath -m "$2"); shift 2 ;;
        *) echo "usage: $0 [--config FILE.yaml] [--override FILE.yaml]... [--out DIR] [--progress]" >&2
           exit 2 ;;
    esac
done
CONFIGS=("$CONFIG" "${OVERRIDES[@]}")

# A run directory holds one run: refuse to clear a directory this script did not make.
if [ -d "$OUT" ] && [ -n "$(ls -A "$OUT")" ] && [ ! -e "$OUT/.${SCENARIO}_run" ]; then
    echo "error: $OUT exists and is not a run directory of this script" >&2; exit 2
fi
rm -rf "$OUT"; mkdir -p "$OUT/logs"; touch "$OUT/.${SCENARIO}_run"
source "$ROOT/tools/env.sh"
export ROS_LOG_DIR=$OUT/logs/ros PYTHONUNBUFFERED=1
# --progress: every step's output also goes to the terminal, log lines as '[node] message'.
if [ $PROGRESS = 1 ]; then export RCUTILS_CONSOLE_OUTPUT_FORMAT=${RCUTILS_CONSOLE_OUTPUT_FORMAT:-"[{name}] {message}"}; fi
cd "$ROOT"
PARAMS=(--ros-args)
for file in "${CONFIGS[@]}"; do PARAMS+=(--params-file "$file"); done

experiment_list() {   # a list parameter of the experiment node (the last file setting it wins)
    python - "$1" "${CONFIGS[@]}" <<'PY'
import sys, yaml
key, value = sys.argv[1], None
for path in sys.argv[2:]:
    value = (yaml.safe_load(open(path)).get("experiment") or {}).get(
        "ros__parameters", {}).get(key, value)
print(*value)
PY
}

# Every process gets its own session (setsid), so Ctrl-C reaches only this script, which then
# stops them in order: the running step first, then the learners (every node that calls
# others), then the servers they call (robot_sim, lpa_mapping, demonstration_source), the
# recorder last, so the bag holds everything the others published. The nodes of one wave stop
# side by side.
PIDS=() NAMES=() MODULES=() CURRENT=""
# LPA_HOSTS (set by scenarios/multi_host/run.sh): "NAME=NETNS ..." runs node or step NAME in
# that network namespace (ip netns exec keeps the PID, so stopping works as on one host), with
# the environment of LPA_HOST_ENV (e.g. discovery over the namespaces' subnet). NAME may be a
# shell pattern (babbling_*); the first entry that matches wins.
on_host() {   # on_host NAME: the command prefix that puts NAME on its host ('' on this one)
    local entry entries
    # every word of every line, without pathname expansion of the patterns
    read -r -d '' -a entries <<<"${LPA_HOSTS:-}" || true
    for entry in "${entries[@]}"; do
        # shellcheck disable=SC2053   # the entry's name is a pattern on purpose
        if [[ "$1" == ${entry%%=*} ]]; then echo "ip netns exec ${entry#*=} env ${LPA_HOST_ENV:-}"; return; fi
    done
}
# sim_time NAMESPACE: the arguments that put a node on the simulated clock of the robot in
# NAMESPACE (its robot_sim publishes /NAMESPACE/clock), so the node's clock and the header
# stamps of that robot's data agree. Lock-step nodes still take each state's time from the
# StepRobot answer, which is exact; the clock is for logs, tools and users' nodes.
sim_time() { echo "-p use_sim_time:=true -r /clock:=/$1/clock"; }
start() {   # start NAME MODULE ARGS...: a node in the background, its output in logs/NAME.log
    local name=$1 module=$2; shift 2
    setsid $(on_host "$name") python -m "lpa_transfer_nodes.$module" "$@" >"$OUT/logs/$name.log" 2>&1 &
    PIDS+=($!) NAMES+=("$name") MODULES+=("$module")
}
FAILED=0
stop_process() {   # stop_process PID NAME: SIGINT (the nodes finalise their files), SIGKILL after 20 s
    kill -INT "$1" 2>/dev/null || true
    await_process "$@"
}
await_process() {   # await_process PID NAME: wait for a signalled process, SIGKILL after 20 s
    local pid=$1 name=$2 waited=0 code=0
    while kill -0 "$pid" 2>/dev/null && [ $waited -lt 200 ]; do sleep 0.1; waited=$((waited + 1)); done
    if kill -0 "$pid" 2>/dev/null; then
        echo "$name did not stop on SIGINT: killed" >&2; kill -KILL "$pid" 2>/dev/null || true
        FAILED=1
    fi
    wait "$pid" || code=$?
    if [ $code != 0 ]; then echo "$name exited with $code (see $OUT/logs/$name.log)" >&2; FAILED=1; fi
}
stop_wave() {   # stop_wave INDEX...: SIGINT to each of these nodes at once, then wait for each
    local i
    for i in "$@"; do kill -INT "${PIDS[$i]}" 2>/dev/null || true; done
    for i in "$@"; do await_process "${PIDS[$i]}" "${NAMES[$i]}"; done
}
stop_all() {
    local i learners=() servers=() recorders=()
    if [ -n "$CURRENT" ]; then stop_process "$CURRENT" "$CURRENT_NAME"; CURRENT=""; fi
    for ((i = ${#PIDS[@]} - 1; i >= 0; i--)); do
        case ${MODULES[$i]} in
            recorder) recorders+=("$i") ;;
            robot_sim|lpa_mapping|demonstration_source) servers+=("$i") ;;
            *) learners+=("$i") ;;
        esac
    done
    stop_wave "${learners[@]}"; stop_wave "${servers[@]}"; stop_wave "${recorders[@]}"
    PIDS=() NAMES=() MODULES=()
}
trap stop_all EXIT
trap 'echo "interrupted: stopping the nodes" >&2; stop_all; exit 130' INT TERM

step() {   # step NAME COMMAND...: one step with its own log, waited for (so Ctrl-C interrupts it)
    local name=$1; shift
    echo "[$(date +%T)] $name" >&2
    if [ $PROGRESS = 1 ]; then
        setsid $(on_host "$name") "$@" > >(tee "$OUT/logs/$name.log") 2>&1 &
    else
        setsid $(on_host "$name") "$@" >"$OUT/logs/$name.log" 2>&1 &
    fi
    CURRENT=$! CURRENT_NAME=$name
    local code=0; wait "$CURRENT" || code=$?
    CURRENT=""
    if [ $code != 0 ]; then
        echo "error: $name failed; its log ($OUT/logs/$name.log) ends with:" >&2
        tail -n 15 "$OUT/logs/$name.log" >&2; exit 1
    fi
}

