#!/usr/bin/env bash
# Starts the nodes live (real time) for interactive use: sim_node, residual_node, mhe_node,
# detector_node and standard_topics_node (and foxglove_node with --foxglove), each with
# `ros2 run` in a process group of its own, their output in one folder. Several --scenario options fly several
# aircraft in the one domain: vehicle k under /uavk with nodes of its own, on the first
# simulator's /clock (the others follow it). With --mavlink the aircraft is a real one:
# mavlink_node listens to its autopilot in sim_node's place and gives the others /clock.
# Ctrl-C (or SIGTERM) stops them all: SIGINT to each group, SIGKILL to what remains after
# a few seconds. A node ending on its own stops the others too (every simulator finishing
# its scenario: exit status 0; any other node, or a failing simulator: 1).
#
# The nodes run on the ROS domain scripts/env.sh reserves (the one of the shell that starts
# the script, or a free one; docs/ros_interface.md#ros-domains): a ROS_DOMAIN_ID another run
# of the project holds ends the script, status 2. A second shell watches them with
# `ROS_DOMAIN_ID=<the domain said> ros2 topic echo faults/estimate`.
set -euo pipefail

# Started with SIGINT ignored (as a background job of another script), bash could not trap
# Ctrl-C: start again with SIGINT at its default.
if [ -n "$(trap -p INT)" ] && [ -z "${_UAV_BRINGUP_SIGINT_RESET:-}" ]; then
    _UAV_BRINGUP_SIGINT_RESET=1 exec env --default-signal=INT bash "${BASH_SOURCE[0]}" "$@"
fi

usage() {
    cat <<'EOF'
usage: scripts/bringup.sh [--ns NS] [--params FILE] [--scenario FILE] [--logs DIR]
                         [--model-calibration FILE] [--foxglove]
                         [--mavlink CONNECTION [--vehicle NAME]]

  --ns NS          namespace of every node (-r __ns:=NS)
  --params FILE    a ROS parameter file given to every node (--params-file)
  --scenario FILE  the scenario sim_node flies (default: the shipped default scenario);
                   given again, another aircraft: vehicles /uav1, /uav2, ... (no --ns)
  --logs DIR       folder of the nodes' output (default: runs/bringup/logs)
  --model-calibration FILE
                   residual_node's models from scripts/calibrate_model.py's FILE, and
                   mhe_node's noise from the noise file it names
  --foxglove       also start foxglove_node: every topic live in Foxglove (ws://127.0.0.1:8765)
  --mavlink CONNECTION
                   the aircraft's autopilot instead of sim_node: mavlink_node listens on
                   CONNECTION (udpin:127.0.0.1:14550, /dev/ttyACM0,921600, ...; docs/onboard.md)
                   and publishes /clock; no --scenario
  --vehicle NAME   with --mavlink: the aircraft the nodes model (default: aerosonde);
                   mavlink_node carries its model's fuel unless --params sets fuel_mass_kg.
                   A flight log played to the link: --params from log_streamer LOG
                   --write-params FILE (the log's maximum ages; docs/onboard.md)
EOF
}

root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
ns=""
params=""
scenarios=()
logs="$root/runs/bringup/logs"
foxglove=""
model_calibration=""
mavlink=""
mavlink_vehicle=""
STOP_TIMEOUT_S=5

die() {
    echo "bringup.sh: $*" >&2
    exit 2
}

while [ $# -gt 0 ]; do
    case "$1" in
        --ns|--params|--scenario|--logs|--model-calibration|--mavlink|--vehicle)
            if [ $# -lt 2 ] || [ -z "$2" ]; then die "$1 needs a value"; fi
            case "$1" in
                --ns) ns="$2" ;;
                --params) params="$(realpath -e -- "$2" 2>/dev/null)" || die "no parameter file '$2'" ;;
                --scenario) scenarios+=("$(realpath -e -- "$2" 2>/dev/null)") || die "no scenario file '$2'" ;;
                --logs) logs="$2" ;;
                --model-calibration) model_calibration="$(realpath -e -- "$2" 2>/dev/null)" \
                    || die "no model calibration file '$2'" ;;
                --mavlink) mavlink="$2" ;;
                --vehicle) mavlink_vehicle="$2" ;;
            esac
            shift 2 ;;
        --foxglove) foxglove=1; shift ;;
        -h|--help) usage; exit 0 ;;
        *) usage >&2; die "unknown argument '$1'" ;;
    esac
done

if [ ${#scenarios[@]} -gt 1 ] && [ -n "$ns" ]; then
    die "--ns names the namespace of one aircraft; several --scenario fly /uav1, /uav2, ..."
fi
if [ -n "$mavlink" ] && [ ${#scenarios[@]} -gt 0 ]; then
    die "--mavlink listens to one aircraft's autopilot: it flies no --scenario"
fi
if [ -n "$mavlink_vehicle" ] && [ -z "$mavlink" ]; then
    die "--vehicle names the aircraft on --mavlink; a scenario names its own"
fi

"$root/scripts/setup.sh"
# shellcheck disable=SC1091
source "$root/scripts/env.sh" || exit 2  # a held ROS_DOMAIN_ID: env.sh's one line
mkdir -p "$logs"
logs="$(cd "$logs" && pwd)"
export ROS_LOG_DIR="$logs"

declare -A pids=()        # by node key: <vehicle>/<node>, or <node> alone
declare -A simulators=()  # the keys of the sim_nodes still flying
declare -A sources=()     # the keys of each aircraft's source: its sim_node or mavlink_node

# The graph (uav_fault_estimator.chain.node_graph): a line per node in start order, KEY PACKAGE
# EXECUTABLE and its ROS arguments, quoted for the shell.
plan_args=()
[ -n "$ns" ] && plan_args+=(--ns "$ns")
[ -n "$params" ] && plan_args+=(--params "$params")
for scenario in "${scenarios[@]}"; do plan_args+=(--scenario "$scenario"); done
# a model calibration is checked there, for each scenario's vehicle: one line, no node started
[ -n "$model_calibration" ] && plan_args+=(--model-calibration "$model_calibration")
[ -n "$foxglove" ] && plan_args+=(--foxglove)
[ -n "$mavlink" ] && plan_args+=(--mavlink "$mavlink")
[ -n "$mavlink_vehicle" ] && plan_args+=(--vehicle "$mavlink_vehicle")
plan="$(python -m uav_fault_estimator.chain.node_graph --caller bringup.sh "${plan_args[@]}")" || exit 2

# Each node in a session (and so a process group) of its own, with SIGINT at its default:
# a background job of a script starts with SIGINT ignored, and would keep it ignored.
# start_node LINE (a line of the plan)
start_node() {
    local words key package executable
    eval "words=($1)"
    key="${words[0]}" package="${words[1]}" executable="${words[2]}"
    mkdir -p "$(dirname "$logs/$key.log")"
    setsid env --default-signal=INT \
        ros2 run "$package" "$executable" --ros-args "${words[@]:3}" \
        >"$logs/$key.log" 2>&1 &
    pids[$key]=$!
    [ "$executable" = sim_node ] && simulators[$key]=1
    case "$executable" in sim_node|mavlink_node) sources[$key]="$executable" ;; esac
    return 0
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
while IFS= read -r line; do start_node "$line"; done <<<"$plan"
for key in "${!sources[@]}"; do  # a vehicle's nodes: uavk/<node>, or under --ns
    vehicle="${key%"${sources[$key]}"}"
    topic="${vehicle:+/$vehicle}faults/estimate"
    [ -z "$vehicle" ] && [ -n "$ns" ] && topic="${ns%/}/$topic"
    echo "bringup.sh: running; watch with: source scripts/env.sh; ROS_DOMAIN_ID=$ROS_DOMAIN_ID ros2 topic echo $topic"
done
if [ -n "$foxglove" ]; then
    echo "bringup.sh: live in Foxglove: open a connection to the address in $logs/foxglove_node.log (default ws://127.0.0.1:8765)"
fi
[ -n "$mavlink" ] && echo "bringup.sh: mavlink_node listens on $mavlink (log: $logs/mavlink_node.log)"
echo "bringup.sh: Ctrl-C stops every node"

while true; do
    ended=""
    status=0
    wait -n -p ended "${pids[@]}" || status=$?
    [ -n "$ended" ] || continue  # woken by a signal whose trap did not exit
    for key in "${!pids[@]}"; do
        if [ "${pids[$key]}" = "$ended" ]; then break; fi
    done
    if [ -n "${simulators[$key]:-}" ] && [ "$status" -eq 0 ]; then
        unset "simulators[$key]"
        unset "pids[$key]"
        if [ ${#simulators[@]} -eq 0 ]; then
            echo "bringup.sh: every sim_node finished its scenario: stopping the other nodes" >&2
            stop_all
            exit 0
        fi
        echo "bringup.sh: $key finished its scenario" >&2
        continue
    fi
    how="status $status"
    [ "$status" -gt 128 ] && how="$how (killed by signal $((status - 128)))"
    echo "bringup.sh: $key exited with $how (log: $logs/$key.log): stopping the other nodes" >&2
    stop_all
    exit 1
done
