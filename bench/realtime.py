"""Real-time factor of the demo: simulated seconds per wall second for the whole run
of programs/vplus/move_parts.pg on scenes/scara_pick.toml (interpreter, controller,
MuJoCo, the cell's components; no recording unless --rrd is given), against bare
MuJoCo stepping of the very same compiled model for the same simulated time, with no
Python between steps (`mujoco.mj_step(..., nstep=...)`): the ratio twin/bare says how
much of what the physics allows the twin gets.

    .venv/bin/python bench/realtime.py [--rrd out/bench.rrd] [--parts N]

It also prints the run's own physics: the wall time MuJoCo's step timer counted inside
the run (the parts in play, contacts, the weld), a second baseline closer to what the
twin could reach than the idle model's bare stepping.

Ends with the line `rtf=<headless> bare=<bare MuJoCo> ratio=<twin/bare>`.  The figures
are one run's ratios; this machine is shared and noisy, so compare runs made one after
the other on the same machine.
"""

from __future__ import annotations

import argparse
import io
import statistics
import time
from pathlib import Path

import mujoco

from twin.language.vplus.runtime import Console
from twin.runner import run_program

ROOT = Path(__file__).resolve().parent.parent
DEMO = ROOT / "programs" / "vplus" / "move_parts.pg"
SCENE = ROOT / "scenes" / "scara_pick.toml"
BARE_CHUNK = 1000  # steps per mj_step call: no Python between them


def demo_run(rrd: str | None = None):
    """One run of the demo; returns its result (report and simulation)."""
    return run_program(DEMO, scene=SCENE, rrd_path=rrd, console=Console(stdin=io.StringIO(), echo=None))


def physics_seconds(data: mujoco.MjData) -> float:
    """Wall seconds MuJoCo itself spent in `mj_step` on `data` (its own step timer, which
    costs nothing from Python): the physics of the run as it happened, parts in play."""
    return float(data.timer[mujoco.mjtTimer.mjTIMER_STEP].duration)


def bare_rtf(model: mujoco.MjModel, sim_seconds: float) -> float:
    """Simulated seconds per wall second of mj_step alone on `model` from its initial state."""
    data = mujoco.MjData(model)
    steps = round(sim_seconds / model.opt.timestep)
    start = time.perf_counter()
    for _ in range(steps // BARE_CHUNK):
        mujoco.mj_step(model, data, nstep=BARE_CHUNK)
    mujoco.mj_step(model, data, nstep=max(1, steps % BARE_CHUNK))
    return steps * model.opt.timestep / (time.perf_counter() - start)


def demo_model() -> mujoco.MjModel:
    from twin.simulation import Simulation

    return Simulation(SCENE).cell.model


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rrd", default=None, help="also write a Rerun recording")
    args = parser.parse_args()
    result = demo_run(args.rrd)
    r = result.report
    rtf = r.sim_time_s / r.wall_time_s
    print(f"demo run: {r.sim_time_s:.1f} s simulated in {r.wall_time_s:.2f} s wall "
          f"= {rtf:.1f}x real time; cycle time {statistics.median(r.cycle_times_s):.3f} s (median), "
          f"bin {r.regions.get('bin')}")
    physics = physics_seconds(result.simulation.cell.data)
    print(f"its own physics (mj_step inside the run): {physics:.2f} s = {r.sim_time_s / physics:.1f}x, "
          f"{physics / r.wall_time_s:.0%} of the run")
    bare = bare_rtf(demo_model(), r.sim_time_s)
    print(f"rtf={rtf:.1f} bare={bare:.1f} ratio={rtf / bare:.2f}")


if __name__ == "__main__":
    main()
