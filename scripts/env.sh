# Shell environment of the project, to be sourced: `source scripts/env.sh`.
# Activates .venv, sources the colcon install space (which puts the project's `ros2`,
# package ros2cli_lite, on PATH where no real ROS 2 is sourced), keeps DDS on loopback and
# gives the shell a ROS domain of its own.
# Run scripts/setup.sh first.

_uav_root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"

if [ ! -f "$_uav_root/ros_ws/install/setup.bash" ]; then
    echo "env.sh: ros_ws is not built: run $_uav_root/scripts/setup.sh first" >&2
    unset _uav_root
    return 1 2>/dev/null || exit 1
fi

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

# No DDS traffic beyond loopback on these machines; a domain of this shell's own unless
# the caller chose one (derived from the checkout's path, so two checkouts do not meet).
export ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST
# Quicker discovery for short-lived tools (see the file); a user's own profile wins.
export FASTRTPS_DEFAULT_PROFILES_FILE="${FASTRTPS_DEFAULT_PROFILES_FILE:-$_uav_root/config/fastdds.xml}"
if [ -z "${ROS_DOMAIN_ID:-}" ]; then
    ROS_DOMAIN_ID=$(( $(printf '%s' "$_uav_root" | cksum | cut -d' ' -f1) % 90 + 1 ))
    export ROS_DOMAIN_ID
fi
unset _uav_root _uav_nounset
