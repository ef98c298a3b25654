"""The recording of a run, read back with the rerun SDK: TYPE lines at their simulated
times, the program-line trace, the blueprint, the cell's annotations and entity paths, and
parked parts sent once rather than every frame."""

from __future__ import annotations

import os
import re
import signal
import socket
import subprocess
import sys
import time
import warnings
from pathlib import Path

import numpy as np
import pytest
from rerun.chunk import RrdReader

from twin.runner import run_program

from test_recorder import read_rrd, timed

ROOT = Path(__file__).resolve().parents[1]

PROGRAM = """.PROGRAM rec()
    TYPE "start"
    TIMER 1 = 0
    WAIT TIMER(1) >= 1.0
    TYPE "one ", /S
    TYPE "second"
    MOVE place
    MOVE start
    TYPE "back to start"
.END
"""


@pytest.fixture(scope="module")
def recorded(tmp_path_factory):
    folder = tmp_path_factory.mktemp("rec")
    program = folder / "rec.pg"
    program.write_text(PROGRAM)
    path = folder / "rec.rrd"
    result = run_program(program, rrd_path=path)
    assert result.report.errors == []
    return path, read_rrd(path), result


def test_type_output_line_by_line_at_its_time(recorded):
    _, rrd, result = recorded
    log = timed(rrd["/program/log"])
    texts = [t[0] for t in log["TextLog:text"]]
    times = [t * 1e-9 for t in log["sim_time"]]
    assert texts[1:] == ["start", "one second", "back to start"] and texts[0].startswith("twin run ")
    assert times[1] == pytest.approx(0.0, abs=0.017)
    assert 1.0 <= times[2] <= 1.0 + 0.033                    # after the WAIT, to the 16 ms cycle
    assert times[3] > times[2] + 0.2      # MOVE start waits for MOVE place (one motion planned ahead)


def test_the_program_line_trace(recorded):
    _, rrd, _ = recorded
    lines = timed(rrd["/program/task0/line"])
    texts = [t[0] for t in lines["TextLog:text"]]
    assert texts[0] == "rec line 4: WAIT TIMER(1) >= 1.0"    # lines that run through in a cycle are not seen
    assert texts[1] == "rec line 8: MOVE start"
    numbers = [v[0] for v in timed(rrd["/program/task0/line_number"])["Scalars:scalars"]]
    assert numbers == [4.0, 8.0]
    assert 1.0 <= lines["sim_time"][1] * 1e-9 <= 1.0 + 0.033


def test_the_blueprint_and_the_entity_paths(recorded):
    path, rrd, _ = recorded
    reader = RrdReader(path)
    (store,) = reader.blueprints()
    origins = set()
    for chunk in reader.stream(store=store):
        batch = chunk.to_record_batch()
        if "ViewBlueprint:space_origin" in batch.schema.names:
            origins |= {v[0] for v in batch.column("ViewBlueprint:space_origin").to_pylist()}
    assert origins == {"world", "robot/joints", "signals", "program"}
    assert {"/world/tcp", "/world/regions", "/world/locations/pick", "/world/locations/place",
            "/gripper/closed", "/gripper/force_n", "/robot/joints/j1", "/cell/events"} <= set(rrd)
    tcp = timed(rrd["/world/tcp"])
    assert len(tcp["sim_time"]) > 30                        # one point per frame: the tool tip's path


def test_parked_parts_are_sent_once(recorded):
    _, rrd, result = recorded
    presented = {p["id"] for p in result.report.parts}
    bodies = [re.fullmatch(r"/world/part_(\d+)(_rest)?", p) for p in rrd]
    # free bodies not presented, and rest bodies (a retired part's: none in these few seconds)
    parked = [b.group(0) for b in bodies if b and (b.group(2) or int(b.group(1)) not in presented)]
    assert len(parked) > 44  # of the pool's 24 bodies (MAX_RECYCLED_BODIES) and their 24 rest bodies
    for entity in parked:
        rows = sum(len(cols["sim_time"]) for static, cols in rrd[entity] if not static)
        assert rows == 1, entity
    moving = timed(rrd["/world/link2"])
    assert len(moving["sim_time"]) > 10 and np.ptp(np.array(moving["Transform3D:translation"])[:, 0, 0]) > 0


def test_planned_paths_beside_the_executed_one(recorded):
    """Each motion's planned tool-tip path, at the time it was planned: MOVE place once the
    WAIT is over, MOVE start while MOVE place still runs (planned ahead); each ends where the
    tool tip then comes to rest."""
    _, rrd, _ = recorded
    plans = timed(rrd["/world/plan"])
    times = [t * 1e-9 for t in plans["sim_time"]]
    strips = [np.array(s[0]) for s in plans["LineStrips3D:strips"]]
    assert [label[0] for label in plans["LineStrips3D:labels"]] == ["joint", "joint"]
    assert 1.0 <= times[0] <= 1.0 + 0.033 and times[0] < times[1]
    tcp = timed(rrd["/world/tcp"])
    tcp_times = np.array(tcp["sim_time"]) * 1e-9
    tcp_xyz = np.array([p[0] for p in tcp["Points3D:positions"]])
    for strip, planned_at in zip(strips, times):
        assert len(strip) == 32
        at_plan = tcp_xyz[np.searchsorted(tcp_times, planned_at) - 1]
        assert np.linalg.norm(strip[0] - at_plan) < 0.2              # from the (planned) start
    assert np.linalg.norm(strips[0][-1] - strips[1][0]) < 1e-6         # the second starts where the first ends
    assert np.linalg.norm(strips[1][-1] - tcp_xyz[-1]) < 1e-3          # the robot ends on the plan
    assert np.linalg.norm(strips[0][-1] - strips[0][0]) > 0.1          # a real path (place is 180 mm away)


GPL_MAIN = """Module Test
    Public Sub Blink()
        Thread.Sleep(500)
        Signal.DIO(2) = True
        Thread.Sleep(700)
    End Sub
    Public Sub Main()
        Dim t As New Thread("Blink", , "blinker")
        Controller.PowerEnabled = True
        Robot.Attached = 1
        Robot.Home
        t.Start
        Thread.Sleep(1000)
        Move.Loc(place, fast)
        Move.WaitForEOM
        t.Join(-1)
    End Sub
End Module
"""


def test_the_line_trace_of_gpl_threads(tmp_path):
    """Each GPL thread's program line (text and number), logged when it changes."""
    folder = tmp_path / "proj"
    folder.mkdir()
    (folder / "Project.gpr").write_text('ProjectBegin\nProjectName="proj"\nProjectStart="Main"\n'
                                        'ProjectSource="Main.gpl"\nProjectSource="Locations.gpo"\nProjectEnd\n')
    (folder / "Main.gpl").write_text(GPL_MAIN)
    (folder / "Locations.gpo").write_text((ROOT / "programs/gpl/pick_place/Locations.gpo").read_text())
    path = tmp_path / "gpl.rrd"
    result = run_program(folder, scene=ROOT / "scenes/scara_pick.toml", rrd_path=path, max_sim_time=20.0)
    assert result.report.errors == []
    rrd = read_rrd(path)
    blinker = timed(rrd["/program/thread_blinker/line"])
    assert [t[0] for t in blinker["TextLog:text"]] == ["Test.Blink line 3: Thread.Sleep(500)",
                                                       "Test.Blink line 5: Thread.Sleep(700)"]
    assert 0.5 <= blinker["sim_time"][1] * 1e-9 <= 0.5 + 0.033
    main = timed(rrd["/program/thread_main/line_number"])
    assert [v[0] for v in main["Scalars:scalars"]] == [13.0, 15.0]
    assert 1.0 <= main["sim_time"][1] * 1e-9 <= 1.0 + 0.033
    assert len(timed(rrd["/world/plan"])["sim_time"]) == 1


RERUN_CLI = Path(sys.executable).parent / "rerun"


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _wait_listening(port: int, server: subprocess.Popen, seconds: float = 30.0) -> None:
    deadline = time.monotonic() + seconds
    while time.monotonic() < deadline:
        assert server.poll() is None, server.stderr.read()
        with socket.socket() as s:
            if s.connect_ex(("127.0.0.1", port)) == 0:
                return
        time.sleep(0.1)
    raise AssertionError(f"no rerun server on port {port} after {seconds} s")


@pytest.mark.skipif(not RERUN_CLI.exists(), reason="rerun CLI not in this environment")
def test_twin_run_connect_streams_to_a_running_server(tmp_path):
    """`twin run --connect ADDR` streams the run to a Rerun gRPC server already listening
    (the rerun CLI, headless: it saves what it receives), with no display and no --rrd."""
    port, saved = _free_port(), tmp_path / "received.rrd"
    server = subprocess.Popen([RERUN_CLI, "--save", saved, "--bind", "127.0.0.1", "--port", str(port)],
                              stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    try:
        _wait_listening(port, server)
        program = tmp_path / "c.pg"
        program.write_text('.PROGRAM c()\n    TYPE "hello"\n    MOVE place\n.END\n')
        run = subprocess.run([sys.executable, "-m", "twin.cli", "run", program, "--quiet",
                              "--connect", f"rerun+http://127.0.0.1:{port}/proxy"],
                             capture_output=True, text=True, cwd=tmp_path, timeout=300,
                             env={**os.environ, "MUJOCO_GL": "egl", "DISPLAY": ""})
        assert run.returncode == 0, run.stderr
        assert run.stdout.splitlines()[0] == "hello"
        assert sorted(tmp_path.glob("*.rrd")) == [saved]   # twin itself wrote no file
    finally:
        server.send_signal(signal.SIGINT)   # the CLI finishes its file on Ctrl-C
        server.wait(timeout=30)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")     # a streamed file has no footer: read it whole
        rrd = read_rrd(saved)
    texts = [t[0] for t in timed(rrd["/program/log"])["TextLog:text"]]
    assert texts[1:] == ["hello"] and texts[0].startswith("twin run ")
    assert {"/world/tcp", "/world/plan", "/robot/joints/j1", "/world/link2"} <= set(rrd)
