#!/usr/bin/env bash
# Chapter 5 seed shares on separate "hosts" (issue 30, item 4): each seed runs the whole graph
# (scenarios/inverse_dynamics/run.sh) in its own Linux network namespace, in parallel; then
# scenarios/inverse_dynamics/merge_results.py joins the shares into what one run over all the
# seeds writes. A share needs nothing from the others, so each namespace has a loopback
# interface only: no link, no route, nothing it could reach; DDS discovers on that loopback
# (ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST, as on one host) over UDP only
# (FASTDDS_BUILTIN_TRANSPORTS=UDPv4: shared memory would join the shares' processes behind the
# namespaces' back). On real machines: run.sh with a share's --override file on each, then
# merge_results.py on the copied run directories.
#
# Usage (as root): scenarios/multi_host/seed_shares.sh --seeds "0 1" --out DIR
#                  [inverse_dynamics run.sh arguments: --config, --override ...]
# Writes DIR/share_<seed>.yaml (the override naming the seed), DIR/seed<seed>/ (that share's
# run; its terminal output in DIR/seed<seed>.log) and DIR/merged/ (the joined outputs).
# Exits 1 if a share or the merge fails, naming it. Without root or network namespaces it
# says so in one line and exits 77 (skip). The namespaces are removed at the end, also after
# Ctrl-C or a failure.
set -uo pipefail
HERE=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
ROOT=$(cd "$HERE/../.." && pwd)
if [ "$(id -u)" != 0 ] || ! ip netns list >/dev/null 2>&1; then
    echo "skipped: network namespaces need root and iproute2's ip netns" >&2; exit 77
fi
SEEDS=() OUT="" ARGS=()
while [ $# -gt 0 ]; do
    case "$1" in
        --seeds) read -r -a SEEDS <<<"$2"; shift 2 ;;
        --out) OUT=$2; shift 2 ;;
        *) ARGS+=("$1"); shift ;;
    esac
done
if [ ${#SEEDS[@]} -lt 1 ] || [ -z "$OUT" ]; then
    echo "usage: $0 --seeds \"S1 S2 ...\" --out DIR [run.sh arguments]" >&2; exit 2
fi
for seed in "${SEEDS[@]}"; do
    [[ "$seed" =~ ^[0-9]+$ ]] || { echo "error: seed '$seed' is not a whole number" >&2; exit 2; }
done
source "$ROOT/tools/env.sh"
mkdir -p "$OUT"
OUT=$(realpath "$OUT")
PREFIX=lpa$$sh
PIDS=()
cleanup() {
    for pid in "${PIDS[@]}"; do kill -TERM "$pid" 2>/dev/null; done
    for pid in "${PIDS[@]}"; do wait "$pid" 2>/dev/null; done
    for seed in "${SEEDS[@]}"; do ip netns del "$PREFIX$seed" 2>/dev/null; done
}
trap cleanup EXIT
trap 'exit 130' INT TERM
for seed in "${SEEDS[@]}"; do
    ns=$PREFIX$seed
    ip netns add "$ns" && ip -n "$ns" link set lo up || {
        echo "error: could not make the network namespace for seed $seed" >&2; exit 1; }
    printf 'experiment:\n  ros__parameters:\n    seeds: [%s]\n' "$seed" >"$OUT/share_$seed.yaml"
    rm -rf "$OUT/seed$seed"
    ip netns exec "$ns" env -u FASTRTPS_DEFAULT_PROFILES_FILE FASTDDS_BUILTIN_TRANSPORTS=UDPv4 \
        bash "$ROOT/scenarios/inverse_dynamics/run.sh" "${ARGS[@]}" \
        --override "$OUT/share_$seed.yaml" --out "$OUT/seed$seed" >"$OUT/seed$seed.log" 2>&1 &
    PIDS+=($!)
    echo "seed $seed: running in network namespace $ns (log: $OUT/seed$seed.log)"
done
FAILED=()
for i in "${!PIDS[@]}"; do
    wait "${PIDS[$i]}" || FAILED+=("${SEEDS[$i]}")
done
PIDS=()
if [ ${#FAILED[@]} -gt 0 ]; then
    for seed in "${FAILED[@]}"; do
        echo "error: the share of seed $seed failed; last lines of $OUT/seed$seed.log:" >&2
        tail -n 5 "$OUT/seed$seed.log" >&2
    done
    exit 1
fi
RUNS=()
for seed in "${SEEDS[@]}"; do RUNS+=("$OUT/seed$seed"); done
python "$ROOT/scenarios/inverse_dynamics/merge_results.py" "$OUT/merged" "${RUNS[@]}" \
    >"$OUT/merge.log" 2>&1 || {
    echo "error: merging the shares failed:" >&2; tail -n 5 "$OUT/merge.log" >&2; exit 1; }
echo "merged ${#SEEDS[@]} shares into $OUT/merged"
