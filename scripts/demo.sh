#!/usr/bin/env bash
# The main job: fly a scenario through the nodes, record every topic, report.
#   ./scripts/demo.sh [SCENARIO.yaml] [--out DIR]      (uav_fault_estimator.chain.demo_run does the work)
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
# set up if needed; its closing "up to date" note would only be noise here
if ! "$root/scripts/setup.sh" 2>&1 | { grep --line-buffered -v '^setup.sh: the workspace is up to date ' || true; } >&2
then
    exit 1
fi
# shellcheck disable=SC1091
source "$root/scripts/env.sh"
exec python "$root/scripts/demo.py" "$@"
