"""Simulated cycle time of the standard SCARA benchmark motion (the "Adept cycle": 25 mm
up, 305 mm over, 25 mm down, and back) at full speed, against the datasheet figure of the
modelled robot (Cobra s600: 0.54 s, models/robots/cobra_s600.xml).  Not a test; the test
suite checks the same figure (tests/test_motion_controller.py).

The motion is a V+ program run on the demo cell, as a user would write it: SPEED 100
MONITOR, then DEPART 25 / APPRO b, 25 / MOVE b / DEPART 25 / APPRO a, 25 / MOVE a in a
loop, continuous path on (burst: no stop at the ends, no hand time), 2 kg-class payload
as in the cell.  The cycle time is the controller's timeline (the simulated start of
each cycle's first motion), the median over the cycles after the first.

    .venv/bin/python bench/cycle_time.py [--cycles 10] [--straight] [--stop]
"""

from __future__ import annotations

import argparse
import statistics
import sys
from pathlib import Path

from twin.controller.location import Location
from twin.language.vplus.runtime import Console, VPlusSystem
from twin.simulation import DEFAULT_SCENE, Simulation

DATASHEET_S = 0.54  # Omron Adept Cobra s600 datasheet: Adept cycle, burst mode, 2 kg
POINT_A = Location(350.0, -152.5, 300.0, 0.0, 180.0, 180.0)  # 305 mm apart along y,
POINT_B = Location(350.0, 152.5, 300.0, 0.0, 180.0, 180.0)  # in front of the robot

PROGRAM = """.PROGRAM adept.cycle()
    SPEED 100 MONITOR
    MOVE a
    BREAK
    FOR i = 1 TO {cycles}
        DEPART{s} 25
        APPRO b, 25
        MOVE{s} b
        {stop}
        DEPART{s} 25
        APPRO a, 25
        MOVE{s} a
        {stop}
    END
    BREAK
.END
"""


def cycle_times(cycles: int = 10, straight: bool = False, stop: bool = False,
                scene: str | Path = DEFAULT_SCENE) -> list[float]:
    """Seconds per Adept cycle, one per cycle after the first."""
    sim = Simulation(scene)
    system = VPlusSystem(sim.controller, sim.io, sim.clock, console=Console(echo=None))
    system.define_location("a", POINT_A)
    system.define_location("b", POINT_B)
    text = PROGRAM.format(cycles=cycles, s="S" if straight else "", stop="BREAK" if stop else "")
    (name,) = system.load_text(text, "adept_cycle.pg")
    task = system.start(name)
    sim.scheduler.add(task)
    outcome = sim.run(max_sim_time=60.0)
    if outcome.errors:
        raise RuntimeError(outcome.errors)
    starts = [m.start_s for m in sim.controller.history[1:]]  # after the MOVE a
    per_cycle = starts[::6]
    return [b - a for a, b in zip(per_cycle[1:], per_cycle[2:])]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--cycles", type=int, default=10)
    ap.add_argument("--straight", action="store_true", help="DEPARTS / MOVES for the vertical legs")
    ap.add_argument("--stop", action="store_true", help="BREAK at both ends (CP broken)")
    args = ap.parse_args()
    times = cycle_times(args.cycles, args.straight, args.stop)
    median = statistics.median(times)
    print(f"Adept cycle (25/305/25 mm and back), Cobra s600 model, SPEED 100 MONITOR, "
          f"{'straight' if args.straight else 'joint'} vertical legs, {'stops' if args.stop else 'CP'}:")
    print(f"  simulated {median:.3f} s per cycle (min {min(times):.3f}, max {max(times):.3f}, "
          f"{len(times)} cycles); datasheet {DATASHEET_S:.2f} s; "
          f"{100 * (median / DATASHEET_S - 1):+.1f} %")
    sys.exit(0)


if __name__ == "__main__":
    main()
