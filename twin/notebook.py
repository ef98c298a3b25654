"""twin from Python and Jupyter: a cell you load a program into, run in pieces, look
into, change, and plot (docs/notebooks.md).

    import twin
    cell = twin.open_cell("scenes/scara_pick.toml")
    cell.load("programs/vplus/move_parts.pg")      # a file, a GPL project folder, or V+ source text
    cell.run(until=10.0)                            # to t = 10 s of simulated time ...
    cell.tcp                                        # tool tip x, y, z (mm, robot base frame)
    cell["height2"] = 80.0                          # a V+ variable, read and set
    cell.run()                                      # ... and on to the end
    cell.plot_joints()

`run` stops at a simulated time (`until`), when a task is at a program line (`line`), when
a signal is on or off (`signal=1001`, `signal=-1001`), after an event (`event="grasp"`),
or at the end; it returns why it stopped and can be called again to continue.  The history
of every major cycle (16 ms) is kept: `history()` gives numpy arrays, `dataframe()` a pandas
DataFrame (pandas optional).  Loading a program starts it on a fresh copy of the cell;
`reset()` starts the same program afresh.
"""

from __future__ import annotations

import io
import re
import socket
import tempfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .controller.location import Location
from .errors import ProgramError
from .language.vplus.parser import normalize_name
from .language.vplus.runtime import Console, VPlusSystem
from .report import Report
from .resources import find_user_file
from .runner import StartedRun, build_report, start_program
from .simulation import DEFAULT_SCENE, Simulation

__all__ = ["open_cell", "Cell", "History"]


def open_cell(scene: str | Path = DEFAULT_SCENE, *, seed: int | None = None, rrd: str | Path | None = None,
              max_sim_time: float = 3600.0) -> "Cell":
    """The cell of a scene file (a bundled one by its relative name, e.g. 'scenes/scara_pick.toml').
    `rrd`: also record each loaded program's run to this Rerun file."""
    return Cell(scene, seed=seed, rrd=rrd, max_sim_time=max_sim_time)


@dataclass
class History:
    """One row per major cycle: time (s), joints (degrees / mm as V+ shows them), tool tip
    (x, y, z mm, base frame), gripper closed (0/1), grip force on the held part (N), and the
    digital signals that were ever on (columns by number)."""
    time: np.ndarray
    joints: np.ndarray
    tcp: np.ndarray
    gripper: np.ndarray
    grip_force: np.ndarray
    signals: dict[int, np.ndarray] = field(default_factory=dict)
    joint_names: list[str] = field(default_factory=list)


class Cell:
    """A loaded cell, a program on it, and the run so far (see the module docstring)."""

    def __init__(self, scene: str | Path, *, seed: int | None = None, rrd: str | Path | None = None,
                 max_sim_time: float = 3600.0) -> None:
        self.scene = find_user_file(scene)
        if not self.scene.exists():
            raise ProgramError(f"{scene}: no such scene file", file=str(scene))
        self.seed, self.rrd, self.max_sim_time = seed, rrd, max_sim_time
        self._program: str | Path | None = None
        self._main: str | None = None
        self._inline_dir: tempfile.TemporaryDirectory | None = None
        self._serve_port: int | None = None    # set by viewer(): each run is served there
        self.console = Console(stdin=io.StringIO(""))
        self.started: StartedRun | None = None
        self.sim = Simulation(self.scene, seed=seed)   # until a program is loaded: the cell alone
        self._rows: list[tuple] = []
        self._signal_rows: list[dict[int, bool]] = []

    # ---- program -----------------------------------------------------------------

    def load(self, program: str | Path, main: str | None = None) -> "Cell":
        """Load a program and start it on a fresh cell: a V+ file, a GPL project folder, or V+
        source text (anything with a line break or a .PROGRAM)."""
        text = str(program)
        if isinstance(program, str) and ("\n" in text or ".PROGRAM" in text.upper()):
            self._inline_dir = tempfile.TemporaryDirectory(prefix="twin-cell-")
            program = Path(self._inline_dir.name) / "cell.pg"
            program.write_text(text if text.endswith("\n") else text + "\n")
        self._program, self._main = program, main
        return self.reset()

    def close(self) -> None:
        """Finish the recording of the run so far (the .rrd file is complete after this)."""
        sim = self.started.simulation if self.started is not None else None
        if sim is not None and sim.recorder is not None:
            if sim.trace is not None:
                sim.trace.close(sim.cell.time)
            sim.recorder.close()

    def reset(self) -> "Cell":
        """Start the loaded program again on a fresh cell (or reload the bare cell)."""
        self.close()
        self.console.text.clear()
        self._rows.clear()
        self._signal_rows.clear()
        if self._program is None:
            self.started, self.sim = None, Simulation(self.scene, seed=self.seed)
        else:
            # The recording is written as the cell runs (a notebook never "finishes" a run).
            recorder = self._recorder if self.rrd is not None or self._serve_port is not None else None
            self.started = start_program(self._program, self.scene, self._main, rrd_path=self.rrd, seed=self.seed,
                                         console=self.console, recorder=recorder)
            self.sim = self.started.simulation
        self.sim.begin(self.max_sim_time)
        self._sample()
        return self

    def _recorder(self, sim: Simulation):
        from .recorder import Recorder  # here: rerun is imported only when recording

        return Recorder(sim.cell.model, self.rrd, serve_port=self._serve_port)

    def viewer(self, width: int | None = None, height: int | None = None):
        """The Rerun viewer inline in the notebook (rerun's notebook widget), showing the run
        live as it goes: display it (the last expression of a cell) and `run` in the next.
        Each run is served on a loopback port of this machine, which the widget connects to
        (the browser must run where the kernel does), and still written to `rrd` if given.
        Call it before running: at t > 0 the run so far was not recorded for it."""
        try:
            from rerun.notebook import HAS_NOTEBOOK, Viewer
        except ImportError:
            HAS_NOTEBOOK = False
        if not HAS_NOTEBOOK:
            raise RuntimeError("cell.viewer() needs Rerun's notebook widget: pip install 'twin[notebook]' "
                               "(it brings rerun-sdk[notebook]); or record with rrd=... and open the file "
                               "in the Rerun viewer")
        if self._serve_port is None:
            if self.started is not None and self.time > 0:
                raise RuntimeError(f"the run is at t = {self.time:.3f} s and was not recorded for a viewer: "
                                   "call cell.viewer() before cell.run(), or cell.reset() after it")
            self._serve_port = _free_port()
            if self.started is not None:
                self.reset()   # at t = 0: the same run, now served
        return Viewer(url=f"rerun+http://127.0.0.1:{self._serve_port}/proxy", width=width, height=height)

    @property
    def system(self):
        """The controller memory of the loaded program (VPlusSystem or GplSystem)."""
        if self.started is None:
            raise RuntimeError("no program loaded: call cell.load(...) first")
        return self.started.system

    # ---- running -----------------------------------------------------------------

    def run(self, until: float | None = None, *, line: int | None = None, signal: int | None = None,
            event: str | None = None, progress: bool = True) -> str:
        """Run on; returns why it stopped: 'time', 'line', 'signal', 'event' or 'finished'.

        `until`: a simulated time (s, absolute); `line`: a program line of task 0's program
        (seen at the end of each 16 ms cycle: a line that waits, as a motion does, is always
        seen); `signal`: n stops when n is on, -n when it is off; `event`: a cell event kind
        ('grasp', 'release', 'dropped'...) occurring after this call."""
        if self.sim.finished:
            return "finished"
        events_before = len(self.sim.cell.events)
        reason = ["finished"]

        def stop() -> bool:
            checks = (("time", until is not None and self.sim.cell.time >= until - 1e-9),
                      ("line", line is not None and self.line == line),
                      ("signal", signal is not None and self.signal(signal)),
                      ("event", event is not None and any(
                          e["kind"] == event for e in self.sim.cell.events[events_before:])))
            for name, hit in checks:
                if hit:
                    reason[0] = name
                    return True
            return False

        bar = None
        if progress:
            from .progress import Progress
            bar = Progress(self.sim, delay_s=1.0, notebook=True)

        def on_cycle() -> None:
            self._sample()
            if bar is not None:
                bar()

        try:
            self.sim.advance(until=stop, on_cycle=on_cycle)
        finally:
            if bar is not None:
                bar.close()
            if self.sim.recorder is not None:
                self.sim.recorder.send_buffered()   # the viewer shows the run up to here
        return reason[0]

    @property
    def time(self) -> float:
        """Simulated time, s."""
        return self.sim.cell.time

    @property
    def finished(self) -> bool:
        return self.sim.finished

    @property
    def line(self) -> int | None:
        """The program line task 0 is at (None when it is not running)."""
        where = self._task_statement()
        return None if where is None else where[1].line

    def _task_statement(self):
        system = self.started.system if self.started is not None else None
        if not isinstance(system, VPlusSystem):
            return None
        task = system.task(0)
        return None if task is None else task.current_statement()

    @property
    def output(self) -> str:
        """What the program has TYPEd so far."""
        return self.console.output

    def report(self) -> Report:
        """The placement report of the run so far."""
        if self.started is None:
            raise RuntimeError("no program loaded: call cell.load(...) first")
        return build_report(self.started, self.sim.outcome())

    # ---- the cell's state --------------------------------------------------------

    @property
    def tcp(self) -> np.ndarray:
        """Tool tip x, y, z (mm) in the robot base frame, as HERE reports it."""
        here = self.sim.controller.here()
        return np.array([here.x, here.y, here.z])

    @property
    def here(self) -> Location:
        return self.sim.controller.here()

    @property
    def joints(self) -> np.ndarray:
        """Joint positions as V+ shows them (degrees, mm)."""
        c = self.sim.controller
        return np.array(c.to_user_joints(c.joints()))

    @property
    def parts(self) -> list[dict]:
        """Every part presented so far: id, pose (mm, quaternion), region, dropped."""
        return self.sim.cell.parts_report()

    def signal(self, number: int) -> bool:
        """SIG(n): n is on (n > 0) or off (n < 0)."""
        return self.sim.io.sig(number)

    def set_signal(self, number: int, on: bool = True) -> None:
        self.sim.io.set(abs(number), bool(on))

    def __getitem__(self, name: str) -> Any:
        """A V+ global variable (real, string, location, array) by name."""
        system = self._vplus()
        key = normalize_name(name)
        if key not in system.globals:
            raise KeyError(f"no V+ variable {name!r} (defined: {', '.join(sorted(system.globals))})")
        return system.globals[key]

    def __setitem__(self, name: str, value: Any) -> None:
        """Set a V+ global variable; the program sees it at its next use."""
        if isinstance(value, (list, tuple)) and len(value) == 6:
            value = Location(*value)
        self._vplus().globals[normalize_name(name)] = float(value) if isinstance(value, int) else value

    @property
    def variables(self) -> dict[str, Any]:
        """Every V+ global variable and its value now (a copy)."""
        return dict(self._vplus().globals)

    def _vplus(self) -> VPlusSystem:
        system = self.system
        if not isinstance(system, VPlusSystem):
            raise TypeError("variables by name are available for V+ programs")
        return system

    @property
    def locations(self) -> dict[str, Location]:
        """The locations the program sees: taught in the cell file, then set by the program."""
        found = dict(self.sim.taught_locations())
        if isinstance(self.started and self.started.system, VPlusSystem):
            found.update({k: v for k, v in self.started.system.globals.items() if isinstance(v, Location)})
        return found

    def teach(self, name: str) -> Location:
        """Teach location `name` from the robot's pose now (as HERE name); `save` writes it."""
        here = self.sim.controller.here()
        if isinstance(self.started and self.started.system, VPlusSystem):
            self.started.system.define_location(name, here)
        self._taught = {**getattr(self, "_taught", {}), name: here}
        return here

    def save(self, path: str | Path | None = None) -> Path:
        """Write the taught locations into the cell file's [locations] table (or a copy at `path`)."""
        target = Path(path) if path is not None else self.scene
        text = write_locations(self.scene.read_text(), getattr(self, "_taught", {}))
        target.write_text(text)
        return target

    # ---- history -----------------------------------------------------------------

    def _sample(self) -> None:
        c, g = self.sim.controller, self.sim.cell.gripper
        here = c.here()
        force = g.load(g.held) if g.held is not None else 0.0
        self._rows.append((self.sim.cell.time, c.to_user_joints(c.joints()), (here.x, here.y, here.z),
                           float(g.closed), float(force)))
        self._signal_rows.append({n: v for n, v in self.sim.io.state.items()})

    def history(self) -> History:
        t, q, tcp, closed, force = (np.array(col, dtype=float) for col in zip(*self._rows))
        numbers = sorted({n for row in self._signal_rows for n in row})
        signals = {n: np.array([float(row.get(n, False)) for row in self._signal_rows]) for n in numbers}
        return History(t, q, tcp, closed, force, signals, list(self.sim.cell.robot_joint_names))

    def dataframe(self):
        """The history as a pandas DataFrame indexed by time (needs pandas)."""
        import pandas as pd

        h = self.history()
        columns = {name: h.joints[:, i] for i, name in enumerate(h.joint_names)}
        columns.update({"tcp_x": h.tcp[:, 0], "tcp_y": h.tcp[:, 1], "tcp_z": h.tcp[:, 2],
                        "gripper_closed": h.gripper, "grip_force_n": h.grip_force})
        columns.update({f"signal_{n}": v for n, v in h.signals.items()})
        return pd.DataFrame(columns, index=pd.Index(h.time, name="time_s"))

    # ---- plots (matplotlib) --------------------------------------------------------

    def plot_joints(self, ax=None):
        """Joint positions over simulated time."""
        import matplotlib.pyplot as plt

        h = self.history()
        ax = ax or plt.subplots(figsize=(8, 3.5))[1]
        for i, name in enumerate(h.joint_names):
            ax.plot(h.time, h.joints[:, i], label=name)
        ax.set(xlabel="simulated time (s)", ylabel="joint (deg / mm)", title="joints")
        ax.legend(loc="upper right", fontsize="small")
        return ax

    def plot_tcp(self, ax=None):
        """The tool tip's path seen from above (x, y in mm, base frame), coloured by time."""
        import matplotlib.pyplot as plt

        h = self.history()
        ax = ax or plt.subplots(figsize=(5, 5))[1]
        points = ax.scatter(h.tcp[:, 0], h.tcp[:, 1], c=h.time, s=2, cmap="viridis")
        ax.figure.colorbar(points, ax=ax, label="simulated time (s)")
        ax.set(xlabel="x (mm)", ylabel="y (mm)", title="tool tip path", aspect="equal")
        return ax

    def plot_cycle_times(self, ax=None):
        """Time between consecutive put-downs, per cycle."""
        import matplotlib.pyplot as plt

        cycles = self.report().cycle_times_s
        ax = ax or plt.subplots(figsize=(6, 3))[1]
        ax.bar(range(1, len(cycles) + 1), cycles)
        ax.set(xlabel="cycle", ylabel="cycle time (s)", title="cycle times")
        return ax


_LOCATION_LINE = re.compile(r"^(\s*)([A-Za-z_][\w.]*)\s*=")


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def write_locations(scene_text: str, taught: dict[str, Location]) -> str:
    """The scene text with each taught location set in its [locations] table: an existing
    `name = [...]` line is replaced (its comment kept), a new name is added at the table's end."""
    lines = scene_text.splitlines(keepends=True)
    start = next((i for i, ln in enumerate(lines) if ln.strip() == "[locations]"), None)
    if start is None:
        lines += ["\n[locations]\n"]
        start = len(lines) - 1
    end = next((i for i in range(start + 1, len(lines)) if lines[i].lstrip().startswith("[")), len(lines))
    for name, loc in taught.items():
        value = "[" + ", ".join(f"{v:.3f}" for v in (loc.x, loc.y, loc.z, loc.yaw, loc.pitch, loc.roll)) + "]"
        for i in range(start + 1, end):
            match = _LOCATION_LINE.match(lines[i])
            if match and match.group(2) == name:
                comment = lines[i][lines[i].index("#"):].rstrip("\n") if "#" in lines[i] else ""
                lines[i] = f"{match.group(1)}{name} = {value}" + (f"   {comment}" if comment else "") + "\n"
                break
        else:
            while end > start + 1 and not lines[end - 1].strip():
                end -= 1
            lines.insert(end, f"{name} = {value}\n")
            end += 1
    return "".join(lines)
