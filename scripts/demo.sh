#!/usr/bin/env bash
# Run the main job on a fresh machine: the SCARA pick-and-place cell, its report,
# a Rerun recording (out/demo.rrd), then check the report against expectations.
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
"$ROOT/scripts/bootstrap.sh"
cd "$ROOT"
export MUJOCO_GL="${MUJOCO_GL:-egl}"
mkdir -p out

.venv/bin/twin run programs/vplus/move_parts.pg --scene scenes/scara_pick.toml \
    --report out/report.json --rrd out/demo.rrd
.venv/bin/twin check out/report.json --expect scenes/scara_pick.expect.toml
