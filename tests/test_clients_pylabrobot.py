"""PyLabRobot's PreciseFlexBackend, installed unmodified from the package index (the
`clients` test extra), drives `twin serve programs/gpl/tcs` on the PF400 plate bench
(the `test` extra installs it) as it drives a real PF400 running Brooks' TCP Command Server: set up, read joint and
Cartesian positions, move to Cartesian and joint targets, open and close the gripper,
pick the plate from the source nest and place it on the target nest; the report shows
the plate there."""

from __future__ import annotations

import asyncio
import json

import pytest

from pylabrobot.arms.precise_flex.coords import ElbowOrientation, PreciseFlexCartesianCoords
from pylabrobot.arms.precise_flex.pf_400 import PreciseFlex400Backend
from pylabrobot.arms.precise_flex.precise_flex_backend import PreciseFlexError
from pylabrobot.resources import Coordinate, Rotation

from clients_helpers import serving

PORT = 10100  # the TCS's port, moved to a free one by the test
PLATE_WIDTH = 85.48  # mm, the portrait side of an SBS plate


def pose(x, y, z, yaw=0.0) -> PreciseFlexCartesianCoords:
    """The gripper level, fingers down (pitch 90, roll 180), elbow right."""
    return PreciseFlexCartesianCoords(location=Coordinate(x, y, z), rotation=Rotation(x=180.0, y=90.0, z=yaw),
                                      orientation=ElbowOrientation.RIGHT)


async def session(log: dict, port: int) -> None:
    arm = PreciseFlex400Backend(host="127.0.0.1", port=port, timeout=20)
    await arm.setup()
    log["version"] = await arm.get_version()
    log["start_joints"] = await arm.get_joint_position()
    log["start_pose"] = await arm.get_cartesian_position()

    await arm.set_speed(80)
    await arm.move_to(pose(400.0, 50.0, 150.0, yaw=20.0))
    log["after_cartesian"] = await arm.get_cartesian_position()
    joints = {1: 180.0, 2: -40.0, 3: 100.0, 4: -50.0}
    await arm.move_to(joints)
    log["after_joints"] = await arm.get_joint_position()

    await arm.open_gripper(110.0)
    log["opened"] = (await arm.get_joint_position())[5]
    await arm.close_gripper(70.0)
    log["closed"] = (await arm.get_joint_position())[5], await arm.is_gripper_closed()
    await arm.open_gripper(110.0)

    await arm.pick_up_resource(pose(350.0, -150.0, 27.2), plate_width=PLATE_WIDTH)
    log["holding"] = (await arm.get_joint_position())[5], await arm.is_gripper_closed()
    await arm.drop_resource(pose(350.0, 150.0, 28.2))
    log["after_place"] = await arm.get_cartesian_position()

    # On to the pallet's second position (pallet station 5: origin, last X point, index).
    await arm.pick_up_resource(pose(350.0, 150.0, 27.2), plate_width=PLATE_WIDTH)
    await arm.set_pallet_origin(5, pose(-150.0, 280.0, 18.2, yaw=90.0))
    await arm.set_pallet_x(5, 2, -150.0, 420.0, 18.2)
    await arm.set_station_type(5, access_type=1, location_type=1, z_clearance=100.0, z_above=0.0,
                               z_grasp_offset=10.0)
    await arm.set_pallet_index(5, 2)
    log["pallet_index"] = await arm.get_pallet_index(5)
    await arm.place_plate_station(5)
    log["at_pallet"] = await arm.get_cartesian_position()
    try:
        await arm.send_command("no_such_command")
    except PreciseFlexError as err:
        log["unknown"] = err.replycode
    await arm.stop()


def test_pylabrobot_drives_the_tcs_and_moves_the_plate(tmp_path):
    report = tmp_path / "report.json"
    log: dict = {}
    arguments = ["programs/gpl/tcs", "--scene", "scenes/pf400_plates.toml", "--fast", "--report", str(report)]
    with serving(arguments, [PORT]) as served:
        asyncio.run(asyncio.wait_for(session(log, served.port(PORT)), timeout=300))
    assert served.returncode == 0, served.stderr

    assert "TCS" in log["version"]
    assert set(log["start_joints"]) >= {1, 2, 3, 4, 5}
    start = log["start_pose"]  # the scene's home: the plate-centre tool point
    assert (start.location.x, start.location.y, start.location.z) == pytest.approx((350.0, 0.0, 140.0), abs=0.05)
    assert start.rotation.y == pytest.approx(90.0) and start.orientation == ElbowOrientation.RIGHT

    reached = log["after_cartesian"]
    assert (reached.location.x, reached.location.y, reached.location.z) == pytest.approx((400.0, 50.0, 150.0), abs=0.1)
    assert reached.rotation.z == pytest.approx(20.0, abs=0.05)
    for axis, value in {1: 180.0, 2: -40.0, 3: 100.0, 4: -50.0}.items():
        assert log["after_joints"][axis] == pytest.approx(value, abs=0.05)

    assert log["opened"] == pytest.approx(110.0)
    assert log["closed"] == (pytest.approx(70.0), True)  # closed on nothing: fully closed
    assert log["holding"] == (pytest.approx(PLATE_WIDTH), False)  # a plate between the jaws
    placed = log["after_place"]
    assert (placed.location.x, placed.location.y) == pytest.approx((350.0, 150.0), abs=0.1)
    assert log["unknown"] == -714

    assert log["pallet_index"] == (5, 2, 1, 1)
    at_pallet = log["at_pallet"]  # back at the approach point above pallet position 2
    assert (at_pallet.location.x, at_pallet.location.y) == pytest.approx((-150.0, 420.0), abs=0.1)

    data = json.loads(report.read_text())
    assert data["errors"] == []
    # The plate went to the target nest, then to the pallet's second cell.
    releases = [e["where"] for e in data["events"] if e["kind"] == "release" and e["part"] == 0]
    assert releases == ["nest_b", "pallet"]
    plate = data["parts"][0]  # (the stacker may have put the next plate on the source nest)
    assert plate["region"] == "pallet" and plate["tray"] == "pallet" and plate["cell"] == 1
    assert not plate["dropped"]
    assert plate["pose"][:2] == pytest.approx([-150.0, 420.0], abs=2.0)
