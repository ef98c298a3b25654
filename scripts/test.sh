#!/usr/bin/env bash
# Run the test suite; arguments go to pytest (e.g. scripts/test.sh tests/test_check.py -k cli).
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
"$ROOT/scripts/bootstrap.sh"
cd "$ROOT"
export MUJOCO_GL="${MUJOCO_GL:-egl}"
# On every core (pytest-xdist): about 40 % less time than one process on a 2-core machine.
# Arguments come after, so `scripts/test.sh -n 0 ...` runs in one process.
exec .venv/bin/python -m pytest -q -n auto --dist worksteal "$@"
