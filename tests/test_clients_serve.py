"""`twin serve`: the cell keeps running for a client; ports printed; Ctrl-C writes the report."""

from __future__ import annotations

import json
import signal
import subprocess
import sys
import time

from test_clients_ros import MOTION_PORT, REPLY, SUCCESS, connect, receive_message, trajectory_point


def test_serve_runs_in_real_time_prints_ports_and_writes_the_report_at_ctrl_c(tmp_path):
    report = tmp_path / "report.json"
    process = subprocess.Popen(
        [sys.executable, "-m", "twin.cli", "serve", "programs/vplus/ros_server.pg", "--report", str(report)],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )
    try:
        ports = set()
        while len(ports) < 2:
            line = process.stderr.readline()
            assert line, "twin serve ended early"
            if line.startswith("twin serve: listening on 127.0.0.1:"):
                ports.add(int(line.rsplit(":", 1)[1]))
        assert ports == {11000, 11002}
        motion = connect(MOTION_PORT)
        started = time.monotonic()
        motion.sendall(trajectory_point(3, [0.2, 0.3, 0.01, 0.5], velocity=1.0))
        kind, comm, code, _ = receive_message(motion)
        took = time.monotonic() - started
        motion.close()
        assert (comm, code) == (REPLY, SUCCESS)
        process.send_signal(signal.SIGINT)
        _, errors = process.communicate(timeout=60)
    finally:
        if process.poll() is None:
            process.kill()
    assert process.returncode == 0, errors
    assert "twin serve: stopped" in errors
    data = json.loads(report.read_text())
    assert data["errors"] == []
    assert "client connected" in data["output"]
    # Real-time pacing: the move took its simulated time on the wall clock too
    # (the wall clock may only lag, never lead).
    assert took >= 0.2
    assert data["wall_time_s"] >= data["sim_time_s"] * 0.9
