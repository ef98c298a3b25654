"""The suction gripper (twin/physics/components/gripper.py) on the suction conveyor cell with
a nest added: it holds a part only from contact with the vacuum on, carries 0.5 kg at the
robot's full acceleration, lets go when the vacuum goes off or the blow-off comes on, and
loses a part heavier than its holding force (reported as dropped)."""

from __future__ import annotations

import numpy as np
import pytest

from twin.language.vplus.runtime import Console, VPlusSystem
from twin.runner import run_program
from twin.simulation import Simulation

from conftest import ROOT

SCENE = ROOT / "scenes" / "scara_conveyor_suction.toml"
# A nest at world (300, -150), top at z 850, presenting `mass` kg blocks; the source is
# held back so that only the nest's part is in the cell. Cup face 0.5 mm above the part:
# world z 870.5 -> base 120.5 -> flange 200.5 (the cup's TCP is 80 mm below the flange).
NEST = """nest_pick = [300.0, -150.0, 200.5, 0.0, 180.0, 90.0]
far = [-150.0, 380.0, 250.0, 0.0, 180.0, 90.0]
over_table = [420.0, -250.0, 250.0, 0.0, 180.0, 90.0]

[[part]]
name = "load"
shape = "box"
size = [30.0, 30.0, 20.0]
mass = {mass}

[[feeder]]
name = "nest"
part = "load"
nest = [300.0, -150.0, 850.0]
nest_size = [28.0, 28.0]
pool = 2
delay = 0.1
"""


def _scene(tmp_path, mass: float):
    text = SCENE.read_text().replace("position = 40.0", "position = 40.0\nstart = 1e6")
    path = tmp_path / "suction.toml"
    path.write_text(text + NEST.format(mass=mass))
    return path


class LoadProbe:
    """Recorder stand-in: the force the cup carries, each major cycle."""

    def __init__(self, sim: Simulation):
        self.sim, self.loads = sim, []

    def wants_frame(self, t: float) -> bool:
        g = self.sim.cell.gripper
        if g.held is not None:
            self.loads.append(g.load(g.held))
        return False

    def log_scalar(self, *args) -> None:
        """Not needed."""

    def log_text(self, *args, **kwargs) -> None:
        """Not needed."""


def _run(path, body: str):
    sim = Simulation(path)
    probe = LoadProbe(sim)
    sim.recorder = probe
    system = VPlusSystem(sim.controller, sim.io, sim.clock, console=Console(echo=None))
    for name, loc in sim.taught_locations().items():
        system.define_location(name, loc)
    sim.controller.settings.monitor_speed = 100.0  # full speed: SPEED 100 at monitor speed 100
    text = ".PROGRAM t()\n    PARAMETER HAND.TIME = 0.1\n    SPEED 100 ALWAYS\n" \
           "    ACCEL 100, 100\n    MOVE start\n    DELAY 0.5\n    APPRO nest_pick, 30\n    MOVES nest_pick\n" \
           "    CLOSEI\n    DEPARTS 30\n" + body + ".END\n"
    sim.scheduler.add(system.start(system.load_text(text, "t.pg")[0]))
    outcome = sim.run(max_sim_time=30.0)
    assert outcome.errors == []
    return sim, probe


def test_suction_holds_half_a_kilo_at_full_acceleration_and_drops_it_when_the_vacuum_goes_off(tmp_path):
    sim, probe = _run(_scene(tmp_path, 0.5), "    MOVE far\n    MOVE over_table\n    MOVE far\n"
                                              "    MOVE over_table\n    OPENI\n    DELAY 1\n")
    cell = sim.cell
    kinds = [e["kind"] for e in cell.events]
    assert kinds.count("grasp") == 1 and "slip" not in kinds
    capacity = cell.gripper.holding_force_n
    assert capacity == pytest.approx(np.pi * 0.015 ** 2 * 70e3)
    peak = max(probe.loads)
    print(f"\nsuction: peak load {peak:.1f} N, holding force {capacity:.1f} N, margin {capacity / peak:.2f}")
    assert 0.5 * 9.81 * 1.5 < peak < capacity  # well above its weight: the moves were hard
    # OPENI over bare table: the vacuum goes off, the part falls and is dropped.
    (part,) = [p for p in cell.parts_report() if p["picked"]]
    assert part["dropped"] and part["region"] == "table" and cell.gripper_holding() is None
    assert part["pose"][2] < 800


def test_a_part_heavier_than_the_holding_force_is_lost_and_reported(tmp_path):
    # 5.2 kg weighs 51 N: more than the cup's 49.5 N before the arm even moves fast.
    sim, _ = _run(_scene(tmp_path, 5.2), "    MOVE far\n")
    cell = sim.cell
    # It falls back onto the nest; the cup, still on, grips it again and loses it again.
    slips = [e for e in cell.events if e["kind"] == "slip"]
    assert slips and all(s["force_n"] > s["capacity_n"] == pytest.approx(49.48, abs=0.01) for s in slips)
    assert cell.counts()["dropped"] == 1 and cell.gripper_holding() is None
    assert any(e["kind"] == "dropped" and e["cause"] == "slip" for e in cell.events)


def test_vacuum_needs_contact_and_the_switch_and_blow_off_follow_the_part(tmp_path):
    path = _scene(tmp_path, 0.05)
    sim = Simulation(path)
    cell = sim.cell
    io = sim.io
    cell.step(int(0.5 / cell.timestep))  # the nest presents a part
    g = cell.gripper
    q_high = cell.kinematics.ik(_matrix([300.0, -150.0, 210.5, 0.0, 180.0, 90.0]), cell.robot_qpos(), righty=True)
    _hold(cell, q_high, 1.0)
    cell.set_gripper(True)  # vacuum on 10 mm above the part: nothing to hold
    cell.step(100)
    assert g.vacuum and g.held is None and not io.sig(1002)
    q_pick = cell.kinematics.ik(_matrix([300.0, -150.0, 200.5, 0.0, 180.0, 90.0]), q_high, righty=True)
    _hold(cell, q_pick, 0.5)  # down to 0.5 mm above it: sealed
    assert g.held is not None and io.sig(1002)
    io.set(11, True)  # blow-off
    cell.step(10)
    assert g.held is None and not g.vacuum and not io.sig(1002)


def _matrix(loc):
    from twin.physics.geometry import vplus_to_matrix
    return vplus_to_matrix(loc)


def _hold(cell, q, seconds: float) -> None:
    """Drive the servos to q (smoothly, no controller) and wait there."""
    q0 = cell.robot_qpos()
    n = int(seconds / cell.timestep)
    for k in range(1, n + 1):
        s = min(1.0, 2.0 * k / n)
        cell.set_servo(q0 + (q - q0) * (3 * s * s - 2 * s ** 3), np.zeros_like(q))
        cell.step(1)


def test_the_suction_cell_runs_a_v_plus_pick_from_the_nest_into_the_tray(tmp_path):
    """OPENI over a tray cell is a placement; the report puts the part in its cell."""
    path = _scene(tmp_path, 0.05)
    path.write_text(path.read_text().replace("far = [", "cell7 = [320.0, 37.5, 152.0, 0.0, 180.0, 90.0]\nfar = ["))
    program = tmp_path / "one.pg"
    program.write_text(".PROGRAM one()\n    PARAMETER HAND.TIME = 0.1\n    MOVE start\n    DELAY 0.5\n"
                       "    APPRO nest_pick, 30\n    MOVES nest_pick\n    CLOSEI\n    DEPARTS 30\n"
                       "    APPRO cell7, 30\n    MOVES cell7\n    OPENI\n    DEPARTS 30\n.END\n")
    report = run_program(program, scene=path).report
    (part,) = [p for p in report.parts if p["picked"]]
    assert (part["region"], part["tray"], part["cell"]) == ("tray", "tray", 7)
    assert np.hypot(part["pose"][0] - 320.0, part["pose"][1] - 37.5) < 1.0
    assert report.counts["placed"] == 1 and report.counts["dropped"] == 0
