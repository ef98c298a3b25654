"""The Python API for notebooks (twin.open_cell), played as a new user would from
docs/notebooks.md: load the demo cell, run to t = 10 s, read the tool tip, change a
variable, continue, plot the joints; and each way of stopping, teaching, inline source."""

from __future__ import annotations

import os
import socket
import subprocess
import sys

import matplotlib
import numpy as np
import pytest

import twin
from twin.physics.scene import load_scene

from conftest import ROOT
from test_recorder import read_rrd

matplotlib.use("Agg")


@pytest.fixture(scope="module")
def demo():
    cell = twin.open_cell("scenes/scara_pick.toml")
    cell.load("programs/vplus/move_parts.pg")
    return cell


def test_the_new_users_session(demo):
    cell = demo
    assert cell.run(until=10.0, progress=False) == "time"
    assert cell.time == pytest.approx(10.0, abs=0.016)
    x, y, z = cell.tcp
    assert 0 < np.hypot(x, y) < 600 and -50 < z < 400       # inside the Cobra's reach, base frame mm
    assert cell["height2"] == pytest.approx(50.8)
    before = cell.history()
    cell["height2"] = 120.0                 # the approach height at "place", seen at the next APPRO
    assert cell.run(until=20.0, progress=False) == "time"
    after = cell.history()
    new = after.time > 10.0
    place_side = after.tcp[:, 1] > 100     # place is on the belt at +y, pick at -y
    old_top = before.tcp[before.tcp[:, 1] > 100, 2].max()
    assert after.tcp[new & place_side, 2].max() > old_top + 50   # it now comes down from 120 mm, not 50.8
    ax = cell.plot_joints()
    assert [line.get_label() for line in ax.get_lines()] == ["j1", "j2", "j3", "j4"]
    assert len(ax.get_lines()[0].get_xdata()) == len(after.time)
    frame = cell.dataframe()
    assert list(frame.columns[:4]) == ["j1", "j2", "j3", "j4"] and frame.index[-1] == pytest.approx(cell.time)


def test_stop_at_a_line_an_event_and_a_signal_then_finish(tmp_path):
    cell = twin.open_cell("scenes/scara_pick.toml")
    cell.load(".PROGRAM three()\n  FOR i = 1 TO 3\n    APPRO pick, 25\n    MOVES pick\n    CLOSEI\n"
              "    SIGNAL 1\n    DEPARTS 25\n    APPRO place, 50\n    MOVES place\n    OPENI\n"
              "    SIGNAL -1\n    DEPARTS 50\n  END\n  TYPE \"done\", i\n.END\n")
    assert cell.run(line=4, progress=False) == "line" and cell.line == 4
    assert cell.run(event="grasp", progress=False) == "event"
    grasp = [e for e in cell.sim.cell.events if e["kind"] == "grasp"][0]
    assert cell.time == pytest.approx(grasp["t"], abs=0.02)
    assert cell.run(signal=1, progress=False) == "signal" and cell.signal(1)
    assert cell.run(signal=-1, progress=False) == "signal" and not cell.signal(1)
    assert cell.run(progress=False) == "finished" and cell.finished
    assert cell.output.startswith("done") and cell.output.endswith("4\n")   # the FOR ran 3 times
    assert cell.report().regions["bin"] == 3
    assert cell.run(progress=False) == "finished"
    cell.reset()
    assert cell.time == 0.0 and cell.output == "" and not cell.finished


def test_teach_a_location_and_save_it_to_the_cell_file(tmp_path):
    scene = tmp_path / "cell.toml"
    scene.write_text((ROOT / "scenes" / "scara_pick.toml").read_text())
    cell = twin.open_cell(scene)
    cell.load("programs/vplus/move_parts.pg")
    cell.run(event="grasp", progress=False)
    here = cell.teach("pick")          # re-teach pick where the gripper closed
    cell.teach("above")                # and a new one
    cell.save()
    saved = load_scene(scene)["locations"]
    assert saved["pick"] == pytest.approx([here.x, here.y, here.z, here.yaw, here.pitch, here.roll], abs=1e-3)
    assert saved["above"] == saved["pick"]
    assert set(saved) >= {"start", "place"}
    assert "pick" in cell.locations and cell.locations["above"].z == pytest.approx(here.z)


def test_the_inline_rerun_viewer_shows_the_run_live(tmp_path):
    """cell.viewer(): rerun's notebook widget, connected to the run served on a loopback port
    (made before running; the program restarts at t = 0), the .rrd still written beside it."""
    notebook = pytest.importorskip("rerun.notebook")
    if not notebook.HAS_NOTEBOOK:
        pytest.skip("rerun-notebook is not installed")
    cell = twin.open_cell("scenes/scara_pick.toml", rrd=tmp_path / "run.rrd")
    cell.load("programs/vplus/move_parts.pg")
    widget = cell.viewer(width=800, height=500)
    assert isinstance(widget, notebook.Viewer)
    url = widget._viewer._url                   # what the widget's front end connects to
    host, port = url.removeprefix("rerun+http://").removesuffix("/proxy").split(":")
    assert host == "127.0.0.1"
    cell.run(until=2.0, progress=False)
    with socket.socket() as s:
        assert s.connect_ex((host, int(port))) == 0      # the run is being served there
    assert cell.viewer()._viewer._url == url          # the same run, the same address
    cell.close()
    rrd = read_rrd(tmp_path / "run.rrd")
    assert {"/world/tcp", "/program/log", "/robot/joints/j1"} <= set(rrd)
    late = twin.open_cell("scenes/scara_pick.toml")
    late.load("programs/vplus/move_parts.pg")
    late.run(until=0.5, progress=False)
    with pytest.raises(RuntimeError, match=r"t = 0\.5.* before cell.run"):
        late.viewer()                              # the run so far was not recorded for it


def test_without_the_notebook_widget_viewer_says_what_to_install(tmp_path):
    """Without rerun-notebook installed (blocked here in a fresh interpreter), a clear message."""
    script = ("import sys; sys.modules['rerun_notebook'] = None\n"
              "import twin\n"
              "try:\n    twin.open_cell('scenes/scara_pick.toml').viewer()\n"
              "except RuntimeError as e:\n    print(e)\n")
    out = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, cwd=tmp_path,
                         env={**os.environ, "MUJOCO_GL": "egl"}, timeout=120)
    assert out.returncode == 0, out.stderr
    assert "pip install 'twin[notebook]'" in out.stdout and "Traceback" not in out.stderr
