"""The built-in vision server: the one place where pictures are taken and analysed.

Both languages talk to it: GPL's Vision class over TCP as the GPL manual describes for
PreciseVision (port 1410, requests answered in order), V+'s AdeptSight / ACE Sight
keywords (VRUN, VWAITI, VRESULT, VLOCATION, VPARAMETER, VSTATE) directly.  docs/vision.md
has the protocol and every decision.

Time.  A process run takes its picture when it is asked for (the cell as it is at that
simulated time) and analyses it at once; its results are *ready* ``time_s`` later, and
whoever waits for them waits that long in simulated time.  Nothing depends on the wall
clock, so the same run gives the same results.

The TCP listener binds port 1410 on a loopback address of its own (127.a.b.c, from the
process id and a counter: concurrent simulations on one machine do not meet), and is
serviced by the simulation's own thread when a client has written a request: the client
side (twin/language/gpl/library/vision.py) sends a line and calls ``serve``, which reads
and answers every complete request; the reply is in the socket when the client reads it.
"""

from __future__ import annotations

import itertools
import os
import select
import socket
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..errors import SceneError
from ..physics.camera import CameraConfig, cameras_of
from .calibration import CameraModel
from .camera import Camera, Image
from .locators import Instance
from .process import Process, processes_of

PORT = 1410  # GPL manual L3169
_addresses = itertools.count()

# Error codes (negative: the run failed); twin-chosen, docs/vision.md.
NO_PROCESS = -3201  # no process by that name or index
NO_TOOL = -3202  # the process has no such tool
NOT_CALIBRATED = -3203  # the camera has no calibration file
NO_RESULT = -3204  # result index beyond the tool's count
NOT_RUN = -3205  # results asked for before any run
BAD_PROPERTY = -3206  # unknown or read-only tool property
BAD_REQUEST = -3207  # a request line the server does not understand
MESSAGES = {NO_PROCESS: "No such vision process", NO_TOOL: "No such vision tool",
            NOT_CALIBRATED: "Camera not calibrated", NO_RESULT: "No such vision result",
            NOT_RUN: "Vision process not run", BAD_PROPERTY: "No such tool property",
            BAD_REQUEST: "Invalid vision request"}

# Status of a run (GPL Vision.Status, V+ VSTATE): the manual's values.
NONE, RUNNING, FAILED, DONE = 0, 1, 2, 3


class VisionError(Exception):
    def __init__(self, code: int, detail: str = ""):
        self.code = code
        super().__init__(MESSAGES[code] + (f": {detail}" if detail else ""))


@dataclass
class Run:
    """One run of a process: its picture, each tool's instances, when they are ready."""

    id: int
    process: Process
    image: Image
    view: np.ndarray
    results: dict[str, list[Instance]]
    ready_at: float
    error: int = 0
    taken_at: float = 0.0  # simulated time of the picture
    latched: int | None = None  # the belt encoder's count at the picture (latch_encoder)

    def status(self, now: float) -> int:
        if now < self.ready_at - 1e-9:
            return RUNNING
        return FAILED if self.error else DONE

    def instances(self, tool: str) -> list[Instance]:
        try:
            return self.results[self.process.tool(tool).name]
        except KeyError:
            raise VisionError(NO_TOOL, f"{tool!r} in process {self.process.name!r}") from None


@dataclass
class VisionServer:
    """The processes of a cell, its cameras and their calibrations."""

    processes: list[Process]
    cameras: dict[str, Camera]
    calibrations: dict[str, CameraModel | None]
    time_s: float
    clock: object  # () -> simulated seconds
    data: object  # the cell's MjData: what the cameras see
    encoders: dict = field(default_factory=dict)  # the cell's belt encoders, by number
    flange: object = None  # () -> the flange pose (4x4, mm, robot frame) from the robot's kinematics
    recorder: object = None
    runs: list[Run] = field(default_factory=list)
    _told: dict[tuple[int, int], bool] = field(default_factory=dict, repr=False)
    _not_found: set[int] = field(default_factory=set, repr=False)
    _listener: socket.socket | None = field(default=None, repr=False)
    _sessions: dict = field(default_factory=dict, repr=False)

    @classmethod
    def for_cell(cls, cell, scene: dict, scene_path: Path) -> "VisionServer":
        """The server of a cell file's [vision] section (`Simulation` makes one only for a
        cell that has the section).  Each camera's calibration is read from its plan's file
        when the file exists."""
        configs: dict[str, CameraConfig] = {c.name: c for c in cameras_of(cell)}
        try:
            processes, time_s = processes_of(scene)
            for p in processes:
                if p.camera not in configs:
                    raise ValueError(f"vision process {p.name!r}: no camera {p.camera!r} "
                                     f"(cameras: {', '.join(configs) or 'none'})")
                if p.latch_encoder is not None and p.latch_encoder not in cell.encoders:
                    raise ValueError(f"vision process {p.name!r}: latch_encoder {p.latch_encoder}: the cell has no "
                                     f"belt encoder {p.latch_encoder} (encoders: "
                                     f"{', '.join(map(str, sorted(cell.encoders))) or 'none'})")
        except ValueError as err:
            raise SceneError(f"{scene_path}: {err}") from None
        calibrations = {}
        for name, config in configs.items():
            path = None if config.calibration is None else Path(scene_path).parent / config.calibration.file
            calibrations[name] = CameraModel.load(path) if path is not None and path.exists() else None
        return cls(processes=processes, cameras={n: Camera(c, cell.model) for n, c in configs.items()},
                   calibrations=calibrations, time_s=time_s, clock=lambda: cell.time, data=cell.data,
                   encoders=dict(cell.encoders), flange=lambda: _flange_mm(cell))

    # ------------------------------------------------------------------ processes
    def process(self, key) -> Process:
        """A process by name (any case) or by its 1-based index in the cell file (a V+
        sequence number)."""
        if isinstance(key, (int, float)) and not isinstance(key, bool):
            index = int(key)
            if 1 <= index <= len(self.processes):
                return self.processes[index - 1]
        else:
            for p in self.processes:
                if p.name.lower() == str(key).lower():
                    return p
        raise VisionError(NO_PROCESS, repr(key))

    def run(self, key) -> Run:
        """Take the picture now and analyse it; the results are ready after time_s.  With
        ``latch_encoder`` the picture also latches that belt encoder, at the same simulated
        instant (the camera's strobe wired to the encoder's latch input): the program reads
        the count as it reads a photo-eye's (V+ BELT(%b, 2), GPL Conveyor latch)."""
        process = self.process(key)
        camera_model = self.calibrations.get(process.camera)
        if camera_model is None:
            raise VisionError(NOT_CALIBRATED, f"camera {process.camera!r} (run `twin calibrate` on the cell file)")
        if camera_model.flange_T is not None:  # on the robot: where the flange is now
            camera_model = camera_model.at_flange(self.flange())
        now = float(self.clock())
        image = self.cameras[process.camera].shoot(self.data)
        view, results = process.run(image.rgb, camera_model)
        latched = None
        if process.latch_encoder is not None:
            encoder = self.encoders[process.latch_encoder]
            encoder.latch(now, encoder.conveyor.travel_mm())
            latched = encoder.latches[-1][1]
        run = Run(id=len(self.runs) + 1, process=process, image=image, view=view, results=results,
                  ready_at=now + self.time_s, taken_at=now, latched=latched)
        self.runs.append(run)
        if self.recorder is not None:
            from .overlay import record_run  # drawing only when recording
            record_run(self.recorder, run, camera_model)
        return run

    def told_count(self, run: Run, count: int) -> None:
        """A program was told how many instances a tool found: none is a part not found."""
        if count == 0:
            self._not_found.add(run.id)

    def told_result(self, run: Run, index: int, inst: Instance) -> None:
        """A program was given instance `index` of a run (by any of its tools)."""
        key = (run.id, index)
        self._told[key] = self._told.get(key, True) and inst.passed is not False

    def report_counts(self) -> dict[str, int]:
        """For the report's counts: instances the programs were given that passed
        (located) or failed an inspection (rejected), and runs in which they were told
        nothing was found (not_found); docs/vision.md."""
        passed = sum(self._told.values())
        return {"located": passed, "rejected": len(self._told) - passed, "not_found": len(self._not_found)}

    def last_run(self, process: Process) -> Run | None:
        for run in reversed(self.runs):
            if run.process is process:
                return run
        return None

    # ------------------------------------------------------------------ TCP
    @property
    def address(self) -> tuple[str, int]:
        """The loopback address and port the listener is bound to (bound on first use)."""
        if self._listener is None:
            self._listener = self._bind()
        return self._listener.getsockname()

    @staticmethod
    def _bind() -> socket.socket:
        pid = os.getpid()
        for _ in range(64):
            n = next(_addresses)
            host = f"127.{(pid >> 8) & 255}.{pid & 255}.{n % 253 + 1}"
            sock = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
            try:
                sock.bind((host, PORT))
            except OSError:
                sock.close()
                continue
            sock.listen(8)
            sock.setblocking(False)
            return sock
        raise OSError("no loopback address free for the vision server's port 1410")

    def serve(self, wait_s: float = 2.0) -> int:
        """Accept new connections and answer every complete request line; returns how many
        were answered.  A client calls it right after writing a request, so it waits (wall
        clock, at most wait_s) until at least one request has arrived."""
        listener, answered = self._listener, 0
        if listener is None:
            return 0
        end = time.monotonic() + wait_s
        while answered == 0 and time.monotonic() < end:
            readable, _, _ = select.select([listener, *self._sessions], [], [], 0.01)
            for sock in readable:
                if sock is listener:
                    conn, _ = listener.accept()
                    conn.setblocking(True)
                    self._sessions[conn] = {"buffer": b"", "run": None}
                    continue
                session = self._sessions[sock]
                chunk = sock.recv(65536)
                if not chunk:
                    sock.close()
                    del self._sessions[sock]
                    continue
                session["buffer"] += chunk
                while b"\n" in session["buffer"]:
                    line, session["buffer"] = session["buffer"].split(b"\n", 1)
                    reply = self.handle(session, line.decode("latin-1").rstrip("\r\n"))  # keep an empty last field (no tool)
                    sock.sendall((reply + "\n").encode("latin-1"))
                    answered += 1
        return answered

    def handle(self, session: dict, line: str) -> str:
        """One request line -> one reply line ("OK ..." or "ERR code message")."""
        words = line.split("\t")
        command = words[0].upper()
        try:
            if command == "PROCESS" and len(words) == 2:
                run = self.run(words[1])
                session["run"] = run
                return f"OK\t{run.id}\t{run.ready_at!r}"
            run = session.get("run")
            if command in ("COUNT", "RESULT") and run is None:
                raise VisionError(NOT_RUN)
            if command == "COUNT" and len(words) == 2:
                count = len(run.instances(words[1]))
                self.told_count(run, count)
                return f"OK\t{count}"
            if command == "RESULT" and len(words) == 3:
                instances = run.instances(words[1])
                index = int(words[2])
                if not 1 <= index <= len(instances):
                    raise VisionError(NO_RESULT, f"{words[1]} {index} of {len(instances)}")
                self.told_result(run, index, instances[index - 1])
                return "OK\t" + encode_instance(instances[index - 1], run.id)
            if command in ("GET", "SET") and len(words) >= 3:
                process = run.process if run is not None else self.processes[0]
                tool = process.tool(words[1]) if words[1] else None
                name = words[2]
                if tool is None:
                    return f"OK\t{self.system_property(name)}"
                if command == "SET" and len(words) == 4:
                    try:
                        tool.set_parameter(name, words[3])
                    except (KeyError, ValueError) as err:
                        raise VisionError(BAD_PROPERTY, str(err)) from None
                    return "OK"
                params = tool.parameters()
                if name not in params:
                    raise VisionError(BAD_PROPERTY, f"{tool.name}.{name}")
                return f"OK\t{params[name]}"
            raise VisionError(BAD_REQUEST, line)
        except VisionError as err:
            return f"ERR\t{err.code}\t{err}"
        except KeyError as err:
            return f"ERR\t{NO_TOOL}\t{err.args[0]}"

    def system_property(self, name: str):
        if name.lower() == "processes":
            return ",".join(p.name for p in self.processes)
        if name.lower() == "time_s":
            return self.time_s
        raise VisionError(BAD_PROPERTY, f"system property {name!r} (processes, time_s)")

    def close(self) -> None:
        for sock in list(self._sessions):
            sock.close()
        self._sessions.clear()
        if self._listener is not None:
            self._listener.close()
            self._listener = None
        for camera in self.cameras.values():
            camera.close()


def _flange_mm(cell) -> np.ndarray:
    """The flange pose in the robot frame (mm) as the controller knows it: its kinematics of
    the joint positions."""
    T = cell.kinematics.fk(cell.robot_qpos())
    T[:3, 3] *= 1000.0
    return T


# One result set on the wire: tab-separated fields.
INFO_FIELDS = ("x", "y", "angle", "score", "area", "width", "length")


def encode_instance(inst: Instance, run_id: int) -> str:
    passed = "" if inst.passed is None else str(int(inst.passed))
    actual = "" if inst.actual is None else repr(inst.actual)
    info = [repr(float(getattr(inst, f))) for f in INFO_FIELDS]
    return "\t".join([str(run_id), repr(inst.x), repr(inst.y), repr(inst.z), repr(inst.angle), passed, actual,
                      inst.model, *info])


def decode_instance(fields: list[str]) -> dict:
    run_id, x, y, z, angle, passed, actual, model, *info = fields
    return {"process_id": int(run_id), "x": float(x), "y": float(y), "z": float(z), "angle": float(angle),
            "passed": None if passed == "" else passed == "1", "actual": None if actual == "" else float(actual),
            "model": model, "info": [float(v) for v in info]}
