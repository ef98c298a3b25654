"""Simulated cycle time of the standard SCARA benchmark motion (the "Adept cycle": 25 mm
up, 305 mm over, 25 mm down, and back) at full speed, against the datasheet figure of the
modelled robot (Cobra s600: 0.54 s, models/robots/cobra_s600.xml).  Not a test; the test
suite checks the same figure (tests/test_motion_controller.py).

The motion is a V+ program run on the demo cell, as a user would write it: SPEED 100
MONITOR, then DEPART 25 / APPRO b, 25 / MOVE b / DEPART 25 / APPRO a, 25 / MOVE a in a
loop, continuous path on (burst: no stop at the ends, no hand time), 2 kg-class payload
as in the cell.  The cycle time is the controller's timeline (the simulated start of
each cycle's first motion), the median over the cycles after the first.

`--demo` measures instead the demo program move.parts (the eV+ guide's sample program,
programs/vplus/move_parts.pg, `parts` cut down) on the demo cell at SPEED 100 MONITOR,
against the datasheet-based expectation DEMO_EXPECTED_S: the burst-mode Adept cycle plus
the two HAND.TIME waits the program asks for (CLOSEI, OPENI).  The demo moves farther
(360 mm over, 50.8 mm lifts at the place) and stops at both ends, so it takes longer;
the test suite holds it within DEMO_BAND of the expectation.

    .venv/bin/python bench/cycle_time.py [--cycles 10] [--straight] [--stop] [--demo]
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
HAND_TIME_S = 0.16  # move.parts: PARAMETER HAND.TIME = 0.16, waited after CLOSEI and OPENI
DEMO_EXPECTED_S = DATASHEET_S + 2 * HAND_TIME_S
DEMO_BAND = (1.0, 1.35)  # plausible demo cycle / DEMO_EXPECTED_S: farther, and two stops
DEMO_PROGRAM = Path(__file__).resolve().parent.parent / "programs" / "vplus" / "move_parts.pg"
MOTIONS_PER_PART = 6  # APPRO, MOVES, DEPARTS at the pick and again at the place
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
    text = PROGRAM.format(cycles=cycles, s="S" if straight else "", stop="BREAK" if stop else "")
    sim = _run(text, scene, {"a": POINT_A, "b": POINT_B})
    starts = [m.start_s for m in sim.controller.history[1:]]  # after the MOVE a
    per_cycle = starts[::6]
    return [b - a for a, b in zip(per_cycle[1:], per_cycle[2:])]


def demo_cycle_times(parts: int = 6, scene: str | Path = DEFAULT_SCENE) -> list[float]:
    """Seconds per part of move.parts at SPEED 100 MONITOR, one per part after the first
    (the time between the starts of successive APPRO pick motions)."""
    text = DEMO_PROGRAM.read_text().replace("parts = 100", f"parts = {parts}")
    sim = _run(text, scene, {}, monitor_speed=100.0)
    starts = [m.start_s for m in sim.controller.history[1::MOTIONS_PER_PART]]  # after the MOVE start
    return [b - a for a, b in zip(starts[1:], starts[2:])]


def _run(text: str, scene: str | Path, locations: dict, monitor_speed: float | None = None) -> Simulation:
    """Run a V+ program on a cell (its taught locations, then `locations`); the simulation."""
    sim = Simulation(scene)
    if monitor_speed is not None:
        sim.controller.settings.monitor_speed = monitor_speed
    system = VPlusSystem(sim.controller, sim.io, sim.clock, console=Console(echo=None))
    for name, location in {**sim.taught_locations(), **locations}.items():
        system.define_location(name, location)
    (name,) = system.load_text(text, "bench.pg")
    sim.scheduler.add(system.start(name))
    outcome = sim.run(max_sim_time=60.0)
    if outcome.errors:
        raise RuntimeError(outcome.errors)
    return sim


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--cycles", type=int, default=10)
    ap.add_argument("--straight", action="store_true", help="DEPARTS / MOVES for the vertical legs")
    ap.add_argument("--stop", action="store_true", help="BREAK at both ends (CP broken)")
    ap.add_argument("--demo", action="store_true", help="move.parts on the demo cell instead")
    args = ap.parse_args()
    if args.demo:
        median = statistics.median(demo_cycle_times(args.cycles))
        print(f"move.parts on the Cobra cell, SPEED 100 MONITOR: {median:.3f} s per part; "
              f"expected from the datasheet {DEMO_EXPECTED_S:.2f} s "
              f"({DATASHEET_S:.2f} s Adept cycle + 2 x HAND.TIME {HAND_TIME_S:.2f} s); "
              f"{100 * (median / DEMO_EXPECTED_S - 1):+.1f} %")
        sys.exit(0)
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
