"""The PreciseFlex PF400 model (models/robots/pf400.xml): a SCARA whose first joint is the
vertical column, its flange pointing out level (pitch 90), and the plate bench
scenes/pf400_plates.toml."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from twin.controller.kinematics import KinematicsError, RobotKinematics
from twin.physics.geometry import vplus_to_matrix
from twin.runner import run_program

MODEL = Path("models/robots/pf400.xml")
DATA = Path(__file__).parent / "data"


@pytest.fixture(scope="module")
def kin() -> RobotKinematics:
    return RobotKinematics.from_mjcf(MODEL)


def test_the_pf400_is_a_scara_with_the_column_first(kin):
    s = kin.scara
    assert s is not None
    assert (s.slide, s.shoulder, s.elbow_joint, s.wrist) == (0, 1, 2, 3)
    assert s.l1 + s.l2 == pytest.approx(0.591)  # 302 + 289 mm, the 588 mm reach class
    assert list(kin.revolute) == [False, True, True, True]
    # At zero the flange reads (x, y, z, yaw 0, pitch 90, roll 180): level, fingers down.
    T = kin.fk(np.zeros(4))
    assert T[:3, :3] == pytest.approx(vplus_to_matrix([0, 0, 0, 0, 90, 180])[:3, :3], abs=1e-12)
    assert T[:3, 3] == pytest.approx([0.591, 0.0, -0.01], abs=1e-12)


@pytest.mark.parametrize("righty", [True, False])
@pytest.mark.parametrize("pose", [(300, -150, 87.2, 0), (450, 0, 150, 45), (420, 200, 300, -135)])
def test_inverse_kinematics_round_trips_in_both_arm_configurations(kin, pose, righty):
    x, y, z, yaw = pose
    T = vplus_to_matrix([x, y, z, yaw, 90, 180])
    q = kin.ik(T, np.array([0.2, 0.0, 0.0, 0.0]), righty=righty)
    assert kin.fk(q) == pytest.approx(T, abs=1e-9)
    assert kin.is_righty(q) == righty
    assert (q[2] < math.pi) == righty  # J3, the elbow (12 to 348 deg), carries the configuration


def test_a_tilted_tool_or_a_height_past_the_column_is_refused(kin):
    tilted = vplus_to_matrix([300, 0, 100, 0, 80, 180])
    with pytest.raises(KinematicsError) as err:
        kin.ik(tilted, np.zeros(4))
    assert err.value.code == -610
    high = vplus_to_matrix([300, 0, 500, 0, 90, 180])
    with pytest.raises(KinematicsError) as err:
        kin.ik(high, np.zeros(4))
    assert err.value.joint == 1  # the column's 400 mm stroke
    behind = vplus_to_matrix([-150, 300, 78, 90, 90, 180])
    assert kin.is_righty(kin.ik(behind, np.zeros(4), righty=True))
    with pytest.raises(KinematicsError) as err:
        kin.ik(behind, np.zeros(4), righty=False)  # lefty there needs the shoulder past 93 deg
    assert err.value.joint == 2
    # 589 mm out: within the 591 mm of the two links, but the elbow would have to open
    # to 9.4 deg, and the PF400's J3 stops at 12 deg (it never stretches the arm).
    far = vplus_to_matrix([589, 0, 100, 0, 90, 180])
    with pytest.raises(KinematicsError) as err:
        kin.ik(far, np.zeros(4), righty=True)
    assert err.value.joint == 3


def test_a_vplus_program_moves_the_plate_between_the_nests():
    result = run_program(DATA / "pf400_move_plate.pg", scene="scenes/pf400_plates.toml")
    report = result.report
    assert report.errors == []
    assert report.regions["nest_b"] == 1
    (plate,) = report.parts  # the feeder's one plate, still in play on the target nest
    assert plate["region"] == "nest_b" and plate["picked"] and not plate["dropped"]
    x, y, z = plate["pose"][:3]
    assert math.hypot(x - 350.0, y - 150.0) < 2.0  # mm: where the target nest is
    assert z == pytest.approx(770.0 + 14.35 / 2, abs=0.5)  # resting on it
    kinds = [e["kind"] for e in report.events]
    assert kinds.count("grasp") == 1 and kinds.count("release") == 1


def test_a_gpl_program_for_the_pf400_runs_in_its_own_coordinates():
    """Plate-centre tool, pitch 90, ZWorld approaches, GPL_Righty; Where, WhereAngles
    and the plate-present input read as on the robot."""
    result = run_program(DATA / "gpl" / "pf400_plate", scene="scenes/pf400_plates.toml")
    report = result.report
    assert report.errors == []
    assert report.output.splitlines() == ["at pick 350 -150 pitch 90 config 1", "J1 97", "holding True"]
    assert report.regions["nest_b"] == 1
