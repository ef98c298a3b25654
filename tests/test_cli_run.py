"""`twin run` as a user meets it: the summary line, the progress line, and a run stopped by
Ctrl-C (SIGINT) or SIGTERM that still leaves its report (marked interrupted) and a
readable recording."""

from __future__ import annotations

import io
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from rerun.chunk import RrdReader

from twin.cli import _summary
from twin.progress import Progress
from twin.report import Report
from twin.simulation import Simulation

from conftest import ROOT, SCARA_SCENE

DEMO = ROOT / "programs" / "vplus" / "move_parts.pg"
TWIN = Path(sys.executable).parent / "twin"


@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM])
def test_a_signal_stops_the_run_cleanly_and_keeps_report_and_recording(tmp_path, signum):
    report, rrd = tmp_path / "report.json", tmp_path / "demo.rrd"
    env = {**os.environ, "MUJOCO_GL": os.environ.get("MUJOCO_GL", "egl")}
    proc = subprocess.Popen([str(TWIN), "run", str(DEMO), "--report", str(report), "--rrd", str(rrd)],
                            cwd=tmp_path, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 60
    # The recording opens as the run starts (a temporary file beside it, renamed at the end).
    while not any(tmp_path.glob(".demo.rrd.*.tmp")) and time.monotonic() < deadline:
        time.sleep(0.1)
    time.sleep(2.0)
    proc.send_signal(signum)
    out, err = proc.communicate(timeout=60)
    assert "Traceback" not in err, err
    assert proc.returncode == 130, err
    rep = Report.load(report)
    assert rep.interrupted is True
    assert 0 < rep.sim_time_s < 150            # stopped well before the 185 s of a full run
    assert err.splitlines()[-1].startswith(f"twin: interrupted at {rep.sim_time_s:.1f} s simulated")
    entities = {chunk.entity_path for chunk in RrdReader(rrd).stream()}
    assert {"/world", "/robot/joints/j1", "/program/log"} <= entities


def test_the_summary_names_dropped_parts_and_errors():
    parts = [{"id": i, "pose": [0, 0, 0, 1, 0, 0, 0], "region": "bin" if i < 3 else None, "dropped": i >= 3}
             for i in range(5)]
    r = Report(program="p", scene="s", seed=0, sim_time_s=10.0, wall_time_s=2.0, output="", parts=parts,
               errors=[{"message": "*Collision detected* link2 with table"}], cycle_times_s=[1.5, 1.7, 1.6])
    assert _summary(r) == ("twin: 10.0 s simulated in 2.0 s (5.0x real time); 5 parts: bin 3; "
                           "2 dropped (parts 3, 4); 1 error (*Collision detected* link2 with table); "
                           "cycle time 1.600 s (median)")


def test_the_progress_line_shows_time_rate_parts_and_errors():
    sim = Simulation(SCARA_SCENE)
    sim.begin(2.0)   # no program: the cell would settle for 3 s, the limit comes first
    out = io.StringIO()
    line = Progress(sim, delay_s=0.0, interval_s=0.0, file=out)
    sim.advance(on_cycle=line)
    line.close()
    shown = out.getvalue()
    assert "t = 2.0 s simulated" in shown and "x real time, 0 parts placed, 1 error" in shown
