"""The conveyor cell's physics on its own: parts flowing down the infeed belt of
scenes/scara_conveyor.toml for a while (no program, the robot holds still), and what it
costs: simulated seconds per wall second, the belt's transport error and the latches.

    .venv/bin/python bench/conveyor.py [--seconds 120]

Figures: real-time factor (one run; the machine is shared, compare runs made one after
the other), parts created / missed (all of them, nobody picks), speed error of a part
riding the belt (its travel over 5 s against speed x time), and latches per part.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

from twin.physics.cell import Cell

ROOT = Path(__file__).resolve().parent.parent


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=120.0, help="simulated seconds")
    args = parser.parse_args()
    cell = Cell.from_scene(ROOT / "scenes" / "scara_conveyor.toml")
    steps = round(args.seconds / cell.timestep)
    t0 = time.perf_counter()
    cell.step(round(1.0 / cell.timestep))
    first = cell.parts.instances[0]["body"]
    p0, s0 = cell.part_position(first)[0], cell.time
    cell.step(round(5.0 / cell.timestep))
    travel_mm = (cell.part_position(first)[0] - p0) * 1000.0
    expected = cell.conveyors["infeed"].speed_mm_s * (cell.time - s0)
    cell.step(steps - round(6.0 / cell.timestep))
    wall = time.perf_counter() - t0
    counts = cell.counts()
    latches = cell.components_report()["conveyor.infeed"]["latches"]
    print(f"conveyor cell: {cell.time:.1f} s simulated in {wall:.2f} s wall = {cell.time / wall:.1f}x real time; "
          f"{counts['created']} parts created, {counts['missed']} missed, {latches} latches; "
          f"belt transport error {100 * (travel_mm - expected) / expected:+.5f} % over 5 s")


if __name__ == "__main__":
    main()
