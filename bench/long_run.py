"""Long runs stay fast: the demo cell (scenes/scara_pick.toml) runs the demo program
(programs/vplus/move_parts.pg) with ``parts`` raised to 1000; the CPU time
(`time.process_time()`, the machine is shared) of every 25 parts placed and the process's
resident memory are sampled.  The feeder recycles its pool (120 bodies by default,
``--pool``): once every body has been presented it takes back the one that came to rest
in the bin first, so the bin never overflows.  Flat means the last four blocks' median
within 20 % of the median of blocks 3 to 6 (the first blocks fill the pool), and memory
likewise within 5 %.

    .venv/bin/python bench/long_run.py [--parts 1000] [--pool 120]

Measured (2 shared cores, CPU time): 2.65 s per 25 parts early, 2.43 s for the last
blocks (-8 %), memory 267 to 271 MB (+1.4 %), 1000 parts in the bin in the report.  A
feeder `pool` of 2000: 6.5 s per 25 parts before feeders and sources built at most 120
bodies a type (parts.py MAX_RECYCLED_BODIES), 2.3 s after.
"""

from __future__ import annotations

import argparse
import io
import re
import statistics
import tempfile
import time
from pathlib import Path

from memory import rss_mb  # bench/ modules, run as scripts
from twin.language.vplus.runtime import Console
from twin.runner import finish_run, start_program

ROOT = Path(__file__).resolve().parent.parent
DEMO = ROOT / "programs" / "vplus" / "move_parts.pg"
SCENE = ROOT / "scenes" / "scara_pick.toml"
BLOCK = 25  # parts per sample


def measure(parts: int = 1000, pool: int = 120, show=None) -> dict:
    """CPU seconds and RSS (MB) per block of 25 parts presented by the feeder."""
    with tempfile.TemporaryDirectory() as tmp:
        program = Path(tmp) / "move_parts.pg"
        program.write_text(re.sub(r"parts = 100\b", f"parts = {parts}", DEMO.read_text()))
        scene = Path(tmp) / "scara_pick.toml"
        scene.write_text(re.sub(r"^pool = 120\b", f"pool = {pool}", SCENE.read_text(), flags=re.M))
        started = start_program(program, scene, console=Console(stdin=io.StringIO(), echo=None))
        sim = started.simulation
        feeder = sim.cell.ctx.component("feeder", "nest")
        cpu, rss, sim_s = [], [], []
        mark = [time.process_time(), 0.0]

        def sample() -> None:
            if feeder.presented > (len(cpu) + 1) * BLOCK:
                now = time.process_time()
                cpu.append(now - mark[0])
                sim_s.append(sim.cell.time - mark[1])
                rss.append(rss_mb())
                mark[:] = [now, sim.cell.time]
                if show is not None:
                    show(len(cpu) - 1, cpu[-1], sim_s[-1], rss[-1])

        outcome = sim.run(max_sim_time=parts * 3.0 + 60.0, on_cycle=sample)
        report = finish_run(started, outcome).report
    early = statistics.median(cpu[2:6])
    late = statistics.median(cpu[-4:])
    return {"cpu_s": cpu, "sim_s": sim_s, "rss_mb": rss, "early_cpu_s": early, "late_cpu_s": late,
            "growth": late / early - 1.0, "rss_growth": statistics.median(rss[-4:]) / statistics.median(rss[2:6]) - 1.0,
            "bin": report.regions.get("bin"), "created": report.counts["created"], "errors": report.errors}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--parts", type=int, default=1000)
    parser.add_argument("--pool", type=int, default=120, help="bodies reserved for the feeder")
    args = parser.parse_args()

    def show(k: int, cpu: float, sim_s: float, rss: float) -> None:
        print(f"parts {k * BLOCK + 1:4d}-{(k + 1) * BLOCK:4d}: {cpu:6.2f} s CPU for {sim_s:5.1f} s simulated, "
              f"{rss:.0f} MB", flush=True)

    m = measure(args.parts, args.pool, show)
    print(f"per {BLOCK} parts: {m['early_cpu_s']:.2f} s CPU early, {m['late_cpu_s']:.2f} s at the end "
          f"({m['growth'] * 100:+.1f} %); memory {m['rss_growth'] * 100:+.1f} %; "
          f"{m['created']} parts, bin {m['bin']}; errors: {len(m['errors'])}")


if __name__ == "__main__":
    main()
