"""Where the demo's run time goes: CPU seconds (``time.process_time``, so the figures
hold on a loaded machine better than wall time) of each stage of the run loop, as a
share of the whole run (`Simulation.advance`): MuJoCo's stepping, each component's
check, the scheduler (interpreters and motion planning), the per-step servo update,
the recording.

    .venv/bin/python bench/profile_shares.py [--max-sim-time S]

The stages are timed by wrapping their methods (about a microsecond per call added to
the stage it wraps); the shares are what to attack first, not exact figures.  It ends
with ``mj_step_us=<CPU per physics step inside the run>``: compare it with bare
stepping of the same model (bench/realtime.py) to see what the Python between the
steps costs MuJoCo in cache misses.
"""

from __future__ import annotations

import argparse
import collections
import io
import time
from pathlib import Path

import mujoco

from twin.controller.controller import VirtualController
from twin.controller.scheduler import Scheduler
from twin.language.vplus.runtime import Console
from twin.runner import run_program
from twin.simulation import Simulation

ROOT = Path(__file__).resolve().parent.parent
DEMO = ROOT / "programs" / "vplus" / "move_parts.pg"
SCENE = ROOT / "scenes" / "scara_pick.toml"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--max-sim-time", type=float, default=3600.0, help="stop the demo there (s)")
    args = parser.parse_args()
    cpu: collections.Counter[str] = collections.Counter()
    steps = [0]

    def timed(owner, name: str, label: str) -> None:
        inner = getattr(owner, name)

        def wrapper(*a, **k):
            start = time.process_time()
            try:
                return inner(*a, **k)
            finally:
                cpu[label] += time.process_time() - start
        setattr(owner, name, wrapper)

    bare_step = mujoco.mj_step

    def mj_step(m, d, nstep=1):
        start = time.process_time()
        bare_step(m, d, nstep)
        cpu["mj_step"] += time.process_time() - start
        steps[0] += nstep
    mujoco.mj_step = mj_step
    timed(Simulation, "advance", "run")
    timed(Scheduler, "run_cycle", "scheduler (interpreters, planning)")
    timed(VirtualController, "servo_chunk", "servo references (per chunk)")
    timed(Simulation, "_record", "recording, signals")
    checked = {type(c) for c in Simulation(SCENE).cell._checked}
    for kind in sorted(checked, key=lambda k: k.__name__):
        if "check" in vars(kind):  # its own check (an inherited one is timed once, where defined)
            timed(kind, "check", f"check: {kind.__name__}")
    report = run_program(DEMO, scene=SCENE, max_sim_time=args.max_sim_time,
                         console=Console(stdin=io.StringIO(), echo=None)).report
    mujoco.mj_step = bare_step
    run = cpu.pop("run")
    print(f"demo: {report.sim_time_s:.1f} s simulated, {run:.2f} s CPU = {report.sim_time_s / run:.1f}x "
          f"real time (CPU), bin {report.regions.get('bin')}")
    for label, seconds in cpu.most_common():
        print(f"  {label:40s} {seconds:7.2f} s {seconds / run:6.1%}")
    rest = run - sum(cpu.values())
    print(f"  {'the rest (run loop, wrappers)':40s} {rest:7.2f} s {rest / run:6.1%}")
    print(f"mj_step_us={cpu['mj_step'] / max(1, steps[0]) * 1e6:.1f}")


if __name__ == "__main__":
    main()
