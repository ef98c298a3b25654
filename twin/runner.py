"""Run one program on one cell and produce the placement report.

This is the library entry point behind `twin run`, and the one to use from
Python or a notebook:

    from twin.runner import run_program
    result = run_program("programs/vplus/move_parts.pg")
    result.report.regions        # {'bin': 100, ...}
"""

from __future__ import annotations

import os
import signal
import tempfile
import threading
import uuid
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

from typing import TYPE_CHECKING

from .controller.sandbox import SandboxError, check_root
from .errors import InputError, ProgramError
from .language.gpl.errors import NO_START_PROCEDURE
from .language.vplus.runtime import Console, VPlusSystem
from .outputs import check_replaceable, replace_output, temporary_beside
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
    """A recorder to the .rrd file and/or a viewer it spawns or connects to (None: no
    recording).  A file alone is written to a temporary file beside `rrd_path`, renamed over
    it when the run is over (outputs.replace_output): a run that fails leaves the old file
    alone."""
    if rrd_path is None and not spawn and connect is None:
        return None
    from .recorder import Recorder

    if spawn or connect is not None:
        return Recorder(sim.cell.model, rrd_path, spawn=spawn, connect=connect)
    check_replaceable(rrd_path)
    Path(rrd_path).parent.mkdir(parents=True, exist_ok=True)
    return Recorder(sim.cell.model, temporary_beside(os.path.realpath(rrd_path)))


def _sandbox(program: Path, output: str | Path | None) -> Path:
    """The folder a program's file I/O is confined to (V+ ATTACH "DISK", GPL /flash...):
    `<program>-files` beside the report or recording, else a fresh folder in the temporary
    directory.  It is created by the first file written, so a run without file I/O leaves
    nothing behind."""
    if output is None:
        return Path(tempfile.gettempdir()) / f"twin-files-{uuid.uuid4().hex[:12]}"
    return sandbox_root(program, output)


def sandbox_root(program: str | Path, output: str | Path) -> Path:
    """`<program>-files` beside the report or recording `output` (twin.controller.sandbox
    refuses it when it is a symbolic link)."""
    return Path(output).resolve().parent / f"{Path(program).stem}-files"


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
    if main is not None and main.lower() not in (name.lower() for name in system.programs):
        raise InputError(f"--main {main}: no .PROGRAM {main} in {', '.join(map(str, programs))} "
                         f"(programs: {', '.join(names) or 'none'})")
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
    try:
        system.start(main)
    except ProgramError as err:
        if err.code != NO_START_PROCEDURE:
            raise
        what = f"--main {main}" if main is not None else f"{project / 'Project.gpr'}: ProjectStart"
        raise InputError(f"{what}: {err.message} ({err.code})") from None
    return system


@dataclass
class StartedRun:
    """A cell with its program loaded and started, not yet simulated."""

    program: Path
    scene: Path
    simulation: Simulation
    system: VPlusSystem | GplSystem
    report_path: str | Path | None
    rrd_path: str | Path | None = None  # where the recording goes when the run is over


def _load_cell(scene: Path, seed: int | None, overrides=None) -> Simulation:
    """The cell of `scene`; a scene the loader cannot use is the user's error (exit 2), with
    the loader's own words (a missing key, a wrong value, a broken model file)."""
    try:
        return Simulation(scene, seed=seed, overrides=overrides)
    except KeyError as err:
        raise ProgramError(f"{scene}: scene lacks the key {err}", file=str(scene)) from None
    except (ValueError, TypeError, IndexError, OSError) as err:
        text = str(err).removeprefix(f"{scene}: ")
        raise ProgramError(text, file=str(scene)) from None


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
    max_wall_time: float | None = None,
    no_progress_limit: float | None = None,
    spawn: bool = False,
    connect: str | None = None,
    scene_overrides: dict[str, object] | None = None,
) -> RunResult:
    """Load the cell, load and start the program (a V+ file or a GPL project
    folder, or several V+ files loaded together), simulate, report.

    `progress`: a progress line on standard error once the run lasts a few seconds.
    `handle_signals`: Ctrl-C (SIGINT) and SIGTERM stop the run at the next major cycle;
    the report (marked interrupted) and the recording are still written (a second Ctrl-C
    stops at once).  Only from the main thread; `twin run` sets both.
    `spawn`: also stream to a Rerun viewer started for the run; `connect`: to the viewer (or
    server) at this gRPC address, e.g. rerun+http://127.0.0.1:9876/proxy.
    `max_wall_time`, `no_progress_limit` (over the scene's [controller] no_progress_s; 0:
    none): the watchdog's limits (twin.controller.watchdog).
    `scene_overrides`: scene values by dotted key (`twin sweep --param`)."""
    # From the start: a signal while the cell loads stops the run before its first cycle;
    # and on, while the recording and the report are written.
    with _stop_on_signals(handle_signals) as stop:
        viewer = None
        if spawn or connect is not None:
            def viewer(sim: Simulation):
                return _open_recorder(sim, rrd_path, spawn=spawn, connect=connect)
        started = start_program(program, scene, main, report_path, rrd_path, seed, console, recorder=viewer,
                                scene_overrides=scene_overrides)
        sim = started.simulation
        sim.stop = stop
        if no_progress_limit is not None:
            sim.no_progress_s = no_progress_limit if no_progress_limit > 0 else None
        sim.begin(max_sim_time, max_wall_time)
        try:
            with _progress(sim, progress) as on_cycle:
                sim.advance(on_cycle=on_cycle)
        except BaseException:
            _discard_recording(started)
            raise
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
                  seed: int | None = None, console: Console | None = None, recorder=None,
                  scene_overrides: dict[str, object] | None = None) -> StartedRun:
    """Load the cell and the program and start it (`recorder`: one already made, as
    `twin serve` makes for a live viewer; `scene_overrides` as in `run_program`)."""
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

    sim = _load_cell(scene, seed, scene_overrides)
    sandbox = _sandbox(program, report_path or rrd_path)
    try:
        check_root(sandbox)
    except SandboxError as err:
        raise ProgramError(f"sandbox folder {err}", file=str(sandbox)) from None
    own_recording = recorder is None and rrd_path is not None
    sim.recorder = recorder(sim) if recorder is not None else _open_recorder(sim, rrd_path)
    if sim.vision is not None:
        sim.vision.recorder = sim.recorder
    started = StartedRun(program, scene, sim, None, report_path, rrd_path if own_recording else None)
    try:
        if program.is_dir():
            started.system = _start_gpl(sim, program, main, console, sandbox)
        else:
            started.system = _start_vplus(sim, programs, main, console, sandbox)
    except BaseException:
        _discard_recording(started)
        raise
    if sim.recorder is not None:
        from .program_trace import ProgramTrace

        sim.recorder.log_text(0.0, f"twin run {program} on {scene}")
        sim.recorder.log_cell(sim.cell)
        sim.trace = ProgramTrace(sim.recorder, started.system, sim)
    return started


def _discard_recording(started: StartedRun) -> None:
    """A run that fails before its end leaves no temporary recording behind."""
    recorder = started.simulation.recorder
    if started.rrd_path is not None and recorder is not None:
        recorder.close()
        recorder.path.unlink(missing_ok=True)


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
        if started.rrd_path is not None:
            replace_output(sim.recorder.path, started.rrd_path)

    report = build_report(started, outcome)
    if report_path is not None:
        report.write(report_path)
    return RunResult(report, sim)
