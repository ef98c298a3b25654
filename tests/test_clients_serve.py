"""`twin serve`: the cell keeps running for a client; ports printed; Ctrl-C writes the report."""

from __future__ import annotations

import json
import time

from clients_helpers import serving
from test_clients_ros import MOTION_PORT, STATE_PORT, REPLY, SUCCESS, connect, receive_message, trajectory_point


def test_serve_runs_in_real_time_prints_ports_and_writes_the_report_at_ctrl_c(tmp_path):
    report = tmp_path / "report.json"
    with serving(["programs/vplus/ros_server.pg", "--report", str(report)], [MOTION_PORT, STATE_PORT]) as served:
        motion = connect(served.port(MOTION_PORT))
        started = time.monotonic()
        motion.sendall(trajectory_point(3, [0.2, 0.3, 0.01, 0.5], velocity=1.0))
        kind, comm, code, _ = receive_message(motion)
        took = time.monotonic() - started
        motion.close()
        assert (comm, code) == (REPLY, SUCCESS)
    assert served.returncode == 0, served.stderr
    assert "(port 11000 in the program)" in served.stderr and "(port 11002 in the program)" in served.stderr
    assert "twin serve: stopped" in served.stderr
    data = json.loads(report.read_text())
    assert data["errors"] == []
    assert "client connected" in data["output"]
    # Real-time pacing: the move took its simulated time on the wall clock too
    # (the wall clock may only lag, never lead).
    assert took >= 0.2
    assert data["wall_time_s"] >= data["sim_time_s"] * 0.9
