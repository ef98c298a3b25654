"""Robot kinematics (twin.controller.kinematics) on the Cobra s600 model."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from twin.controller.kinematics import (
    JOINT_LIMIT,
    LOCATION_OUT_OF_RANGE,
    KinematicsError,
    LinearRail,
    RobotKinematics,
)
from twin.controller.location import Location

from conftest import COBRA as ROBOT
from conftest import ROOT
from conftest import tool_down_pose as _pose


def test_model_data_read_from_the_mjcf(kin):
    assert kin.joint_names == ["j1", "j2", "j3", "j4"]
    assert np.allclose(kin.lower, [-1.8326, -2.618, 0, -6.2832])
    assert np.allclose(kin.upper, [1.8326, 2.618, 0.21, 6.2832])
    assert np.allclose(kin.max_velocity, [6.737, 12.566, 1.1, 20.944])
    assert np.allclose(kin.max_acceleration, [75, 125, 30, 110])
    s = kin.scara
    assert s is not None and s.l1 == pytest.approx(0.325) and s.l2 == pytest.approx(0.275)


def test_fk_matches_mujoco_site(kin):
    model = mujoco.MjModel.from_xml_path(str(ROBOT))
    data = mujoco.MjData(model)
    adr = [model.joint(n).qposadr[0] for n in kin.joint_names]
    rng = np.random.default_rng(0)
    for _ in range(50):
        q = rng.uniform(kin.lower, kin.upper)
        data.qpos[adr] = q
        mujoco.mj_kinematics(model, data)
        T = kin.fk(q)
        assert np.allclose(T[:3, 3], data.site("flange").xpos, atol=1e-12)
        assert np.allclose(T[:3, :3], data.site("flange").xmat.reshape(3, 3), atol=1e-12)
        assert np.allclose(kin.fk_positions(q)[0], T[:3, 3], atol=1e-12)
        # The Cobra's tool points down: V+ reads pitch 180 and yaw 0 everywhere.
        loc = Location.from_matrix(T)
        assert loc.pitch == 180.0 and loc.yaw == 0.0


def test_jacobian_is_the_derivative_of_fk(kin):
    q = np.array([0.3, 1.1, 0.07, -0.4])
    J = kin.jacobian(q)
    h = 1e-7
    for i in range(4):
        dq = np.zeros(4)
        dq[i] = h
        dp = (kin.fk(q + dq)[:3, 3] - kin.fk(q - dq)[:3, 3]) / (2 * h)
        assert np.allclose(J[:3, i], dp, atol=1e-6)


@pytest.mark.parametrize("righty", [True, False])
def test_ik_round_trip_over_the_workspace(kin, righty):
    """A grid over the whole reachable annulus, all heights, several rolls: FK(IK(T)) = T
    within 0.01 mm, in the configuration asked for."""
    s = kin.scara
    r_in, r_out = abs(s.l1 - s.l2), s.l1 + s.l2
    seed = np.array([0.0, 0.5 if righty else -0.5, 0.1, 0.0])
    reached = 0
    for x in np.linspace(-0.6, 0.6, 25):
        for y in np.linspace(-0.6, 0.6, 25):
            r = np.hypot(x, y)
            if not (r_in + 1e-3 < r < r_out - 1e-3):
                continue
            for z, roll in ((0.34, 0.0), (0.24, 135.0), (0.131, -60.0)):
                T = _pose(x, y, z, roll)
                # Independent textbook oracle: is it inside J1 +/-105 deg, J2 +/-150 deg?
                c = (r * r - 0.325**2 - 0.275**2) / (2 * 0.325 * 0.275)
                q2 = np.arccos(np.clip(c, -1, 1)) * (1 if righty else -1)
                q1 = np.arctan2(y, x) - np.arctan2(0.275 * np.sin(q2), 0.325 + 0.275 * np.cos(q2))
                q1 = (q1 + np.pi) % (2 * np.pi) - np.pi
                feasible = abs(q1) <= kin.upper[0] and abs(q2) <= kin.upper[1]
                try:
                    q = kin.ik(T, seed, righty=righty)
                except KinematicsError as err:
                    assert err.code == JOINT_LIMIT and not feasible
                    continue
                assert feasible
                assert kin.is_righty(q) == righty
                assert np.all(q >= kin.lower - 1e-9) and np.all(q <= kin.upper + 1e-9)
                Tq = kin.fk(q)
                assert np.linalg.norm(Tq[:3, 3] - T[:3, 3]) < 1e-5
                assert np.allclose(Tq[:3, :3], T[:3, :3], atol=1e-9)
                reached += 1
    assert reached > 600


def test_ik_recovers_random_joint_vectors(kin):
    rng = np.random.default_rng(5)
    for _ in range(300):
        q = rng.uniform(kin.lower, kin.upper)
        q[1] = np.sign(q[1]) * max(abs(q[1]), 0.05)  # keep clear of the stretched arm
        got = kin.ik(kin.fk(q), q + rng.normal(0, 0.2, 4), righty=kin.is_righty(q))
        # J4 is multi-turn (+/-360 deg): the seed picks the turn; everything else is unique.
        assert np.allclose(got, q, atol=1e-9)


def test_scara_ik_is_the_closed_form_where_it_lands(kin, monkeypatch):
    """A SCARA's closed form is exact: `ik` checks it with one forward kinematics instead of
    refining it (belt tracking solves one every servo step); the answer is the refined one."""
    rng = np.random.default_rng(7)
    cases = []
    for _ in range(100):
        q = rng.uniform(kin.lower, kin.upper)
        q[1] = np.sign(q[1]) * max(abs(q[1]), 0.05)
        cases.append((kin.fk(q).copy(), q + rng.normal(0, 0.2, 4), kin.is_righty(q)))
    refined = [kin._refine(T, kin._scara_ik(T, seed, righty, False)) for T, seed, righty in cases]

    def no_refine(*args, **kwargs):
        raise AssertionError("refined a closed form that lands")
    monkeypatch.setattr(kin, "_refine", no_refine)
    for (T, seed, righty), want in zip(cases, refined):
        got = kin.ik(T, seed, righty=righty)
        assert np.allclose(got, want, atol=1e-12)
        assert np.abs(kin.fk(got)[:3, 3] - T[:3, 3]).max() < 1e-10


def test_translation_rates_move_the_flange_without_turning_it(kin):
    """Belt tracking's velocity feed-forward: the joint speeds whose flange twist is the
    asked linear velocity and no rotation; the least-squares answer of the whole Jacobian,
    also for the stretched arm, where the task rows are singular."""
    rng = np.random.default_rng(3)
    for _ in range(50):
        q = rng.uniform(kin.lower, kin.upper)
        v = rng.normal(0.0, 0.2, 3)
        qd = kin.translation_rates(q, v)
        twist = np.concatenate([v, np.zeros(3)])
        assert np.allclose(qd, np.linalg.lstsq(kin.jacobian(q), twist, rcond=None)[0], atol=1e-9)
        if abs(q[1]) > 0.05:  # away from the stretched arm, the twist is met exactly
            assert np.allclose(kin.jacobian(q) @ qd, twist, atol=1e-9)
    stretched = np.zeros(4)
    qd = kin.translation_rates(stretched, np.array([0.1, 0.0, 0.0]))
    assert np.all(np.isfinite(qd))


def test_configuration_is_honoured_and_none_keeps_the_seeds(kin):
    T = _pose(0.35, 0.2, 0.3, 20)
    qr = kin.ik(T, np.zeros(4), righty=True)
    ql = kin.ik(T, np.zeros(4), righty=False)
    assert qr[1] > 0 and ql[1] < 0  # the model: J2 > 0 is RIGHTY
    assert np.allclose(kin.fk(qr), kin.fk(ql), atol=1e-9)
    assert kin.ik(T, ql, righty=None)[1] < 0
    assert kin.ik(T, qr, righty=None)[1] > 0


def test_j4_takes_the_turn_nearest_the_seed(kin):
    T = _pose(0.4, 0.0, 0.3, 10)
    q_a = kin.ik(T, np.array([0, 0.5, 0.1, 0.0]), righty=True)
    q_b = kin.ik(T, np.array([0, 0.5, 0.1, 2 * np.pi]), righty=True)
    assert q_b[3] - q_a[3] == pytest.approx(2 * np.pi)
    q_c = kin.ik(T, np.array([0, 0.5, 0.1, 100.0]), righty=True)  # far outside: stay within the limits
    assert kin.lower[3] <= q_c[3] <= kin.upper[3]


@pytest.mark.parametrize(
    "x,y,why",
    [(0.7, 0.0, "too far"), (0.0, 0.02, "inside the |L1-L2| hole")],
)
def test_out_of_reach_is_location_out_of_range(kin, x, y, why):
    with pytest.raises(KinematicsError) as info:
        kin.ik(_pose(x, y, 0.3, 0), np.zeros(4), righty=True)
    assert info.value.code == LOCATION_OUT_OF_RANGE == -610
    assert info.value.message == "*Location out of range*"


def test_tilted_tool_is_out_of_range_for_a_four_axis_scara(kin):
    T = Location(400, 0, 300, 0, 170, 0).matrix()  # pitch must be 180 (V+ guide v17 L6044-6045)
    T[:3, 3] /= 1e3
    with pytest.raises(KinematicsError) as info:
        kin.ik(T, np.zeros(4))
    assert info.value.code == LOCATION_OUT_OF_RANGE


def test_joint_limits_are_reported_with_the_joint(kin):
    # Behind the robot: J1 would need more than 105 deg in this configuration.
    with pytest.raises(KinematicsError) as info:
        kin.ik(_pose(-0.45, 0.05, 0.3, 0), np.zeros(4), righty=True)
    assert info.value.code == JOINT_LIMIT and info.value.joint == 1
    assert info.value.message == "*Joint 1 limit stop*"
    # Below the J3 stroke.
    with pytest.raises(KinematicsError) as info:
        kin.ik(_pose(0.4, 0.1, 0.05, 0), np.zeros(4), righty=True)
    assert info.value.joint == 3


def test_single_keeps_the_wrist_within_half_a_turn(kin):
    """SINGLE: the wrist stays within +/-180 deg whatever the seed; MULTIPLE (the default)
    takes the turn nearest the seed (V+ guide v17 "Motion Modifiers", SINGLE/MULTIPLE)."""
    T = _pose(0.4, 0.0, 0.3, 10)
    seed = np.array([0, 0.5, 0.1, 2 * np.pi])
    assert kin.ik(T, seed, righty=True)[3] > np.pi
    q = kin.ik(T, seed, righty=True, single=True)
    assert -np.pi <= q[3] < np.pi
    assert np.allclose(kin.fk(q), T, atol=1e-9)


GANTRY = ROOT / "models" / "robots" / "cartesian_gantry.xml"


def test_gantry_ik_round_trip_over_the_whole_workspace():
    """The Cartesian robot (models/robots/cartesian_gantry.xml): every location of its
    box-shaped workspace, several tool rolls, FK(IK(T)) = T within 0.01 mm; a location past
    a stroke is out of range (-610)."""
    gantry = RobotKinematics.from_mjcf(GANTRY)
    assert gantry.scara is None and gantry.joint_names == ["x", "y", "z", "theta"]
    seed = np.array([0.35, 0.4, 0.15, 0.0])
    for x in np.linspace(0.0, 0.7, 8):
        for y in np.linspace(0.0, 0.8, 8):
            for z, roll in ((0.404, 180.0), (0.25, 45.0), (0.104, -100.0)):
                T = _pose(x, y, z, roll)
                q = gantry.ik(T, seed)
                Tq = gantry.fk(q)
                assert np.linalg.norm(Tq[:3, 3] - T[:3, 3]) < 1e-5
                assert np.allclose(Tq[:3, :3], T[:3, :3], atol=1e-9)
                assert q[:3] == pytest.approx([x, y, 0.404 - z], abs=1e-9)  # flange = joints
    for x, y, z in ((0.75, 0.3, 0.2), (0.3, -0.02, 0.2), (0.3, 0.3, 0.09)):
        with pytest.raises(KinematicsError) as info:
            gantry.ik(_pose(x, y, z, 180.0), seed)
        assert info.value.code == LOCATION_OUT_OF_RANGE


def _line_poses(kin, q0, p1, yaw_deg, n):
    """Flange poses on the straight line from fk(q0) to p1, the yaw turning by yaw_deg."""
    T0 = kin.fk(q0)
    out = np.empty((n, 4, 4))
    for i, u in enumerate(np.linspace(0.0, 1.0, n + 1)[1:]):
        c, s = np.cos(np.radians(yaw_deg * u)), np.sin(np.radians(yaw_deg * u))
        out[i] = T0
        out[i, :3, :3] = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1.0]]) @ T0[:3, :3]
        out[i, :3, 3] = T0[:3, 3] + u * (np.asarray(p1) - T0[:3, 3])
    return out


@pytest.mark.parametrize("robot", ["cobra_s600", "pf400", "pf400 on a rail", "cartesian_gantry"])
def test_ik_path_is_ik_pose_by_pose_each_seeded_by_the_last(robot):
    """`ik_path` (the vectorised closed form of a SCARA's straight line) gives what `ik`
    gives pose by pose, continuous, each seeded by the previous one: the same turn of the
    multi-turn wrist across +/-180 deg, the same arm configuration, a rail held still."""
    rail = LinearRail(direction=(0.0, 1.0, 0.0), lower=-0.5, upper=0.5, max_velocity=0.75, max_acceleration=1.0,
                      axis_number=6) if robot.endswith("rail") else None
    kin = RobotKinematics.from_mjcf(ROOT / "models" / "robots" / f"{robot.split()[0]}.xml", rail=rail)
    rng = np.random.default_rng(3)
    checked = 0
    while checked < 20:
        q0 = rng.uniform(kin.lower * 0.8 + kin.upper * 0.2, kin.lower * 0.2 + kin.upper * 0.8)
        p1 = kin.fk(rng.uniform(kin.lower * 0.8 + kin.upper * 0.2, kin.lower * 0.2 + kin.upper * 0.8))[:3, 3]
        poses = _line_poses(kin, q0, p1, rng.uniform(-400, 400), 40)
        try:
            expected, q = [], q0
            for T in poses:
                q = kin.ik(T, q, continuous=True)
                expected.append(q)
        except KinematicsError:
            continue
        assert np.allclose(kin.ik_path(poses, q0), expected, atol=1e-9, rtol=0)
        checked += 1


def test_ik_path_raises_the_error_of_the_first_pose_that_fails(kin):
    """A line out of reach, or one taking a joint past its limit on the way, raises what
    `ik` raises at the first such pose."""
    q0 = kin.ik(_pose(0.4, 0.0, 0.3, 0), np.array([0, 1.0, 0, 0]), righty=True)
    with pytest.raises(KinematicsError) as info:
        kin.ik_path(_line_poses(kin, q0, [0.75, 0.0, 0.3], 0.0, 30), q0)
    assert info.value.code == LOCATION_OUT_OF_RANGE
    with pytest.raises(KinematicsError) as info:
        kin.ik_path(_line_poses(kin, q0, [0.4, 0.0, 0.05], 0.0, 30), q0)  # below the J3 stroke
    assert info.value.code == JOINT_LIMIT and info.value.joint == 3
