"""Vision figures (issue 9): rendering rate at 640 x 480, the cost of a picture and of a
vision run inside a simulation, the vision demos' real-time factors (the table pick and the
vision-guided conveyor), the demo (move_parts on scara_pick) with a camera rendering 10
frames per simulated second (issue 13: goal at least 10x), and the placement check over
seeded layouts for the V+ program and the GPL project.

    MUJOCO_GL=egl .venv/bin/python bench/vision.py [--layouts 20] [--frames 60] [--conveyor-s 60]

Rendering is MuJoCo's offscreen renderer on the CPU (Mesa llvmpipe through EGL on a machine
without a GPU).  The machine is shared and noisy: medians, and compare runs made one after
the other on the same machine.
"""

from __future__ import annotations

import argparse
import io
import statistics
import tempfile
import time
from pathlib import Path

import mujoco

from twin.language.vplus.runtime import Console
from twin.physics.camera import cameras_of
from twin.runner import build_report, run_program, start_program
from twin.simulation import Simulation
from twin.vision.camera import Camera
from twin.vision.check import check_vision_run

ROOT = Path(__file__).resolve().parent.parent
SCENE = ROOT / "scenes" / "scara_vision.toml"
PROGRAMS = {"V+": ROOT / "programs" / "vplus" / "vision_pick.pg", "GPL": ROOT / "programs" / "gpl" / "vision_pick"}
CONVEYOR_SCENE = ROOT / "scenes" / "conveyor_vision.toml"
CONVEYOR = {"V+": ROOT / "programs" / "vplus" / "conveyor_vision.pg", "GPL": ROOT / "programs" / "gpl" / "conveyor_vision"}
DEMO = ROOT / "programs" / "vplus" / "move_parts.pg"
DEMO_SCENE = ROOT / "scenes" / "scara_pick.toml"
# A camera over the demo's table (the scara_vision camera's optics), added to a copy of the
# demo's cell file: the demo itself is not changed.
DEMO_CAMERA = """
[[camera]]
name = "overview"
resolution = [640, 480]
focal_px = 600.0
pose = [250.0, 100.0, 2200.0, 90.0, 180.0, 0.0]
distortion = [-0.08, 0.02, 0.0, 0.0, 0.0]
noise = 2.0
seed = 1
"""


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


def conveyor_run(language: str = "V+", seconds: float = 60.0):
    """The vision-guided conveyor for `seconds` simulated (a picture every 100 mm of belt)."""
    return run_program(CONVEYOR[language], scene=CONVEYOR_SCENE, max_sim_time=seconds,
                       console=Console(stdin=io.StringIO(), echo=None))


def conveyor_rate(seconds: float) -> None:
    """Wall-clock and CPU-time real-time factors (the CPU time of this process, renderer
    threads included: less sensitive to a shared machine's load than the wall clock)."""
    for name in CONVEYOR:
        cpu = time.process_time()
        result = conveyor_run(name, seconds)
        cpu = time.process_time() - cpu
        r = result.report
        print(f"vision conveyor ({name}, seed 1): {r.sim_time_s:.1f} s simulated in {r.wall_time_s:.2f} s wall = "
              f"{r.sim_time_s / r.wall_time_s:.2f}x real time ({r.sim_time_s / cpu:.1f}x per CPU second), "
              f"{len(result.simulation.vision.runs)} pictures, {r.counts['placed']} bars placed, "
              f"{r.counts['missed']} missed")


def demo_with_camera(fps: float = 10.0, baseline: bool = True) -> tuple[float, float | None, int, float]:
    """The demo with a camera taking a picture (render, lens, noise) every 1/fps simulated
    seconds; returns (real-time factor, the same run without pictures or None, pictures,
    median wall seconds a picture took)."""
    with tempfile.TemporaryDirectory() as tmp:
        scene = Path(tmp) / "scara_pick_camera.toml"
        scene.write_text(DEMO_SCENE.read_text() + DEMO_CAMERA)
        rates, cpu_rates, pictures, picture_s = [], [], 0, []
        for shoot in (True, False) if baseline else (True,):
            started = start_program(DEMO, scene=scene, console=Console(stdin=io.StringIO(), echo=None))
            sim = started.simulation
            camera = Camera(cameras_of(sim.cell)[0], sim.cell.model)
            due = [0.0]

            def on_cycle():
                if shoot and sim.cell.time >= due[0]:
                    start = time.perf_counter()
                    camera.shoot(sim.cell.data)
                    picture_s.append(time.perf_counter() - start)
                    due[0] += 1.0 / fps

            cpu = time.process_time()
            outcome = sim.run(on_cycle=on_cycle)
            cpu = time.process_time() - cpu
            r = build_report(started, outcome)
            camera.close()
            rates.append(r.sim_time_s / r.wall_time_s)
            cpu_rates.append(r.sim_time_s / cpu)
            pictures = max(pictures, camera.frames)
    print(f"    (per CPU second: {' and '.join(f'{v:.1f}x' for v in cpu_rates)})")
    return rates[0], rates[1] if baseline else None, pictures, statistics.median(picture_s)


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
    parser.add_argument("--conveyor-s", type=float, default=60.0, help="simulated seconds of the vision conveyor")
    args = parser.parse_args()
    rendering(args.frames)
    demo_rate()
    conveyor_rate(args.conveyor_s)
    with_camera, without, pictures, picture_s = demo_with_camera()
    print(f"demo with a camera at 10 frames per simulated second: {with_camera:.1f}x real time "
          f"({pictures} pictures, {picture_s * 1e3:.1f} ms each; {without:.1f}x without them)")
    if args.layouts:
        layouts(args.layouts)


if __name__ == "__main__":
    main()
