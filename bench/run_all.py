"""Every performance figure of the twin in one table, from one run, each beside its goal
(issue "Fast on one core"): the demo's real-time factor headless and with the Rerun
recording and with a camera at 10 frames per simulated second, the vision conveyor's,
bare MuJoCo stepping of the same model and the ratio twin/bare, interpreter
statements per second, planning time per MOVE and MOVES, memory over a simulated hour,
start-up time.  Figures are one run's medians and ratios on a shared, noisy machine.

    .venv/bin/python bench/run_all.py [--memory-minutes 60]
"""

from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

import gpl_interpreter  # noqa: E402  (bench/ modules, run as scripts)
import interpreter  # noqa: E402
import planning  # noqa: E402
import realtime  # noqa: E402
import startup  # noqa: E402
import vision  # noqa: E402

from twin.controller import trajectory  # noqa: E402

ROWS: list[tuple[str, str, str, bool | None]] = []  # figure, measured, goal, met (None: no goal)


def row(figure: str, measured: str, goal: str = "", met: bool | None = None) -> None:
    ROWS.append((figure, measured, goal, met))


def memory_in_subprocess(minutes: float) -> dict:
    """bench/memory.py in a fresh interpreter, so the other figures' allocations do not count."""
    code = ("import json, sys; sys.path.insert(0, %r); import memory; "
            "m = memory.measure(%r); m.pop('samples_mb'); print(json.dumps(m))") % (
        str(Path(__file__).resolve().parent), minutes)
    out = subprocess.run([sys.executable, "-c", code], check=True, capture_output=True, text=True).stdout
    return json.loads(out.splitlines()[-1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--memory-minutes", type=float, default=60.0)
    args = parser.parse_args()

    # toppra is imported by the first plan (about a second, bench/realtime.py in a fresh
    # process includes it): imported here first, the headless and the recorded runs
    # compare like with like.
    trajectory._libs()
    result = realtime.demo_run()
    headless = result.report
    rtf = headless.sim_time_s / headless.wall_time_s
    physics = realtime.physics_seconds(result.simulation.cell.data)
    row("demo real-time factor, headless", f"{rtf:.1f}x", ">= 50x", rtf >= 50)
    with tempfile.TemporaryDirectory() as tmp:
        recorded = realtime.demo_run(str(Path(tmp) / "bench.rrd")).report
    rtf_rrd = recorded.sim_time_s / recorded.wall_time_s
    row("demo real-time factor, recording", f"{rtf_rrd:.1f}x ({rtf_rrd / rtf - 1:+.0%})",
        "within 20 % of headless", rtf_rrd >= 0.8 * rtf)
    camera_rtf, _, _, picture_s = vision.demo_with_camera(baseline=False)
    row("demo real-time factor, camera 10 frames/s", f"{camera_rtf:.1f}x", ">= 10x", camera_rtf >= 10)
    # The pictures alone, with nothing else to do, allow at most this (10 a simulated second).
    row("  a picture (render, lens, noise); its ceiling", f"{picture_s * 1e3:.1f} ms; {0.1 / picture_s:.1f}x")
    conveyor = vision.conveyor_run().report
    row("vision conveyor real-time factor (V+, 60 s)", f"{conveyor.sim_time_s / conveyor.wall_time_s:.1f}x")
    bare = realtime.bare_rtf(realtime.demo_model(), headless.sim_time_s)
    row("bare MuJoCo, same model", f"{bare:.1f}x")
    row("ratio twin / bare", f"{rtf / bare:.2f}", ">= 0.8", rtf / bare >= 0.8)
    row("its own physics (mj_step in the run)", f"{headless.sim_time_s / physics:.1f}x")
    # The run's physics alone (no Python at all) against bare: what twin / bare can reach.
    row("  its ceiling of twin / bare", f"{headless.sim_time_s / physics / bare:.2f}")
    row("ratio twin / its own physics", f"{physics / headless.wall_time_s:.2f}")
    row("demo cycle time (median)", f"{statistics.median(headless.cycle_times_s):.3f} s",
        "1.824 s within 1 %", abs(statistics.median(headless.cycle_times_s) / 1.824 - 1) <= 0.01)

    for name, (text, statements) in interpreter.PROGRAMS.items():
        rate = statistics.median(interpreter.run_once(text, statements, 100_000) for _ in range(3))
        row(f"V+ statements/s, {name}", f"{rate / 1e6:.2f} M")
    rate = statistics.median(gpl_interpreter.run_once("Main", 100_000, gpl_interpreter.BODY_STATEMENTS)
                             for _ in range(3))
    row("GPL statements/s, loop body", f"{rate / 1e6:.2f} M")

    plans = planning.measure(50, 0)
    for key, label, goal_ms in (("move", "MOVE", 2.0), ("moves", "MOVES", 5.0)):
        ms = [t * 1e3 for t in plans[key]]
        median = statistics.median(ms)
        row(f"planning {label} (median / p95)", f"{median:.2f} / {planning.percentile(ms, 95):.2f} ms",
            f"median < {goal_ms:g} ms", median < goal_ms)

    memory = memory_in_subprocess(args.memory_minutes)
    row(f"memory over {args.memory_minutes:g} simulated min",
        f"{memory['early_mb']:.0f} -> {memory['late_mb']:.0f} MB ({memory['growth']:+.1%})",
        "growth <= 5 %", abs(memory["growth"]) <= 0.05)

    start = startup.measure(5)
    total = start["import_s"] + start["load_s"]
    row("start-up (import + load)", f"{start['import_s']:.2f} + {start['load_s']:.2f} = {total:.2f} s",
        "< 1 s", total < 1.0)

    width = max(len(r[0]) for r in ROWS)
    mwidth = max(len(r[1]) for r in ROWS)
    print(f"{'figure':<{width}}  {'measured':<{mwidth}}  goal")
    for figure, measured, goal, met in ROWS:
        verdict = "" if met is None else ("  met" if met else "  NOT MET")
        print(f"{figure:<{width}}  {measured:<{mwidth}}  {goal}{verdict}")


if __name__ == "__main__":
    main()
