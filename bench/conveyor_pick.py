"""The conveyor demo programs over their full run (5 simulated minutes at 100 mm/s, one part
every 2 s on average): per program and cell, the parts created, picked, placed, missed and
dropped, how far the placed parts sit from their tray cells, the median cycle time and
the wall time.  With --interval S the parts come every S seconds instead (beyond the
robot's capacity: the programs skip parts and the report counts them missed).  Not a
test: tests/test_conveyor_pick.py checks the same runs (-m slow).

    .venv/bin/python bench/conveyor_pick.py [--interval 0.6] [--time 300]
"""

from __future__ import annotations

import argparse
import json
import math
import re
import statistics
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from twin.runner import run_program  # noqa: E402

PROGRAMS = {"V+": ROOT / "programs" / "vplus" / "conveyor_pick.pg", "GPL": ROOT / "programs" / "gpl" / "conveyor_pick"}
CELLS = {"fingers": ROOT / "scenes" / "scara_conveyor.toml", "suction": ROOT / "scenes" / "scara_conveyor_suction.toml"}


def _scene(scene: Path, interval: float | None, folder: Path) -> Path:
    if interval is None:
        return scene
    text = re.sub(r"mean_interval = [0-9.]+", f"mean_interval = {interval}", scene.read_text())
    text = re.sub(r'model = "models/', f'model = "{ROOT.as_posix()}/models/', text)
    path = folder / scene.name
    path.write_text(text)
    return path


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--interval", type=float, default=None, help="mean seconds between parts")
    parser.add_argument("--time", type=float, default=400.0, help="simulated seconds at most")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        for language, program in PROGRAMS.items():
            for cell, scene in CELLS.items():
                report_path = folder / "report.json"
                wall = time.perf_counter()
                run_program(program, scene=_scene(scene, args.interval, folder), report_path=report_path,
                            max_sim_time=args.time)
                wall = time.perf_counter() - wall
                report = json.loads(report_path.read_text())
                centres = report["components"]["tray.tray"]["cell_centres_mm"]
                errors = [math.dist(p["pose"][:2], centres[p["cell"]][:2])
                          for p in report["parts"] if p.get("cell") is not None]
                c = report["counts"]
                print(f"{language:3} {cell:7}: {report['sim_time_s']:.0f} s simulated in {wall:.0f} s; created "
                      f"{c['created']}, picked {c['picked']}, placed {c['placed']}, missed {c['missed']}, "
                      f"dropped {c['dropped']}; tray cell error max {max(errors, default=0):.2f} mm, median "
                      f"{statistics.median(errors) if errors else 0:.2f} mm; cycle "
                      f"{statistics.median(report['cycle_times_s']) if report['cycle_times_s'] else 0:.2f} s; "
                      f"errors {len(report['errors'])}; output: {report['output'].strip().splitlines()[-1:]}")


if __name__ == "__main__":
    main()
