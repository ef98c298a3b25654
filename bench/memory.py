"""Memory over a long run: the demo cell runs a motion cycle (joint and straight-line
moves between the nest and the belt, closing and opening the gripper in the air, so no
part piles up in the bin) for one simulated hour; the process's resident memory is
sampled every simulated minute.  Flat
means the last ten minutes' median within 5 % of the median of minutes 5 to 15 (after
the caches have filled).

    .venv/bin/python bench/memory.py [--minutes 60]
"""

from __future__ import annotations

import argparse
import io
import statistics
import tempfile
from pathlib import Path

from twin.language.vplus.runtime import Console
from twin.runner import finish_run, start_program

ROOT = Path(__file__).resolve().parent.parent
SCENE = ROOT / "scenes" / "scara_pick.toml"
PROGRAM = """.PROGRAM soak()
    WHILE TRUE DO
        APPRO pick, 60
        APPROS pick, 40
        CLOSEI
        APPRO place, 80
        APPROS place, 50
        OPENI
        MOVE start
    END
.END
"""


def rss_mb() -> float:
    with open("/proc/self/status") as status:
        for line in status:
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) / 1024
    raise RuntimeError("no VmRSS in /proc/self/status")


def measure(minutes: float = 60.0) -> dict:
    """RSS samples (MB) once per simulated minute; 'growth' compares the end with minutes 5-15."""
    with tempfile.TemporaryDirectory() as tmp:
        program = Path(tmp) / "soak.pg"
        program.write_text(PROGRAM)
        started = start_program(program, SCENE, console=Console(stdin=io.StringIO(), echo=None))
        sim = started.simulation
        samples: list[float] = []

        def sample() -> bool:
            if sim.cell.time >= len(samples) * 60.0:
                samples.append(rss_mb())
            return sim.cell.time >= minutes * 60.0

        outcome = sim.run(max_sim_time=minutes * 60.0 + 30.0, on_cycle=sample)
        report = finish_run(started, outcome).report
    early = statistics.median(samples[5:16]) if len(samples) > 16 else samples[0]
    late = statistics.median(samples[-10:])
    return {"samples_mb": samples, "early_mb": early, "late_mb": late, "growth": late / early - 1.0,
            "sim_time_s": report.sim_time_s, "wall_time_s": report.wall_time_s, "errors": report.errors}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--minutes", type=float, default=60.0)
    m = measure(parser.parse_args().minutes)
    print(f"memory: {m['early_mb']:.0f} MB early, {m['late_mb']:.0f} MB at the end "
          f"({m['growth'] * 100:+.1f} %) over {m['sim_time_s']:.0f} s simulated in {m['wall_time_s']:.0f} s; "
          f"errors: {len(m['errors'])}")


if __name__ == "__main__":
    main()
