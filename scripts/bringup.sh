#!/usr/bin/env bash
# Starts the nodes live (real time) for interactive use: sim_node, residual_node, mhe_node
# and detector_node (and foxglove_node with --foxglove), each with `ros2 run` in a process
# group of its own, their output in one folder.
# Ctrl-C (or SIGTERM) stops them all: SIGINT to each group, SIGKILL to what remains after
# a few seconds. A node ending on its own stops the others too (the simulator finishing
# its scenario: exit status 0; any other node, or a failing simulator: 1).
#
# The nodes run on the domain of scripts/env.sh (the checkout's own id, or your
# ROS_DOMAIN_ID), so `source scripts/env.sh; ros2 topic echo faults/estimate` in a second
# shell sees them.
set -euo pipefail

# Started with SIGINT ignored (as a background job of another script), bash could not trap
# Ctrl-C: start again with SIGINT at its default.
if [ -n "$(trap -p INT)" ] && [ -z "${_UAV_BRINGUP_SIGINT_RESET:-}" ]; then
    _UAV_BRINGUP_SIGINT_RESET=1 exec env --default-signal=INT bash "${BASH_SOURCE[0]}" "$@"
fi

usage() {
    cat <<'EOF'
usage: scripts/bringup.sh [--ns NS] [--params FILE] [--scenario FILE] [--logs DIR] [--foxglove]

  --ns NS          namespace of every node (-r __ns:=NS)
  --params FILE    a ROS parameter file given to every node (--params-file)
  --scenario FILE  the scenario sim_node flies (default: the shipped default scenario)
  --logs DIR       folder of the nodes' output (default: runs/bringup/logs)
  --foxglove       also start foxglove_node: every topic live in Foxglove (ws://127.0.0.1:8765)
EOF
}

root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
ns=""
params=""
scenario=""
logs="$root/runs/bringup/logs"
foxglove=""
STOP_TIMEOUT_S=5

die() {
    echo "bringup.sh: $*" >&2
    exit 2
}

while [ $# -gt 0 ]; do
    case "$1" in
        --ns|--params|--scenario|--logs)
            if [ $# -lt 2 ] || [ -z "$2" ]; then die "$1 needs a value"; fi
            case "$1" in
                --ns) ns="$2" ;;
                --params) params="$(realpath -e -- "$2" 2>/dev/null)" || die "no parameter file '$2'" ;;
                --scenario) scenario="$(realpath -e -- "$2" 2>/dev/null)" || die "no scenario file '$2'" ;;
                --logs) logs="$2" ;;
            esac
            shift 2 ;;
        --foxglove) foxglove=1; shift ;;
        -h|--help) usage; exit 0 ;;
        *) usage >&2; die "unknown argument '$1'" ;;
    esac
done

"$root/scripts/setup.sh"
# shellcheck disable=SC1091
source "$root/scripts/env.sh"
mkdir -p "$logs"
logs="$(cd "$logs" && pwd)"
export ROS_LOG_DIR="$logs"

names=(sim_node residual_node mhe_node detector_node)
[ -n "$foxglove" ] && names+=(foxglove_node)
declare -A packages=([sim_node]=uav_sim [residual_node]=uav_fault_estimator
                     [mhe_node]=uav_fault_estimator [detector_node]=uav_fault_estimator
                     [foxglove_node]=uav_fault_estimator)
declare -A pids=()

# Each node in a session (and so a process group) of its own, with SIGINT at its default:
# a background job of a script starts with SIGINT ignored, and would keep it ignored.
start_node() {
    local name="$1"
    local ros_args=()
    [ -n "$ns" ] && ros_args+=(-r "__ns:=$ns")
    [ -n "$params" ] && ros_args+=(--params-file "$params")
    [ "$name" = sim_node ] && [ -n "$scenario" ] && ros_args+=(-p "scenario:=$scenario")
    # every node but the simulator runs on its /clock
    [ "$name" != sim_node ] && ros_args+=(-p use_sim_time:=true)
    if [ ${#ros_args[@]} -gt 0 ]; then
        ros_args=(--ros-args "${ros_args[@]}")
    fi
    setsid env --default-signal=INT \
        ros2 run "${packages[$name]}" "$name" "${ros_args[@]}" >"$logs/$name.log" 2>&1 &
    pids[$name]=$!
}

# Whether any process of the node's group still exists.
group_alive() {
    kill -0 -- "-$1" 2>/dev/null
}

stop_all() {
    trap '' INT TERM  # a second Ctrl-C does not interrupt the stop
    local name pid waited=0
    for name in "${!pids[@]}"; do
        kill -INT -- "-${pids[$name]}" 2>/dev/null || true
    done
    while [ "$waited" -lt $((STOP_TIMEOUT_S * 10)) ]; do
        local alive=0
        for pid in "${pids[@]}"; do
            if group_alive "$pid"; then alive=1; fi
        done
        [ "$alive" -eq 0 ] && break
        sleep 0.1
        waited=$((waited + 1))
    done
    for name in "${!pids[@]}"; do
        if group_alive "${pids[$name]}"; then
            echo "bringup.sh: $name did not stop within ${STOP_TIMEOUT_S} s: killed" >&2
            kill -KILL -- "-${pids[$name]}" 2>/dev/null || true
        fi
    done
    wait 2>/dev/null || true
    pids=()
}

on_signal() {
    echo "bringup.sh: $1: stopping the nodes" >&2
    stop_all
    exit "$2"
}

trap 'on_signal interrupted 130' INT
trap 'on_signal terminated 143' TERM
trap 'stop_all' EXIT

echo "bringup.sh: ROS domain $ROS_DOMAIN_ID${ns:+, namespace $ns}; logs in $logs/<node>.log"
for name in "${names[@]}"; do
    start_node "$name"
done
topic="faults/estimate"
[ -n "$ns" ] && topic="${ns%/}/$topic"
echo "bringup.sh: running; watch with: source scripts/env.sh; ros2 topic echo $topic"
if [ -n "$foxglove" ]; then
    echo "bringup.sh: live in Foxglove: open a connection to the address in $logs/foxglove_node.log (default ws://127.0.0.1:8765)"
fi
echo "bringup.sh: Ctrl-C stops every node"

while true; do
    ended=""
    status=0
    wait -n -p ended "${pids[@]}" || status=$?
    [ -n "$ended" ] || continue  # woken by a signal whose trap did not exit
    for name in "${names[@]}"; do
        if [ "${pids[$name]:-}" = "$ended" ]; then break; fi
    done
    if [ "$name" = sim_node ] && [ "$status" -eq 0 ]; then
        echo "bringup.sh: sim_node finished its scenario: stopping the other nodes" >&2
        stop_all
        exit 0
    fi
    how="status $status"
    [ "$status" -gt 128 ] && how="$how (killed by signal $((status - 128)))"
    echo "bringup.sh: $name exited with $how (log: $logs/$name.log): stopping the other nodes" >&2
    stop_all
    exit 1
done
