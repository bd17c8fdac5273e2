# Shell environment of the project, to be sourced: `source scripts/env.sh`.
# Activates .venv, sources the colcon install space (which puts the project's `ros2`,
# package ros2cli_lite, on PATH where no real ROS 2 is sourced), keeps DDS on loopback and
# gives the shell a ROS domain of its own (docs/ros_interface.md#ros-domains). A
# ROS_DOMAIN_ID another run of the project holds is refused: one line, status 1.
# Run scripts/setup.sh first.

_uav_root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"

if [ ! -f "$_uav_root/ros_ws/install/setup.bash" ]; then
    echo "env.sh: ros_ws is not built: run $_uav_root/scripts/setup.sh first" >&2
    unset _uav_root
    return 1 2>/dev/null || exit 1
fi

# A ROS domain this shell holds for as long as it lives (the one it was given, unless
# another run of the project holds that): uav_common.ros_domain, run from the checkout
# (standard library only) before anything in the shell changes, so a refusal leaves it as
# it was. The shell's PID is read here: inside $(...) BASHPID is the subshell's.
_uav_shell_pid="${BASHPID:-$$}"
if ! _uav_domain="$(PYTHONPATH="$_uav_root/ros_ws/src/uav_common" "$_uav_root/.venv/bin/python" \
        -m uav_common.ros_domain --caller env.sh --pid "$_uav_shell_pid" \
        --requested "${ROS_DOMAIN_ID:-}")"; then
    unset _uav_root _uav_domain _uav_shell_pid
    return 1 2>/dev/null || exit 1
fi
unset _uav_shell_pid

# colcon's and the venv's scripts read unset variables: allow it while sourcing them.
case $- in *u*) _uav_nounset=1; set +u ;; *) _uav_nounset= ;; esac
# shellcheck disable=SC1091
source "$_uav_root/.venv/bin/activate"
if [ "${ROS_DISTRO:-}" != "jazzy" ]; then
    # The ROS 2 wheels install their prefix into the venv itself: it is the underlay.
    export AMENT_PREFIX_PATH="$VIRTUAL_ENV${AMENT_PREFIX_PATH:+:$AMENT_PREFIX_PATH}"
    export CMAKE_PREFIX_PATH="$VIRTUAL_ENV${CMAKE_PREFIX_PATH:+:$CMAKE_PREFIX_PATH}"
fi
# shellcheck disable=SC1091
source "$_uav_root/ros_ws/install/setup.bash"
if [ -n "$_uav_nounset" ]; then set -u; fi

# No DDS traffic beyond loopback on these machines.
export ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST
export ROS_DOMAIN_ID="$_uav_domain"
# Quicker discovery for short-lived tools (see the file); a user's own profile wins.
export FASTRTPS_DEFAULT_PROFILES_FILE="${FASTRTPS_DEFAULT_PROFILES_FILE:-$_uav_root/config/fastdds.xml}"
unset _uav_root _uav_nounset _uav_domain
