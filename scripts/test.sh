#!/usr/bin/env bash
# Sets the workspace up if needed, then runs the linter and every test (unit and
# integration). Extra arguments go to pytest, e.g. `./scripts/test.sh -k echo`.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
./scripts/setup.sh
# shellcheck disable=SC1091
source scripts/env.sh
ruff check .
python -m pytest "$@"
