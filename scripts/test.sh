#!/usr/bin/env bash
# Sets the workspace up if needed, then runs the linter and every test (unit and
# integration): what CI runs. Extra arguments go to pytest, e.g. `./scripts/test.sh -k echo`.
#   ./scripts/test.sh --quick [ARGS...]   the tests marked neither slow nor integration
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
selection=()
if [ "${1:-}" = "--quick" ]; then
    shift
    selection=(-m "not slow and not integration")
fi
./scripts/setup.sh
# shellcheck disable=SC1091
source scripts/env.sh
ruff check .
python -m pytest "${selection[@]}" "$@"
