"""The PF400's optional linear rail (scenes/pf400_rail.toml, `[robot.rail]`): GPL axis 6,
an extra axis the arm's inverse kinematics keeps still, moved by joint moves and the TCS's
MoveRail.  PyLabRobot's PreciseFlex400Backend(has_rail=True), unmodified, drives
`twin serve programs/gpl/tcs` there: the rail positions of two stations 1.4 m apart,
MoveRail now and pending, the 6-axis joint replies and moves, a pick and a place that
need the rail; the report shows the plate at the far nest."""

from __future__ import annotations

import asyncio
import json
import math
from pathlib import Path

import numpy as np
import pytest

from pylabrobot.arms.precise_flex.coords import ElbowOrientation, PreciseFlexCartesianCoords
from pylabrobot.arms.precise_flex.joints import PFAxis
from pylabrobot.arms.precise_flex.pf_400 import PreciseFlex400Backend
from pylabrobot.arms.precise_flex.precise_flex_backend import PreciseFlexError
from pylabrobot.resources import Coordinate, Rotation

from clients_helpers import Tcs, numbers, serving
from twin.controller.kinematics import KinematicsError, LinearRail, RobotKinematics
from twin.controller.trajectory import plan_straight_move
from twin.physics.geometry import vplus_to_matrix
from twin.runner import run_program

PORT = 10100
SCENE = "scenes/pf400_rail.toml"
PLATE_WIDTH = 85.48
RAIL = LinearRail(direction=(0.0, 1.0, 0.0), lower=-0.5, upper=0.5, max_velocity=0.75, max_acceleration=1.0,
                  axis_number=6)


@pytest.fixture(scope="module")
def kin() -> RobotKinematics:
    return RobotKinematics.from_mjcf("models/robots/pf400.xml", rail=RAIL)


def test_the_rail_is_an_extra_axis_that_cartesian_motion_keeps_still(kin):
    assert kin.dof == 5 and kin.arm_dof == 4 and kin.axis_numbers == (1, 2, 3, 4, 6)
    assert kin.joint_names[-1] == "rail" and not kin.revolute[-1]
    assert kin.max_velocity[-1] == 0.75 and (kin.lower[-1], kin.upper[-1]) == (-0.5, 0.5)
    q = np.array([0.2, 0.3, 1.5, -0.4, 0.0])
    moved = q.copy()
    moved[4] = -0.3
    # Cartesian poses include the rail: 300 mm along it moves the flange 300 mm along y.
    assert kin.fk(moved)[:3, 3] - kin.fk(q)[:3, 3] == pytest.approx([0.0, -0.3, 0.0], abs=1e-12)
    assert kin.fk_positions(np.array([q, moved])) == pytest.approx(np.array([kin.fk(q), kin.fk(moved)])[:, :3, 3])
    # The arm alone reaches a pose: the rail stays where the seed has it.
    T = vplus_to_matrix([350, -700, 0, 0, 90, 180])
    T[:3, 3] /= 1000
    with pytest.raises(KinematicsError) as err:
        kin.ik(T, q)  # 761 mm from the arm with the rail at 0
    assert err.value.code == -610
    seed = q.copy()
    seed[4] = -0.4
    solved = kin.ik(T, seed, righty=True)
    assert solved[4] == -0.4 and kin.fk(solved) == pytest.approx(T, abs=1e-9)
    assert not kin.jacobian(q)[:, 4].any()  # Cartesian velocities never move the rail
    # A straight line keeps the rail still all along.
    T1 = kin.fk(solved).copy()
    T1[:3, 3] += [0.05, 0.1, 0.02]
    line = plan_straight_move(kin, solved, T1, kin.max_velocity, kin.max_acceleration, 0.5)
    Q = line.sample(line.duration / 20)[1]
    assert len(Q) > 20 and Q[:, 4] == pytest.approx(np.full(len(Q), -0.4), abs=1e-12)


def pose(x, y, z, yaw=0.0) -> PreciseFlexCartesianCoords:
    return PreciseFlexCartesianCoords(location=Coordinate(x, y, z), rotation=Rotation(x=180.0, y=90.0, z=yaw),
                                      orientation=ElbowOrientation.RIGHT)


async def session(log: dict, port: int) -> None:
    arm = PreciseFlex400Backend(host="127.0.0.1", port=port, has_rail=True, timeout=20)
    await arm.setup()
    log["axes"] = [await arm.send_command(f"pd {data_id} 1") for data_id in (2000, 2003, 16077)]
    log["start"] = await arm.get_joint_position()
    # Two stations at the bench's ends, with their rail positions.
    await arm.set_location_xyz(1, pose(350.0, -700.0, -12.8))
    await arm.set_location_xyz(2, pose(350.0, 700.0, -11.8))
    for station in (1, 2):
        await arm.set_station_type(station, access_type=1, location_type=0, z_clearance=60.0, z_above=0.0,
                                   z_grasp_offset=10.0)
    await arm.set_rail_position(1, -400.0)
    await arm.set_rail_position(2, 400.0)
    log["rail_1"] = await arm.get_rail_position(1)
    await arm.set_grasp_data(PLATE_WIDTH, 50.0, 10.0)
    try:  # the far station with the rail in the middle: out of the arm's reach
        await arm.pick_plate_station(1)
    except PreciseFlexError as err:
        log["too_far"] = err.replycode
    await arm.move_rail(station_id=1, mode=1)  # now, to station 1's rail position
    log["at_rail_1"] = await arm.get_joint_position()
    log["held"] = await arm.pick_plate_station(1)
    await arm.move_rail(station_id=2, mode=2)  # pending: before the next place
    log["before_place"] = await arm.get_joint_position()
    await arm.place_plate_station(2)
    log["placed"] = await arm.get_joint_position()
    log["placed_pose"] = await arm.get_cartesian_position()
    await arm.move_rail(mode=1, rail_destination=150.0)  # "MoveRail  1 150": no station
    log["rail_150"] = (await arm.get_joint_position())[PFAxis.RAIL]
    await arm.move_to({PFAxis.RAIL: -250.0})  # moveJ with the 6th value
    log["rail_moved_j"] = await arm.get_joint_position()
    await arm.move_one_axis(6, 50.0, 1)
    log["rail_one_axis"] = (await arm.get_joint_position())[PFAxis.RAIL]
    await arm.stop()


def test_pylabrobot_moves_the_rail_to_pick_and_place_across_the_bench(tmp_path):
    report = tmp_path / "report.json"
    log: dict = {}
    with serving(["programs/gpl/tcs", "--scene", SCENE, "--fast", "--report", str(report)], [PORT]) as served:
        asyncio.run(asyncio.wait_for(session(log, served.port(PORT)), timeout=300))
    assert served.returncode == 0, served.stderr

    # Six axes, the mask of axes 1-4 and 6, the rail's soft limits last.
    assert log["axes"] == ["6", "47", "401.5,93,348,960,134,500"]
    assert log["start"][PFAxis.RAIL] == pytest.approx(0.0, abs=0.05)
    assert log["rail_1"] == -400.0
    assert log["too_far"] == -1033  # the arm alone does not reach it (Invalid Cartesian value)
    at = log["at_rail_1"]
    assert at[PFAxis.RAIL] == pytest.approx(-400.0, abs=0.05)
    for axis in (PFAxis.BASE, PFAxis.SHOULDER, PFAxis.ELBOW, PFAxis.WRIST):  # the arm stayed still
        assert at[axis] == pytest.approx(log["start"][axis], abs=0.05)
    assert log["held"] is True
    assert log["before_place"][PFAxis.RAIL] == pytest.approx(-400.0, abs=0.05)  # pending, not yet moved
    assert log["placed"][PFAxis.RAIL] == pytest.approx(400.0, abs=0.05)
    placed = log["placed_pose"]  # back at the approach point above station 2
    assert (placed.location.x, placed.location.y) == pytest.approx((350.0, 700.0), abs=0.1)
    assert log["rail_150"] == pytest.approx(150.0, abs=0.05)
    assert log["rail_moved_j"][PFAxis.RAIL] == pytest.approx(-250.0, abs=0.05)
    assert log["rail_moved_j"][PFAxis.BASE] == pytest.approx(log["placed"][PFAxis.BASE], abs=0.05)
    assert log["rail_one_axis"] == pytest.approx(50.0, abs=0.05)

    data = json.loads(report.read_text())
    assert data["errors"] == []
    releases = [e["where"] for e in data["events"] if e["kind"] == "release" and e["part"] == 0]
    assert releases == ["nest_b"]
    plate = data["parts"][0]
    assert plate["region"] == "nest_b" and not plate["dropped"]
    x, y, z = plate["pose"][:3]
    assert math.hypot(x - 350.0, y - 700.0) < 2.0  # mm: on the far nest, 1.4 m from where it was
    assert z == pytest.approx(770.0 + 14.35 / 2, abs=0.5)


def test_a_gpl_program_sees_the_rail_as_axis_6_and_cartesian_positions_include_it():
    result = run_program(Path(__file__).parent / "data" / "gpl" / "pf400_rail", scene=SCENE)
    assert result.report.errors == []
    assert result.report.output.splitlines() == [
        "axes 6",
        "rail -400 y -400",  # the rail alone: the flange rides along
        "rail -400 y -600",  # a Cartesian move: the arm reaches, the rail stays
        "rail 250 y 50",  # an Angles location with Angle(6): the rail moves with the arm
    ]


def test_the_commands_of_a_field_pf400_driver_on_a_rail():
    """The command sequence of a public field driver for a PF400 on a rail (the AD-SDL
    pf400 driver: it reads `sysState` 21 as ready, `pd 2800` as homed, `state` as a
    number, `wherej` as six axes) and its neutral pose, J3 folded at 177 deg and J4 at
    537 deg, which the PF400's ranges (12 .. 348, +/-960 deg) hold."""
    with serving(["programs/gpl/tcs", "--scene", SCENE, "--fast"], [PORT]) as served:
        tcs = Tcs(served.port(PORT))
        assert tcs("mode 0") == "0"
        assert tcs("sysState") == "0 7" and tcs("pd 2800") == "0 0"  # off; not homed
        assert tcs("hp 1") == "0" and tcs("sysState") == "0 20"
        assert tcs("attach 1") == "0" and tcs("sysState") == "0 21" and tcs("pd 234") == "0 21"
        assert tcs("home") == "0" and tcs("pd 2800") == "0 1"
        assert tcs("state") == "0 1"  # Robot.TrajState 1 "Idle" (the TCP Command Server 3.0's state labels)
        assert tcs("Profile 1 50 50 50 50 0.1 0.1 10 0") == "0"
        assert tcs("GripOpenPos 123") == "0" and tcs("GripClosePos 77") == "0"
        neutral = [400.0, 1.4, 177.101, 537.107, 77.0, -150.0]
        assert tcs("movej 1 " + " ".join(str(v) for v in neutral)) == "0"
        assert numbers(tcs("wherej")) == pytest.approx(neutral, abs=0.01)
        assert tcs("moveoneaxis 6 200 1") == "0" and numbers(tcs("wherej"))[5] == pytest.approx(200.0, abs=0.05)
        assert tcs("attach 0") == "0" and tcs("sysState") == "0 20"
        tcs.close()
    assert served.returncode == 0, served.stderr
