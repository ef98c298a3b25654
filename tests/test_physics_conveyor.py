"""Conveyors, encoders, part sources, photo-eyes, presence sensors and trays
(twin/physics/components/, docs/scene.md), on scenes/scara_conveyor.toml and variants.

Short simulated times only (a few seconds each)."""

from __future__ import annotations

import copy
import math
import tomllib

import numpy as np
import pytest

from twin.physics.cell import Cell

from conftest import ROOT

SCENE = ROOT / "scenes" / "scara_conveyor.toml"
BASE = tomllib.loads(SCENE.read_text())


def make_cell(edit=None, seed=None) -> Cell:
    scene = copy.deepcopy(BASE)
    if edit is not None:
        edit(scene)
    return Cell(scene, SCENE, seed=seed)


def run_for(cell: Cell, seconds: float) -> None:
    cell.step(max(1, round(seconds / cell.timestep)))


def one_part(scene: dict) -> None:
    """Exactly one part: the source's first, then never another."""
    scene["source"][0].update(distribution="fixed", mean_interval=1e6)


def first_part(cell: Cell) -> int:
    (inst,) = cell.parts.instances
    return inst["body"]


# ---------------------------------------------------------------- belt transport
def test_a_part_on_a_stopped_belt_stays_put():
    cell = make_cell(lambda s: (one_part(s), s["conveyor"][0].update(running=False)))
    run_for(cell, 1.0)  # the part lands and settles
    i = first_part(cell)
    p0 = cell.part_position(i)
    run_for(cell, 10.0)
    drift = np.linalg.norm(cell.part_position(i) - p0)
    assert drift < 1e-4, f"drifted {drift * 1e3:.4f} mm"
    assert cell.conveyors["infeed"].travel_mm() == 0.0 and cell.encoders[1].counts() == 0


def test_a_part_on_a_running_belt_travels_speed_times_time():
    cell = make_cell(one_part)
    run_for(cell, 1.0)
    i = first_part(cell)
    p0, t0 = cell.part_position(i), cell.time
    run_for(cell, 5.0)
    d = cell.part_position(i) - p0
    expected = 100.0 * (cell.time - t0)  # mm
    assert abs(d[0] * 1e3 - expected) < 0.01 * expected
    assert abs(d[1]) < 1e-4 and abs(d[2]) < 1e-4  # straight along the belt, no bounce


def _slip_after_start(accel: float, speed: float = 500.0) -> float:
    """Belt travel minus part travel (mm) over 0.5 s after the belt starts (run output on)."""
    def edit(s):
        one_part(s)
        s["conveyor"][0].update(run_output=12, speed=speed, accel=accel)
    cell = make_cell(edit)
    run_for(cell, 1.0)
    i = first_part(cell)
    belt = cell.conveyors["infeed"]
    assert belt.speed_mm_s == 0.0  # the output is off: stopped
    p0, b0 = cell.part_position(i), belt.travel_mm()
    cell.io.set(12, True)
    run_for(cell, 0.5)
    return (belt.travel_mm() - b0) - (cell.part_position(i) - p0)[0] * 1e3


def test_a_gentle_ramp_carries_the_part_and_a_steep_one_makes_it_slip():
    # Friction accelerates the part at most mu g = 0.8 * 9.81 = 7.8 m/s^2 (MuJoCo takes
    # the larger friction of the pair: the belt's 0.8): a ramp to 500 mm/s within that
    # carries the part along, lagging only by the soft contact's v * ~6 ms (about 3 mm);
    # a step to 500 mm/s makes it slide v^2 / 2 mu g = 16 mm more before it catches up.
    gentle = _slip_after_start(accel=2000.0)
    steep = _slip_after_start(accel=1e6)
    assert 0.0 <= gentle < 3.5
    assert steep - gentle == pytest.approx(500.0 ** 2 / (2 * 0.8 * 9810), rel=0.3)
    assert steep > 10.0


def test_run_and_reverse_outputs_drive_the_belt_and_its_encoder():
    def edit(s):
        one_part(s)
        s["conveyor"][0].update(run_output=12, reverse_output=13, accel=1e5)
    cell = make_cell(edit)
    enc, belt = cell.encoders[1], cell.conveyors["infeed"]
    run_for(cell, 0.5)
    assert enc.counts() == 0
    cell.io.set(12, True)
    run_for(cell, 1.0)
    forward = enc.counts()
    assert forward == pytest.approx(100.0 * 1.0 * 10.0, abs=15)  # 1 s at 100 mm/s, 10 counts/mm
    cell.io.set(13, True)
    run_for(cell, 1.0)
    assert belt.speed_mm_s == pytest.approx(-100.0)
    assert enc.counts() == pytest.approx(0, abs=25)  # counted back down
    cell.io.set(12, False)
    run_for(cell, 0.2)
    stopped = enc.counts()
    run_for(cell, 0.5)
    assert enc.counts() == stopped and belt.speed_mm_s == 0.0


def test_encoder_counts_are_belt_travel_times_counts_per_mm():
    cell = make_cell(lambda s: (one_part(s), s["conveyor"][0].update(encoder={"number": 1, "counts_per_mm": 4.5})))
    enc = cell.encoders[1]
    assert enc.number == 1 and enc.counts_per_mm == 4.5
    run_for(cell, 1.0)
    i = first_part(cell)
    c0, p0 = enc.counts(), cell.part_position(i)
    for _ in range(7):  # also between checks: counts follow the time exactly
        cell.step(3)
        assert enc.counts() == math.floor(100.0 * cell.time * 4.5 + 0.5)
    run_for(cell, 3.0)
    part_travel_mm = (cell.part_position(i) - p0)[0] * 1e3
    assert enc.counts() - c0 == pytest.approx(part_travel_mm * 4.5, abs=4.5 * 0.05 * 4)


def test_belt_frame_for_the_controller():
    belt = make_cell().conveyors["infeed"]
    T = belt.frame_world
    assert T.shape == (4, 4)
    assert np.allclose(T[:3, 0], [1, 0, 0]) and np.allclose(T[:3, 2], [0, 0, 1])
    assert np.allclose(T[:3, 3], [-0.1, 0.35, 0.85])


# ---------------------------------------------------------------- photo-eye and latch
def _leading_edge_x(cell: Cell, i: int) -> float:
    """Largest world x of the part's box (its corners), m."""
    m, d = cell.model, cell.data
    g = cell.parts.geom[i]
    R, c, h = d.geom_xmat[g].reshape(3, 3), d.geom_xpos[g], m.geom_size[g]
    corners = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)]) * h
    return float((c + corners @ R.T)[:, 0].max())


def test_a_photo_eye_breaks_and_latches_the_encoder_at_the_parts_leading_edge():
    cell = make_cell(lambda s: (one_part(s), s["source"][0].update(jitter_yaw=10.0)))
    enc = cell.encoders[1]
    assert enc.latch_input == 1001
    beam_x = -0.5  # the scene's photo-eye: 200 mm from the belt's upstream end at x = -700
    cell.step(1)
    i = first_part(cell)
    previous = (_leading_edge_x(cell, i), enc.counts())
    crossing = None
    while cell.time < 3.0:
        cell.step(1)
        edge = _leading_edge_x(cell, i)
        if crossing is None and edge >= beam_x:
            e0, c0 = previous  # interpolate the count to the step the edge reached the beam
            crossing = c0 + (enc.counts() - c0) * (beam_x - e0) / (edge - e0)
        previous = (edge, enc.counts())
        if crossing is not None and cell.io.sig(1001):
            break
    assert crossing is not None and cell.io.sig(1001)
    ((t_latch, latched),) = enc.latches
    assert abs(latched - crossing) <= 1.0, (latched, crossing)
    assert t_latch == pytest.approx(crossing / 1000.0, abs=0.002)  # 1000 counts/s
    run_for(cell, 0.5)  # the 30 mm part has passed the beam
    assert not cell.io.sig(1001) and len(enc.latches) == 1
    assert cell.components_report()["sensor.infeed_eye"]["breaks"] == 1


def test_a_presence_sensor_sees_a_part_in_its_box():
    def edit(s):
        one_part(s)
        s["sensor"].append({"name": "tray_full", "type": "presence", "input": 1005,
                            "lo": [200.0, -40.0, 795.0], "hi": [440.0, 160.0, 860.0]})
    cell = make_cell(edit)
    run_for(cell, 0.1)
    assert not cell.io.sig(1005)
    i = first_part(cell)
    tray = cell.trays["tray"]
    _put(cell, i, tray.cell_centres[7] + [0, 0, 0.0105])
    run_for(cell, 0.1)
    assert cell.io.sig(1005)


def _put(cell: Cell, i: int, pos) -> None:
    cell.data.qpos[cell.parts.qadr[i]:cell.parts.qadr[i] + 3] = pos
    cell.data.qvel[cell.parts.dadr[i]:cell.parts.dadr[i] + 6] = 0.0


# ---------------------------------------------------------------- sources and pool
def _spawn_times(seed: int) -> list[float]:
    cell = make_cell(seed=seed)
    run_for(cell, 20.0)
    return [e["t"] for e in cell.events if e["kind"] == "spawn"]


def test_the_source_is_random_but_seeded():
    a, b, c = _spawn_times(1), _spawn_times(1), _spawn_times(2)
    assert a == b and a != c
    gaps = np.diff(a)
    assert len(set(np.round(gaps, 3))) > 3  # random spacing
    assert gaps.min() >= 0.6 - 0.011  # min_gap 60 mm at 100 mm/s
    assert 4 <= len(a) <= 20  # about one part every 2 s


def test_a_small_pool_never_runs_out_and_missed_parts_are_counted():
    # 1 part/s, 11.6 s on the belt, about 1 s to fall and come to rest in the reject bin:
    # 14 bodies are enough for ever.
    cell = make_cell(lambda s: s["source"][0].update(pool=14, distribution="fixed", mean_interval=1.0))
    run_for(cell, 40.0)
    kinds = [e["kind"] for e in cell.events]
    assert "source_empty" not in kinds
    counts = cell.counts()
    assert counts["created"] >= 39 and cell.parts.size == 14
    # Every part that reached the belt's end (x = 500 mm, 11.6 s from the source) was missed.
    assert counts["missed"] >= counts["created"] - 13 and counts["picked"] == counts["placed"] == 0
    report = cell.parts_report()
    assert [p["id"] for p in report] == list(range(counts["created"]))
    assert all(p["region"] == "reject" for p in report if p["missed"])


# ---------------------------------------------------------------- several of each, any pose
def test_several_conveyors_sources_sensors_and_trays_at_any_pose():
    def edit(s):
        one_part(s)
        s["conveyor"].append({"name": "diagonal", "top_center": [300.0, -300.0, 820.0],
                              "size": [80.0, 400.0, 10.0], "direction": [-1.0, -1.0, 0.2],
                              "speed": 50.0, "encoder": {"number": 2, "counts_per_mm": 2.0}})
        s["source"].append({"name": "diag_parts", "conveyor": "diagonal", "distribution": "fixed",
                            "mean_interval": 1e6, "position": 50.0})
        s["sensor"].append({"name": "diag_eye", "type": "photo_eye", "conveyor": "diagonal",
                            "position": 150.0, "input": 1003, "latch_encoder": 2})
        s["tray"].append({"name": "tray2", "center": [-300.0, -300.0, 800.0], "yaw": 30.0,
                          "rows": 2, "cols": 3, "pitch": [40.0, 40.0]})
    cell = make_cell(edit)
    assert sorted(cell.encoders) == [1, 2] and set(cell.trays) == {"tray", "tray2"}
    run_for(cell, 0.5)
    diag = cell.conveyors["diagonal"]
    (body,) = [inst["body"] for inst in cell.parts.instances if inst["body"] in cell.ctx.component("source", "diag_parts").bodies]
    p0 = cell.part_position(body)
    run_for(cell, 3.5)
    moved = cell.part_position(body) - p0
    assert np.linalg.norm(moved) * 1e3 == pytest.approx(50.0 * 3.5, rel=0.02)
    assert np.allclose(moved / np.linalg.norm(moved), diag.axis, atol=0.01)  # up the incline
    assert len(cell.encoders[2].latches) == 1 and cell.encoders[2].counts() == pytest.approx(50 * cell.time * 2, abs=1)
    tray2 = cell.trays["tray2"]
    _put(cell, body, tray2.cell_centres[4] + [0, 0, 0.0105])
    run_for(cell, 1.0)
    entry = cell.parts_report()[-1]
    assert (entry["region"], entry["tray"], entry["cell"]) == ("tray2", "tray2", 4)


def test_tray_cells_and_their_centres():
    tray = make_cell().trays["tray"]
    assert len(tray.cell_centres) == 20
    assert tray.cell_centre_mm(0) == [230.0, -7.5, 800.0]  # the scene's tray_origin location
    assert tray.cell_centre_mm(1) == [275.0, -7.5, 800.0]  # next column: +x
    assert tray.cell_centre_mm(5) == [230.0, 37.5, 800.0]  # next row: +y
    assert tray.cell_of(np.array([0.275 + 0.02, -0.0075 - 0.02, 0.81])) == 1
    assert tray.cell_of(np.array([0.0, 0.0, 0.81])) is None


# ---------------------------------------------------------------- recording and reach
class ScalarProbe:
    """Recorder stand-in: which time series the run sends."""

    def __init__(self):
        self.series: dict[str, list[tuple[float, float]]] = {}

    def wants_frame(self, t: float) -> bool:
        return True

    def sample(self, t: float, data) -> None:
        """Poses are not needed here."""

    def log_scalar(self, name: str, t: float, value: float) -> None:
        self.series.setdefault(name, []).append((t, value))

    def log_text(self, *args, **kwargs) -> None:
        """Not needed."""


def test_the_recording_has_belt_speed_encoder_counts_and_sensor_states():
    from twin.simulation import Simulation

    sim = Simulation(SCENE)
    sim.recorder = probe = ScalarProbe()
    sim.run(max_sim_time=3.0)
    s = probe.series
    assert {"conveyor/infeed/speed_mm_s", "conveyor/infeed/encoder_1", "sensor/infeed_eye"} <= set(s)
    t, counts = s["conveyor/infeed/encoder_1"][-1]
    assert counts == pytest.approx(100.0 * t * 10.0, abs=1)
    assert max(v for _, v in s["sensor/infeed_eye"]) == 1.0  # the first part broke the beam
    assert ("signals/1001" in s) and s["signals/1001"][0][1] == 1.0  # and its input changed


@pytest.mark.parametrize("scene", ["scara_conveyor", "scara_conveyor_suction"])
def test_the_conveyor_cells_taught_locations_are_reachable(scene):
    from twin.physics.geometry import vplus_to_matrix

    cell = Cell.from_scene(ROOT / "scenes" / f"{scene}.toml")
    kin, q = cell.kinematics, cell.robot_qpos()
    locs = cell.locations()
    tray = cell.trays["tray"]
    for name, shift in [("belt_pick", (x, 0)) for x in (-300.0, 0.0, 300.0)] + \
                       [("tray_origin", (45.0 * c, 45.0 * r)) for r in (0, 3) for c in (0, 4)]:
        loc = list(locs[name])
        loc[0] += shift[0]
        loc[1] += shift[1]
        q = kin.ik(vplus_to_matrix(loc), q, righty=True)
        assert q is not None and 0.0 <= q[2] <= 0.21, (name, shift)
    # tray_origin is over cell 0, at the right height above the tray floor.
    cell.data.qpos[cell.robot.qadr] = kin.ik(vplus_to_matrix(locs["tray_origin"]), q, righty=True)
    import mujoco
    mujoco.mj_kinematics(cell.model, cell.data)
    tcp = cell.data.site(f"{cell.gripper.prefix}tcp").xpos
    assert np.allclose(tcp[:2], tray.cell_centres[0][:2], atol=1e-6)
    expected = 0.012 if scene == "scara_conveyor" else 0.022  # part centre / part top, 2 mm up
    assert tcp[2] - tray.cell_centres[0][2] == pytest.approx(expected, abs=1e-4)


def test_a_source_of_boxes_cylinders_and_meshes(tmp_path):
    """Three part types (an STL read with trimesh among them), drawn by weight; each rides the
    belt and latches the encoder at its leading edge."""
    import trimesh

    stl = tmp_path / "hex.stl"
    trimesh.creation.cylinder(radius=14.0, height=18.0, sections=6).export(stl)  # a hexagonal prism, mm
    scene = SCENE.read_text().replace('[[conveyor]]', f'''[[part]]
name = "can"
shape = "cylinder"
radius = 12.0
height = 25.0
mass = 0.03

[[part]]
name = "hex"
shape = "mesh"
mesh = "{stl}"
mass = 0.04

[[conveyor]]''', 1).replace('parts = ["block"]', 'parts = ["block", "can", "hex"]\nweights = [1.0, 1.0, 2.0]').replace(
        'distribution = "exponential"', 'distribution = "fixed"').replace("mean_interval = 2.0", "mean_interval = 0.8")
    path = tmp_path / "mixed.toml"
    path.write_text(scene)
    cell = Cell.from_scene(path)
    run_for(cell, 8.0)
    report = cell.parts_report()
    assert {p["type"] for p in report} == {"block", "can", "hex"}
    spawned_before_eye = [e for e in cell.events if e["kind"] == "spawn" and e["t"] < cell.time - 2.0]
    assert len(cell.encoders[1].latches) >= len(spawned_before_eye)
    on_belt = [p for p in report if p["region"] == "infeed"]
    assert on_belt and all(abs(p["pose"][1] - 350.0) < 3.0 for p in on_belt)  # riding, not tumbling off
    assert cell.counts()["dropped"] == 0



def test_a_program_may_declare_a_part_missed_but_not_one_it_picked():
    cell = make_cell(one_part)
    run_for(cell, 0.5)
    (inst,) = cell.parts.instances
    cell.mark_missed(inst["id"], "left the window")
    cell.mark_missed(inst["id"], "left the window")  # once only
    assert cell.counts()["missed"] == 1
    assert [e["cause"] for e in cell.events if e["kind"] == "missed"] == ["left the window"]
    inst["missed"], inst["picked"] = False, True
    cell.mark_missed(inst["id"], "left the window")
    assert cell.counts()["missed"] == 0
