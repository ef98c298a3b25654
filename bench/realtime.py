"""Real-time factor of the demo: simulated seconds per wall second for the whole run
of programs/vplus/move_parts.pg on scenes/scara_pick.toml (interpreter, controller,
MuJoCo, feeder, belt and bin; no recording unless --rrd is given).

    .venv/bin/python bench/realtime.py [--rrd out/bench.rrd]

The figure is one run's ratio; this machine is shared and noisy, so compare runs
made one after the other on the same machine.
"""

from __future__ import annotations

import argparse
import io
import statistics
from pathlib import Path

from twin.language.vplus.runtime import Console
from twin.runner import run_program

ROOT = Path(__file__).resolve().parent.parent


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rrd", default=None, help="also write a Rerun recording")
    args = parser.parse_args()
    result = run_program(ROOT / "programs" / "vplus" / "move_parts.pg",
                         scene=ROOT / "scenes" / "scara_pick.toml", rrd_path=args.rrd,
                         console=Console(stdin=io.StringIO(), echo=None))
    r = result.report
    print(f"demo run: {r.sim_time_s:.1f} s simulated in {r.wall_time_s:.2f} s wall "
          f"= {r.sim_time_s / r.wall_time_s:.1f}x real time; "
          f"cycle time {statistics.median(r.cycle_times_s):.3f} s (median), bin {r.regions.get('bin')}")


if __name__ == "__main__":
    main()
