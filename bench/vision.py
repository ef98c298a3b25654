"""Vision figures (issue 9): rendering rate at 640 x 480, the cost of a picture and of a
vision run inside a simulation, the vision demo's real-time factor, and the placement check
over seeded layouts for the V+ program and the GPL project.

    MUJOCO_GL=egl .venv/bin/python bench/vision.py [--layouts 20] [--frames 60]

Rendering is MuJoCo's offscreen renderer on the CPU (Mesa llvmpipe through EGL on a machine
without a GPU).  The machine is shared and noisy: medians, and compare runs made one after
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
from twin.simulation import Simulation
from twin.vision.camera import Camera
from twin.vision.check import check_vision_run

ROOT = Path(__file__).resolve().parent.parent
SCENE = ROOT / "scenes" / "scara_vision.toml"
PROGRAMS = {"V+": ROOT / "programs" / "vplus" / "vision_pick.pg", "GPL": ROOT / "programs" / "gpl" / "vision_pick"}


def _median_s(fn, n: int) -> float:
    times = []
    for _ in range(n):
        t = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t)
    return statistics.median(times)


def rendering(frames: int) -> None:
    sim = Simulation(SCENE)
    sim.cell.step(200)
    config = next(iter(sim.vision.cameras.values())).config
    camera = Camera(config, sim.cell.model)
    camera.shoot(sim.cell.data)  # the renderer is made by the first picture
    renderer = camera._renderer

    def render_only():
        camera._update(renderer, sim.cell.data)
        renderer.render()

    raw = _median_s(render_only, frames)
    shot = _median_s(lambda: camera.shoot(sim.cell.data), frames)
    run = _median_s(lambda: sim.vision.run("Main"), max(5, frames // 6))
    print(f"rendering {config.width}x{config.height} ({mujoco.__version__}, MSAA {sim.cell.model.vis.quality.offsamples}x, "
          f"no shadows): {1 / raw:.0f} fps render only, {1 / shot:.0f} fps with lens and noise "
          f"({shot * 1000:.1f} ms a picture); a vision run (picture + 3 tools) {run * 1000:.0f} ms median")
    camera.close()
    sim.vision.close()


def demo_rate() -> None:
    result = run_program(PROGRAMS["V+"], scene=SCENE, console=Console(stdin=io.StringIO(), echo=None))
    r = result.report
    runs = result.simulation.vision.runs
    print(f"vision demo (V+, seed 1): {r.sim_time_s:.1f} s simulated in {r.wall_time_s:.2f} s wall = "
          f"{r.sim_time_s / r.wall_time_s:.2f}x real time, {len(runs)} pictures")


def layouts(n: int) -> None:
    for name, program in PROGRAMS.items():
        failures, worst_mm, worst_deg, plates, wrong, walls = [], 0.0, 0.0, 0, 0, []
        for seed in range(1, n + 1):
            result = run_program(program, scene=SCENE, seed=seed, console=Console(stdin=io.StringIO(), echo=None))
            out = check_vision_run(result)
            walls.append(result.report.wall_time_s)
            if result.report.errors:
                out.failures.append(str(result.report.errors[0]["message"]))
            failures += [f"seed {seed}: {f}" for f in out.failures]
            worst_mm, worst_deg = max(worst_mm, out.worst_mm), max(worst_deg, out.worst_deg)
            plates, wrong = plates + out.plates, wrong + out.wrong
        print(f"{name} vision_pick over {n} layouts of 5 parts: {plates} plates placed, worst {worst_mm:.3f} mm "
              f"and {worst_deg:.3f} deg from the cell; {wrong} wrong or upside-down parts; "
              f"{len(failures)} failures; {statistics.median(walls):.1f} s wall per run (median)")
        for f in failures:
            print("   ", f)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--layouts", type=int, default=20, help="seeded layouts per program (0: none)")
    parser.add_argument("--frames", type=int, default=60, help="pictures timed")
    args = parser.parse_args()
    rendering(args.frames)
    demo_rate()
    if args.layouts:
        layouts(args.layouts)


if __name__ == "__main__":
    main()
