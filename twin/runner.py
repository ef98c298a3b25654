"""Run one program on one cell and produce the placement report.

This is the library entry point behind `twin run`, and the one to use from
Python or a notebook:

    from twin.runner import run_program
    result = run_program("programs/vplus/move_parts.pg")
    result.report.regions        # {'bin': 100, ...}
"""

from __future__ import annotations

import signal
import tempfile
import threading
import uuid
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

from .errors import ProgramError
from typing import TYPE_CHECKING

from .language.vplus.runtime import Console, VPlusSystem
from .report import Report
from .resources import find_user_file
from .simulation import DEFAULT_SCENE, Simulation

if TYPE_CHECKING:
    from .language.gpl.runtime import GplSystem


@dataclass
class RunResult:
    report: Report
    simulation: Simulation


def cycle_times(events: list[dict]) -> list[float]:
    """Seconds between consecutive put-downs: the robot's cycle time per part, as a cell
    designer times it (the first part, which includes the move from the start pose, only
    starts the clock)."""
    times = [e["time"] for e in events if e["kind"] == "release"]
    return [round(b - a, 4) for a, b in zip(times, times[1:])]


def _open_recorder(sim: Simulation, rrd_path: str | Path | None, spawn: bool = False, connect: str | None = None):
    """A recorder to the .rrd file and/or a viewer it spawns or connects to (None: no recording)."""
    if rrd_path is None and not spawn and connect is None:
        return None
    from .recorder import Recorder

    return Recorder(sim.cell.model, rrd_path, spawn=spawn, connect=connect)


def _sandbox(program: Path, output: str | Path | None) -> Path:
    """The folder a program's file I/O is confined to (V+ ATTACH "DISK", GPL /flash...):
    `<program>-files` beside the report or recording, else a fresh folder in the temporary
    directory.  It is created by the first file written, so a run without file I/O leaves
    nothing behind."""
    if output is None:
        return Path(tempfile.gettempdir()) / f"twin-files-{uuid.uuid4().hex[:12]}"
    return Path(output).resolve().parent / f"{program.stem}-files"


def _start_vplus(sim: Simulation, programs: list[Path], main: str | None, console: Console | None,
                 sandbox: Path) -> VPlusSystem:
    """Load every V+ file (LOAD of several modules); the first file's first program starts."""
    system = VPlusSystem(sim.controller, sim.io, sim.clock, console=console, seed=sim.cell.seed,
                         sandbox=sandbox)
    system.vision = sim.vision
    for name, location in sim.taught_locations().items():
        system.define_location(name, location)
    names = system.load_files(programs)
    if not names and main is None:
        raise ProgramError(f"{programs[0]}: no .PROGRAM in file", file=str(programs[0]))
    sim.scheduler.add(system.start(main or names[0]))
    return system


def _start_gpl(sim: Simulation, project: Path, main: str | None, console: Console | None,
               sandbox: Path) -> GplSystem:
    """A GPL project folder: Project.gpr names the files and the start procedure
    (`main` overrides it)."""
    from .language.gpl.runtime import GplSystem  # here: a V+ run need not load the GPL compiler

    system = GplSystem(sim.controller, sim.io, sim.clock, sim.scheduler, console=console, sandbox=sandbox,
                       seed=sim.cell.seed)
    system.vision = sim.vision
    system.load_project(project)
    system.start(main)
    return system


@dataclass
class StartedRun:
    """A cell with its program loaded and started, not yet simulated."""

    program: Path
    scene: Path
    simulation: Simulation
    system: VPlusSystem | GplSystem
    report_path: str | Path | None


def run_program(
    program: str | Path | list[str | Path],
    scene: str | Path | None = None,
    main: str | None = None,
    report_path: str | Path | None = None,
    rrd_path: str | Path | None = None,
    max_sim_time: float = 3600.0,
    seed: int | None = None,
    console: Console | None = None,
    progress: bool = False,
    handle_signals: bool = False,
    spawn: bool = False,
    connect: str | None = None,
) -> RunResult:
    """Load the cell, load and start the program (a V+ file or a GPL project
    folder, or several V+ files loaded together), simulate, report.

    `progress`: a progress line on standard error once the run lasts a few seconds.
    `handle_signals`: Ctrl-C (SIGINT) and SIGTERM stop the run at the next major cycle;
    the report (marked interrupted) and the recording are still written (a second Ctrl-C
    stops at once).  Only from the main thread; `twin run` sets both.
    `spawn`: also stream to a Rerun viewer started for the run; `connect`: to the viewer (or
    server) at this gRPC address, e.g. rerun+http://127.0.0.1:9876/proxy."""
    # From the start: a signal while the cell loads stops the run before its first cycle;
    # and on, while the recording and the report are written.
    with _stop_on_signals(handle_signals) as stop:
        viewer = None
        if spawn or connect is not None:
            def viewer(sim: Simulation):
                return _open_recorder(sim, rrd_path, spawn=spawn, connect=connect)
        started = start_program(program, scene, main, report_path, rrd_path, seed, console, recorder=viewer)
        sim = started.simulation
        sim.stop = stop
        sim.begin(max_sim_time)
        with _progress(sim, progress) as on_cycle:
            sim.advance(on_cycle=on_cycle)
        return finish_run(started, sim.outcome())


@contextmanager
def _stop_on_signals(enabled: bool):
    """SIGINT and SIGTERM set the yielded event (the run stops at its next cycle); a second
    one raises KeyboardInterrupt."""
    stop = threading.Event()
    if not enabled or threading.current_thread() is not threading.main_thread():
        yield stop
        return

    def handler(signum, frame):
        if stop.is_set():
            raise KeyboardInterrupt
        stop.set()

    previous = {sig: signal.signal(sig, handler) for sig in (signal.SIGINT, signal.SIGTERM)}
    try:
        yield stop
    finally:
        for sig, old in previous.items():
            signal.signal(sig, old)


@contextmanager
def _progress(sim: Simulation, enabled: bool):
    if not enabled:
        yield None
        return
    from .progress import Progress

    line = Progress(sim)
    try:
        yield line
    finally:
        line.close()


def start_program(program: str | Path | list[str | Path], scene: str | Path | None = None, main: str | None = None,
                  report_path: str | Path | None = None, rrd_path: str | Path | None = None,
                  seed: int | None = None, console: Console | None = None, recorder=None) -> StartedRun:
    """Load the cell and the program and start it (`recorder`: one already made, as
    `twin serve` makes for a live viewer)."""
    # as given, else the bundled file of that name; several V+ files are loaded together
    programs = [find_user_file(p) for p in ([program] if isinstance(program, (str, Path)) else program)]
    program = programs[0]
    for path in programs:
        if not path.exists():
            raise ProgramError(f"*Nonexistent file* {path}", file=str(path))
    if program.is_dir() and len(programs) > 1:
        raise ProgramError(f"{program}: a GPL project folder is run alone", file=str(program))
    scene = find_user_file(scene) if scene is not None else DEFAULT_SCENE
    if not scene.exists():
        raise ProgramError(f"{scene}: no such scene file", file=str(scene))

    sim = Simulation(scene, seed=seed)
    sim.recorder = recorder(sim) if recorder is not None else _open_recorder(sim, rrd_path)
    if sim.vision is not None:
        sim.vision.recorder = sim.recorder
    sandbox = _sandbox(program, report_path or rrd_path)
    if program.is_dir():
        system = _start_gpl(sim, program, main, console, sandbox)
    else:
        system = _start_vplus(sim, programs, main, console, sandbox)

    if sim.recorder is not None:
        from .program_trace import ProgramTrace

        sim.recorder.log_text(0.0, f"twin run {program} on {scene}")
        sim.recorder.log_cell(sim.cell)
        sim.trace = ProgramTrace(sim.recorder, system)
    return StartedRun(program, scene, sim, system, report_path)


def build_report(started: StartedRun, outcome) -> Report:
    """The placement report of a run, so far or at its end."""
    sim, system, program, scene = started.simulation, started.system, started.program, started.scene
    events = [{"time": e.get("t"), **{k: v for k, v in e.items() if k != "t"}} for e in sim.cell.events]
    parts = sim.cell.parts_report()
    return Report(
        program=str(program), scene=str(scene), seed=sim.cell.seed,
        sim_time_s=round(outcome.sim_time_s, 6), wall_time_s=round(outcome.wall_time_s, 3),
        output=system.console.output, errors=outcome.errors, parts=parts,
        regions=sim.cell.region_counts(parts), events=events, cycle_times_s=cycle_times(events),
        counts={**sim.cell.counts(parts), **(sim.vision.report_counts() if sim.vision is not None else {})},
        components=sim.cell.components_report(),
        interrupted=sim.interrupted,
    )


def finish_run(started: StartedRun, outcome) -> RunResult:
    """Close the recording, build the report (and write it when asked)."""
    sim, system, report_path = started.simulation, started.system, started.report_path
    if isinstance(system, VPlusSystem):
        system.devices.close_network()  # a run stopped early still frees its ports
    if sim.vision is not None:
        sim.vision.close()  # its port and renderers
    if sim.recorder is not None:
        if sim.trace is not None:
            sim.trace.close(sim.cell.time)
        sim.recorder.close()

    report = build_report(started, outcome)
    if report_path is not None:
        report.write(report_path)
    return RunResult(report, sim)
