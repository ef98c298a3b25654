"""twin.recorder: a MuJoCo run streamed to an .rrd file, read back and compared."""

from __future__ import annotations

import os
import subprocess
import sys
import time
from pathlib import Path

import mujoco
import numpy as np
import pyarrow as pa
import pytest
from rerun.chunk import RrdReader

from twin.recorder import Recorder, geom_mesh

ROOT = Path(__file__).resolve().parents[1]
ROBOT = ROOT / "models" / "robots" / "cobra_s600.xml"
RERUN_CLI = Path(sys.executable).parent / "rerun"


def cell() -> mujoco.MjModel:
    """The Cobra s600, a floor, and a box that falls freely (2 ms step)."""
    spec = mujoco.MjSpec.from_file(str(ROBOT))
    # The stiff servos need the implicit integrator the cells use (explicit Euler diverges).
    spec.option.integrator = mujoco.mjtIntegrator.mjINT_IMPLICITFAST
    world = spec.worldbody
    world.add_geom(name="floor", type=mujoco.mjtGeom.mjGEOM_PLANE, size=[0, 0, 0.1], rgba=[0.3, 0.3, 0.3, 1])
    box = world.add_body(name="box", pos=[-0.5, -0.5, 0.8], quat=[0.9659258, 0, 0, 0.2588190])
    box.add_freejoint()
    box.add_geom(name="box_geom", type=mujoco.mjtGeom.mjGEOM_BOX, size=[0.02, 0.03, 0.015],
                 rgba=[0.9, 0.2, 0.1, 1], mass=0.2)
    return spec.compile()


def read_rrd(path: Path) -> dict[str, list]:
    """entity path -> list of (is_static, {column: values}) per chunk; times as int nanoseconds."""
    out: dict[str, list] = {}
    for chunk in RrdReader(path).stream():
        rb = chunk.to_record_batch()
        cols = {}
        for name in rb.schema.names:
            if name == "rerun.controls.RowId":
                continue
            col = rb.column(name)
            if pa.types.is_temporal(col.type):
                col = col.cast(pa.int64())
            cols[name] = col.to_pylist()
        out.setdefault(chunk.entity_path, []).append((chunk.is_static, cols))
    return out


def timed(entity: list) -> dict[str, list]:
    """Concatenate the time-indexed chunks of one entity, ordered by sim_time."""
    rows: dict[str, list] = {}
    for static, cols in entity:
        if not static:
            for k, v in cols.items():
                rows.setdefault(k, []).extend(v)
    order = np.argsort(rows["sim_time"], kind="stable")
    return {k: [v[i] for i in order] for k, v in rows.items()}


def simulate(rec: Recorder, model, seconds: float = 2.0):
    data = mujoco.MjData(model)
    data.ctrl[:4] = [0.6, -0.8, 0.1, 1.5]   # the arm moves while the box falls
    costs = []
    while data.time < seconds - 1e-9:
        mujoco.mj_step(model, data)
        if rec.wants_frame(data.time):
            t0 = time.perf_counter()
            rec.sample(data.time, data)
            costs.append(time.perf_counter() - t0)
    return data, np.array(costs)


def test_recording_round_trip(tmp_path):
    model = cell()
    path = tmp_path / "out" / "run.rrd"
    rec = Recorder(model, path, app_id="twin-test", fps=30)
    data, costs = simulate(rec, model)
    rec.log_text(1.5, "All done. 1 parts processed")
    rec.log_text(1.6, "*Undefined value* (-413)", level="ERROR")
    for i in range(100):
        rec.log_scalar("signals/belt_speed", i * 0.02, 0.1 * i)
    t0 = time.perf_counter()
    rec.close()
    close_s = time.perf_counter() - t0
    rec.close()   # a second close is harmless

    size = path.stat().st_size
    print(f"\nrecorder: {len(costs)} frames, sample() median {np.median(costs) * 1e6:.1f} us, "
          f"mean {costs.mean() * 1e6:.1f} us, max {costs.max() * 1e6:.1f} us; close {close_s * 1e3:.1f} ms; "
          f"file {size / 1024:.1f} KiB")
    # 2 s at 30 fps, first frame at the first step: 61 frames.
    assert rec.frames == len(costs) == 61
    # Cheap: a Python rr.log per body per frame would cost ~1 ms here.
    assert np.median(costs) < 100e-6

    rrd = read_rrd(path)
    box = model.body("box").id
    # Moving bodies: one time-indexed row per frame, on the sim_time timeline.
    got = timed(rrd["/world/box"])
    times = np.array(got["sim_time"]) * 1e-9
    assert len(times) == 61
    assert times[-1] == pytest.approx(data.time, abs=1e-9)
    assert np.all(np.abs(np.diff(times) - 1 / 30) <= 0.002 + 1e-9)
    last_pos = np.array(got["Transform3D:translation"][-1]).reshape(3)
    np.testing.assert_allclose(last_pos, data.xpos[box], atol=1e-6)
    last_q = np.array(got["Transform3D:quaternion"][-1]).reshape(4)    # xyzw
    want = data.xquat[box][[1, 2, 3, 0]]
    assert min(np.abs(last_q - want).max(), np.abs(last_q + want).max()) < 1e-6
    assert data.xpos[box][2] < 0.05   # it did fall onto the floor
    # The arm's links move too; their poses are logged per frame.
    link2 = timed(rrd["/world/link2"])
    np.testing.assert_allclose(np.array(link2["Transform3D:translation"][-1]).reshape(3),
                               data.xpos[model.body("link2").id], atol=1e-6)

    # A body that cannot move is logged once, static, at its pose.
    base = rrd["/world/cobra_base"]
    assert [static for static, _ in base] == [True]
    # Geometry: one static mesh per geom, under its body, with its local pose and colour.
    geom = rrd["/world/box/box_geom"]
    assert all(static for static, _ in geom)
    cols = {k: v for _, c in geom for k, v in c.items()}
    verts = np.array(cols["Mesh3D:vertex_positions"][0])
    np.testing.assert_allclose(verts.min(axis=0), [-0.02, -0.03, -0.015], atol=1e-6)
    np.testing.assert_allclose(verts.max(axis=0), [0.02, 0.03, 0.015], atol=1e-6)
    assert "/world/floor" in rrd and "/world/link2/link2_head" in rrd
    head_pose = {k: v for _, c in rrd["/world/link2/link2_head"] for k, v in c.items()}
    np.testing.assert_allclose(np.array(head_pose["Transform3D:translation"]).reshape(3), [0.275, 0, 0.02], atol=1e-7)

    # Joint positions as scalars, in controller units (degrees, mm).
    for name in ("j1", "j2", "j3", "j4"):
        q = timed(rrd[f"/robot/joints/{name}"])
        assert len(q["sim_time"]) == 61
        jnt = model.joint(name)
        scale = 1000.0 if jnt.type[0] == mujoco.mjtJoint.mjJNT_SLIDE else 180 / np.pi
        assert np.ravel(q["Scalars:scalars"][-1])[0] == pytest.approx(data.qpos[jnt.qposadr[0]] * scale, abs=1e-9)
    # The freejoint of the box is not a scalar.
    assert not any(p.startswith("/robot/joints/joint") for p in rrd)

    sig = timed(rrd["/signals/belt_speed"])
    assert np.ravel(sig["Scalars:scalars"]).tolist() == pytest.approx([0.1 * i for i in range(100)])
    log = timed(rrd["/program/log"])
    assert log["TextLog:text"] == [["All done. 1 parts processed"], ["*Undefined value* (-413)"]]
    assert log["TextLog:level"] == [["INFO"], ["ERROR"]]


def test_chunks_bound_memory(tmp_path):
    model = cell()
    path = tmp_path / "chunked.rrd"
    rec = Recorder(model, path, fps=30, chunk_frames=16)
    assert rec._pos.shape[0] == 16   # buffers never grow
    data, _ = simulate(rec, model)
    rec.close()
    rrd = read_rrd(path)
    chunks = [c for static, c in rrd["/world/box"] if not static]
    assert len(chunks) == 4   # 16 + 16 + 16 + 13 frames
    got = timed(rrd["/world/box"])
    assert len(got["sim_time"]) == 61
    np.testing.assert_allclose(np.array(got["Transform3D:translation"][-1]).reshape(3),
                               data.xpos[model.body("box").id], atol=1e-6)


@pytest.mark.skipif(not RERUN_CLI.exists(), reason="rerun CLI not in this environment")
def test_rerun_cli_reads_the_file(tmp_path):
    model = cell()
    path = tmp_path / "cli.rrd"
    rec = Recorder(model, path, fps=30)
    simulate(rec, model, seconds=0.5)
    rec.close()
    env = {**os.environ, "RERUN_ANALYTICS": "0"}
    verify = subprocess.run([RERUN_CLI, "rrd", "verify", path], capture_output=True, text=True, env=env)
    assert verify.returncode == 0, verify.stderr
    stats = subprocess.run([RERUN_CLI, "rrd", "stats", path], capture_output=True, text=True, env=env)
    assert stats.returncode == 0, stats.stderr
    for entity in ("/world/box", "/world/link1", "/robot/joints/j3", "/world/cobra_base/base_column"):
        assert entity in stats.stdout, stats.stdout


def test_disabled_recorder_costs_nothing(tmp_path):
    model = cell()
    rec = Recorder(model, None)
    assert not rec.enabled
    assert not rec.wants_frame(0.0)
    rec.sample(0.0, mujoco.MjData(model))
    rec.log_text(0.0, "x")
    rec.log_scalar("a", 0.0, 1.0)
    rec.close()
    assert rec.frames == 0
    assert not list(tmp_path.iterdir())


def test_wants_frame_follows_fps(tmp_path):
    model = cell()
    rec = Recorder(model, tmp_path / "fps.rrd", fps=10)
    data = mujoco.MjData(model)
    due = []
    for i in range(500):
        t = i * 0.002
        if rec.wants_frame(t):
            due.append(t)
            rec.sample(t, data)
    rec.close()
    np.testing.assert_allclose(due, np.arange(0.0, 1.0, 0.1), atol=1e-9)
    assert not rec.wants_frame(2.0)   # closed


@pytest.mark.parametrize("xml, lo, hi", [
    ('<geom type="box" size="0.1 0.2 0.3"/>', [-0.1, -0.2, -0.3], [0.1, 0.2, 0.3]),
    ('<geom type="cylinder" size="0.05 0.2"/>', [-0.05, -0.05, -0.2], [0.05, 0.05, 0.2]),
    ('<geom type="capsule" size="0.05 0.2"/>', [-0.05, -0.05, -0.25], [0.05, 0.05, 0.25]),
    ('<geom type="sphere" size="0.07"/>', [-0.07] * 3, [0.07] * 3),
    ('<geom type="ellipsoid" size="0.1 0.2 0.3"/>', [-0.1, -0.2, -0.3], [0.1, 0.2, 0.3]),
    ('<geom type="plane" size="1 0.5 0.1"/>', [-1, -0.5, 0], [1, 0.5, 0]),
    ('<geom type="plane" size="0 0 0.1"/>', [-2, -2, 0], [2, 2, 0]),
])
def test_geom_meshes_match_sizes(xml, lo, hi):
    model = mujoco.MjModel.from_xml_string(f"<mujoco><worldbody>{xml}</worldbody></mujoco>")
    mesh = geom_mesh(model, 0)
    np.testing.assert_allclose(mesh.bounds, [lo, hi], atol=2e-3)


def test_mesh_geom_uses_model_vertices():
    xml = """<mujoco><asset><mesh name="tet" vertex="0 0 0  1 0 0  0 1 0  0 0 1"/></asset>
             <worldbody><geom type="mesh" mesh="tet"/></worldbody></mujoco>"""
    model = mujoco.MjModel.from_xml_string(xml)
    mesh = geom_mesh(model, 0)
    assert len(mesh.faces) == 4
    np.testing.assert_allclose(mesh.vertices, model.mesh_vert, atol=1e-7)
    # MuJoCo recentres the mesh; the geom's pose (what the recorder logs) puts it back.
    rot = np.empty(9)
    mujoco.mju_quat2Mat(rot, model.geom_quat[0])
    placed = mesh.vertices @ rot.reshape(3, 3).T + model.geom_pos[0]
    want = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], float)
    assert np.abs(placed[:, None, :] - want[None]).max(axis=2).min(axis=1).max() < 1e-6


def test_a_run_records_signals_and_cell_events_at_their_times(tmp_path):
    """twin run with --rrd: each digital signal change is a 0/1 scalar at the time the
    program set it, and the cell's events (part presented, grasp, release...) are text
    lines at their times."""
    from twin.runner import run_program

    program = tmp_path / "sig.pg"
    program.write_text(""".PROGRAM sig()
    SIGNAL 1
    TIMER 1 = 0
    WAIT TIMER(1) >= 0.5
    SIGNAL -1, 2010
.END
""")
    path = tmp_path / "run.rrd"
    result = run_program(program, rrd_path=path)
    assert result.report.errors == []
    rrd = read_rrd(path)
    out1 = timed(rrd["/signals/1"])
    assert [v[0] for v in out1["Scalars:scalars"]] == [1.0, 0.0]
    t_on, t_off = (t * 1e-9 for t in out1["sim_time"])
    assert t_off - t_on == pytest.approx(0.5, abs=0.0161)  # the WAIT, to the 16 ms cycle
    assert [v[0] for v in timed(rrd["/signals/2010"])["Scalars:scalars"]] == [1.0]
    events = timed(rrd["/cell/events"])
    first = result.report.events[0]
    assert events["TextLog:text"][0][0].startswith(f"{first['kind']}: ")
    assert events["sim_time"][0] * 1e-9 == pytest.approx(first["time"], abs=1e-9)


def test_a_belt_window_is_drawn_where_the_program_set_it(tmp_path):
    """The recording shows a V+ WINDOW (issue 8: "the recording shows ... the window"): a
    flat box on the belt frame between the upstream and downstream limits, from the frame
    after the WINDOW instruction."""
    from twin.runner import run_program

    program = tmp_path / "win.pg"
    program.write_text(""".PROGRAM win()
    ENABLE BELT
    SET nom = TRANS(300, 0, 100, 0, 0, 0)
    DEFBELT %b = nom, 1, 8, 0.1
    WINDOW %b = TRANS(250, 0, 100, 0, 0, 0), TRANS(400, 0, 100, 0, 0, 0)
    DELAY 0.5
.END
""")
    path = tmp_path / "run.rrd"
    result = run_program(program, scene=Path(__file__).resolve().parents[1] / "scenes" / "scara_conveyor.toml",
                         rrd_path=path, max_sim_time=10.0)
    assert result.report.errors == []
    rrd = read_rrd(path)
    windows = [k for k in rrd if k.startswith("/world/belts/") and k.endswith("/window")]
    assert len(windows) == 1
    box = timed(rrd[windows[0]])
    (half,) = box["Boxes3D:half_sizes"][0]
    (centre,) = box["Boxes3D:centers"][0]
    assert half[0] == pytest.approx(0.075) and centre[0] == pytest.approx(0.025)  # -50 .. +100 mm
    assert half[1] > 0.02
    frame = timed(rrd[windows[0].rsplit("/", 1)[0]])
    assert frame["Transform3D:translation"][0][0] == pytest.approx(
        (result.simulation.cell.robot_base_pose() @ [0.3, 0.0, 0.1, 1.0])[:3].tolist(), abs=1e-6)
