#!/usr/bin/env bash
# Sets the workspace up if needed, then runs the linter and every test (unit and
# integration): what CI runs, the test files spread over one pytest process more than the
# cores (a file's tests stay together: they share its ROS domain and fixtures; the node
# tests spend part of their time waiting on other processes: one per core leaves the cores
# idle part of the run). Extra arguments go to pytest, e.g. `./scripts/test.sh -k echo`,
# `./scripts/test.sh -n 0` (in this process).
#   ./scripts/test.sh --quick [ARGS...]   the tests marked neither slow nor integration
#   ./scripts/test.sh --repeat N [--under-load] [ARGS...]
#       the selection N times in a row (under load: a busy process on every core), then per
#       test how many rounds failed; status 1 if any did (scripts/repeat_tests.py)
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
selection=()
repeat=()
while [ $# -gt 0 ]; do
    case "$1" in
        --quick) selection=(-m "not slow and not integration"); shift ;;
        --repeat)
            [[ "${2:-}" =~ ^[1-9][0-9]*$ ]] || { echo "test.sh: --repeat takes a count N >= 1" >&2; exit 2; }
            repeat+=(--rounds "$2"); shift 2 ;;
        --under-load) repeat+=(--under-load); shift ;;
        *) break ;;
    esac
done
if [ ${#repeat[@]} -gt 0 ] && [[ ! " ${repeat[*]} " =~ " --rounds " ]]; then
    echo "test.sh: --under-load goes with --repeat N" >&2
    exit 2
fi
./scripts/setup.sh
# shellcheck disable=SC1091
source scripts/env.sh
ruff check .
spread=(--numprocesses "$(($(nproc) + 1))" --dist loadfile)
if [ ${#repeat[@]} -gt 0 ]; then
    exec python scripts/repeat_tests.py "${repeat[@]}" "${spread[@]}" "${selection[@]}" "$@"
fi
python -m pytest "${spread[@]}" "${selection[@]}" "$@"
