"""Time-optimal trajectories (twin.controller.trajectory) on the Cobra s600 model."""

from __future__ import annotations

import numpy as np
import pytest

from twin.controller.kinematics import (
    JOINT_LIMIT,
    LOCATION_OUT_OF_RANGE,
    STRAIGHT_LINE_CONFIG,
    KinematicsError,
)
from twin.controller.trajectory import KEPT_SAMPLES, joint_move_time, plan_joint_move, plan_straight_move

from conftest import tool_down_pose as _pose

DT = 0.0005


def _random_q(kin, rng, righty=True):
    q = rng.uniform(kin.lower * 0.8, kin.upper * 0.8)
    q[1] = abs(q[1]) if righty else -abs(q[1])
    q[1] = np.sign(q[1]) * max(abs(q[1]), 0.4)
    q[3] = rng.uniform(-3, 3)
    return q


def _check_limits(traj, vmax, amax, tol=0.02):
    t, q, qd = traj.sample(DT)
    assert np.all(np.abs(qd) <= vmax * (1 + tol) + 1e-12)
    qdd = np.diff(qd, axis=0) / np.diff(t)[:, None]
    assert np.all(np.abs(qdd) <= amax * (1 + tol) + 1e-9)
    # qd is the derivative of q
    fd = np.diff(q, axis=0) / np.diff(t)[:, None]
    mid = (qd[1:] + qd[:-1]) / 2
    assert np.allclose(fd, mid, atol=1e-3 * np.max(vmax))
    return t, q, qd, qdd


def test_joint_move_limits_endpoints_and_analytic_time(kin):
    rng = np.random.default_rng(0)
    vmax, amax = kin.max_velocity, kin.max_acceleration
    shapes = set()
    for _ in range(12):
        q0, q1 = _random_q(kin, rng), _random_q(kin, rng, righty=bool(rng.integers(2)))
        if rng.integers(3) == 0:  # short moves: triangular profiles
            q1 = q0 + (q1 - q0) * 0.02
        traj = plan_joint_move(q0, q1, vmax, amax)
        t, q, qd, qdd = _check_limits(traj, vmax, amax)
        assert np.array_equal(q[0], q0) and np.array_equal(q[-1], q1)
        assert np.array_equal(traj.q_start, q0) and np.array_equal(traj.q_end, q1)
        assert np.all(qd[0] == 0) and np.all(qd[-1] == 0)
        assert t[-1] == traj.duration
        analytic = joint_move_time(q0, q1, vmax, amax)
        assert traj.duration == pytest.approx(analytic, rel=0.002)  # the grid's cost: 0.11 % at most
        # time optimal: some joint uses its full acceleration
        assert np.max(np.abs(qdd) / amax) > 0.97
        shapes.add(bool(np.max(np.abs(qd) / vmax) > 0.99))  # cruise reached: trapezoid
        # straight line in joint space
        moving = np.abs(q1 - q0) > 1e-6
        u = (q[:, moving] - q0[moving]) / (q1 - q0)[None, moving]
        assert np.allclose(u, u[:, :1], atol=1e-9)
    assert shapes == {True, False}  # both trapezoid and triangle profiles were tested


def test_joint_move_slow_speed_scales_time(kin):
    q0, q1 = np.array([0.0, 1.0, 0.0, 0.0]), np.array([1.0, 0.5, 0.1, 2.0])
    fast = plan_joint_move(q0, q1, kin.max_velocity, kin.max_acceleration)
    slow = plan_joint_move(q0, q1, kin.max_velocity * 0.1, kin.max_acceleration)
    assert slow.duration > 3 * fast.duration
    assert slow.duration == pytest.approx(joint_move_time(q0, q1, kin.max_velocity * 0.1, kin.max_acceleration),
                                          rel=0.002)


@pytest.mark.parametrize("speed", [0.3, 0.05, 0.01])
def test_slow_joint_moves_still_accelerate_at_the_limit(kin, speed):
    """At a low speed the acceleration phase is a tiny part of the path: the grid still
    resolves it, so the joints speed up as hard as at full speed (SPEED and DURATION
    lower the speed, not the acceleration)."""
    q0, q1 = np.array([0.0, 1.0, 0.0, 0.0]), np.array([1.0, 0.5, 0.1, 2.0])
    vmax = kin.max_velocity * speed
    traj = plan_joint_move(q0, q1, vmax, kin.max_acceleration)
    t, _, qd = traj.sample(DT)
    qdd = np.diff(qd, axis=0) / np.diff(t)[:, None]
    assert np.all(np.abs(qd) <= vmax * 1.001) and np.all(np.abs(qdd) <= kin.max_acceleration * 1.001)
    assert np.max(np.abs(qdd) / kin.max_acceleration) > 0.97
    assert traj.duration == pytest.approx(joint_move_time(q0, q1, vmax, kin.max_acceleration), rel=0.002)


def test_sample_times_include_the_end(kin):
    traj = plan_joint_move(np.zeros(4), np.array([0.1, 0.1, 0.01, 0.1]), kin.max_velocity, kin.max_acceleration)
    t, q, qd = traj.sample(0.002)
    assert np.allclose(np.diff(t[:-1]), 0.002) and 0 < t[-1] - t[-2] <= 0.002 + 1e-12
    assert t[0] == 0.0 and t[-1] == traj.duration
    q_mid, qd_mid = traj.at(t[5])
    assert np.allclose(q_mid, q[5]) and np.allclose(qd_mid, qd[5])
    assert np.array_equal(traj.at(10.0)[0], traj.q_end)


def test_a_plan_run_again_is_sampled_once_and_read_only(kin):
    """A cyclic program runs its cached plans over and over at the monitor speed: the slowed
    plan and its samples are made once, and the shared samples cannot be changed in place."""
    tr = plan_joint_move(kin.lower * 0.3, kin.upper * 0.3, kin.max_velocity, kin.max_acceleration)
    slow = tr.stretched(2 * tr.duration)
    assert tr.stretched(2 * tr.duration) is slow
    assert slow.duration == pytest.approx(2 * tr.duration)
    times, q, qd = slow.sample(0.002)
    again = slow.sample(0.002)
    assert all(a is b for a, b in zip((times, q, qd), again))
    with pytest.raises(ValueError):
        q[0, 0] = 1.0
    _, q_fine, _ = slow.sample(0.001)  # another step: sampled anew
    assert np.allclose(q_fine[:2 * (len(q) - 1):2], q[:-1]) and np.array_equal(q_fine[-1], q[-1])
    assert slow.accel_time == pytest.approx(2 * tr.accel_time) and slow.decel_time == pytest.approx(2 * tr.decel_time)
    crawl = tr.stretched(KEPT_SAMPLES * 0.002 * 1.5)  # a slow crawl's samples are not kept
    assert crawl.sample(0.002)[1] is not crawl.sample(0.002)[1]


def test_zero_length_moves(kin):
    q = np.array([0.2, 1.0, 0.1, 0.3])
    traj = plan_joint_move(q, q, kin.max_velocity, kin.max_acceleration)
    assert traj.duration == 0.0
    t, qs, qd = traj.sample(0.002)
    assert t.tolist() == [0.0] and np.array_equal(qs[0], q) and not qd.any()
    traj = plan_straight_move(kin, q, kin.fk(q), kin.max_velocity, kin.max_acceleration, 1.0)
    assert traj.duration == 0.0 and np.array_equal(traj.sample(0.002)[1][-1], q)


def test_pure_j4_rotation(kin):
    q0 = np.array([0.2, 1.0, 0.1, 0.3])
    q1 = q0 + np.array([0, 0, 0, 1.5])
    traj = plan_joint_move(q0, q1, kin.max_velocity, kin.max_acceleration)
    assert traj.duration == pytest.approx(joint_move_time(q0, q1, kin.max_velocity, kin.max_acceleration), rel=0.01)
    straight = plan_straight_move(kin, q0, kin.fk(q1), kin.max_velocity, kin.max_acceleration, 1.0)
    t, q, qd = straight.sample(DT)
    assert np.allclose(q[:, :3], q0[:3], atol=1e-9)  # only J4 turns
    assert np.allclose(q[-1], q1, atol=1e-9)
    assert straight.duration == pytest.approx(traj.duration, rel=0.01)


def _line_deviation(kin, traj, p0, p1):
    t, q, qd = traj.sample(0.0002)
    P = kin.fk_positions(q)
    d = p1 - p0
    u = np.clip((P - p0) @ d / (d @ d), 0, 1)
    return np.max(np.linalg.norm(P - (p0 + u[:, None] * d), axis=1)), P, t


def test_straight_moves_stay_on_the_line_within_limits(kin):
    rng = np.random.default_rng(7)
    vmax, amax = kin.max_velocity, kin.max_acceleration
    cart = 1.5
    done = 0
    while done < 8:
        q0 = _random_q(kin, rng)
        q1 = _random_q(kin, rng)
        try:
            traj = plan_straight_move(kin, q0, kin.fk(q1), vmax, amax, cart)
        except KinematicsError:
            continue  # the line leaves the workspace or a joint range: tested below
        done += 1
        p0, p1 = kin.fk(q0)[:3, 3], kin.fk(q1)[:3, 3]
        dev, P, t = _line_deviation(kin, traj, p0, p1)
        assert dev < 0.1e-3
        _check_limits(traj, vmax, amax)
        speed = np.linalg.norm(np.diff(P, axis=0), axis=1) / np.diff(t)
        assert speed.max() <= cart * 1.02
        qs = traj.sample(DT)[1]
        assert np.array_equal(qs[0], q0)
        assert np.allclose(kin.fk(qs[-1]), kin.fk(q1), atol=1e-9)
        assert all(kin.is_righty(q) for q in qs[:: max(1, len(qs) // 50)])
        # orientation follows the slerp: the roll changes monotonically
        yaw = np.unwrap([np.arctan2(kin.fk(q)[1, 0], kin.fk(q)[0, 0]) for q in qs[:: max(1, len(qs) // 40)]])
        assert np.all(np.diff(yaw) >= -1e-9) or np.all(np.diff(yaw) <= 1e-9)


@pytest.mark.parametrize("length_mm", [0.05, 1.0])
def test_straight_lines_of_a_fraction_of_a_millimetre_plan_quietly(kin, capfd, length_mm):
    """toppra cannot time about one line in ten of 0.05 mm on a path parameter in [0, 1]
    (its bounds on the path speed): such a line is timed on a stretched parameter and
    still runs straight, reaches its end within the limits, and toppra prints nothing (it
    logged three warnings on stderr a failure).  The conveyor case is the part arriving
    0.2 mm from the waiting tool."""
    rng = np.random.default_rng(3)
    vmax, amax = kin.max_velocity, kin.max_acceleration
    for _ in range(60):
        q0 = _random_q(kin, rng)
        T1 = kin.fk(q0)
        direction = rng.normal(size=3)
        T1[:3, 3] += direction / np.linalg.norm(direction) * length_mm * 1e-3
        try:
            kin.ik(T1, q0, righty=True)
        except KinematicsError:
            continue  # the end is out of reach or past a limit
        traj = plan_straight_move(kin, q0, T1, vmax, amax, 0.5)
        dev, _, _ = _line_deviation(kin, traj, kin.fk(q0)[:3, 3], T1[:3, 3])
        assert dev < 0.1e-3 * length_mm
        _check_limits(traj, vmax, amax)
        assert np.allclose(kin.fk(traj.sample(DT)[1][-1]), T1, atol=1e-9)
    q0 = np.array([0.7602531818079997, 1.9052235678828384, 0.08300000000000002, 1.0946804228959417])
    T1 = np.array([[0.00135569619983365, 0.9999990810434847, 0.0, -0.00870234197071118],
                   [0.9999990810434847, -0.00135569619983365, 0.0, 0.35000070100123176],
                   [0.0, 0.0, -1.0, 0.2580027434659425], [0.0, 0.0, 0.0, 1.0]])
    assert 0.0 < plan_straight_move(kin, q0, T1, vmax, amax, 0.5).duration < 0.05
    assert capfd.readouterr().err == ""


def test_straight_move_tcp_speed_limit_governs_long_lines(kin):
    q0 = kin.ik(_pose(0.45, -0.25, 0.30, 0), np.array([0, 1, 0, 0]), righty=True)
    T1 = _pose(0.45, 0.25, 0.30, 0)
    slow = plan_straight_move(kin, q0, T1, kin.max_velocity, kin.max_acceleration, 0.25)
    dev, P, t = _line_deviation(kin, slow, kin.fk(q0)[:3, 3], T1[:3, 3])
    speed = np.linalg.norm(np.diff(P, axis=0), axis=1) / np.diff(t)
    assert speed.max() == pytest.approx(0.25, rel=0.02)  # cruise at the TCP limit
    assert slow.duration > 0.5 / 0.25
    assert dev < 0.1e-3


def test_straight_line_errors(kin):
    q0 = kin.ik(_pose(0.3, -0.2, 0.3, 0), np.array([0, 1, 0, 0]), righty=True)
    vmax, amax = kin.max_velocity, kin.max_acceleration
    # A straight-line motion cannot change the arm configuration.
    with pytest.raises(KinematicsError) as info:
        plan_straight_move(kin, q0, _pose(0.3, 0.2, 0.3, 0), vmax, amax, 1.0, righty=False)
    assert info.value.code == STRAIGHT_LINE_CONFIG
    # Past the J1 axis closer than the elbow folds (J2 +/-150 deg: 163 mm), both ends reachable.
    qa = kin.ik(_pose(0.160, -0.06, 0.3, 0), np.array([0, 2.5, 0, 0]), righty=True)
    kin.ik(_pose(0.160, 0.06, 0.3, 0), qa, righty=True)
    with pytest.raises(KinematicsError) as info:
        plan_straight_move(kin, qa, _pose(0.160, 0.06, 0.3, 0), vmax, amax, 1.0)
    assert info.value.code == JOINT_LIMIT and info.value.joint == 2
    # Target beyond the reach.
    with pytest.raises(KinematicsError) as info:
        plan_straight_move(kin, q0, _pose(0.62, 0.0, 0.3, 0), vmax, amax, 1.0)
    assert info.value.code == LOCATION_OUT_OF_RANGE


def test_hole_check_sees_a_line_between_waypoints(kin):
    """The analytic check catches a line that dips into the unreachable disc around J1
    even where no waypoint would land inside it."""
    from twin.controller.trajectory import _segment_clear_of_hole

    r_min = np.sqrt(0.325**2 + 0.275**2 + 2 * 0.325 * 0.275 * np.cos(kin.upper[1]))
    a, b = np.array([r_min - 1e-5, -0.004, 0.3]), np.array([r_min - 1e-5, 0.004, 0.3])
    with pytest.raises(KinematicsError) as info:
        _segment_clear_of_hole(kin, a, b, righty=True)
    assert info.value.code == JOINT_LIMIT and info.value.joint == 2
    _segment_clear_of_hole(kin, a + [2e-5, 0, 0], b + [2e-5, 0, 0], righty=True)  # just clear: fine


def test_planning_does_not_load_pyplot_but_plotting_still_works():
    """toppra's eager `import matplotlib.pyplot` is deferred (0.45 s of every run that
    moves the robot); code that plots afterwards gets the real pyplot."""
    import subprocess
    import sys

    script = (
        "import sys\n"
        "from twin.controller.trajectory import _libs\n"
        "_libs()\n"
        "assert 'matplotlib.figure' not in sys.modules, 'pyplot was loaded'\n"
        "import matplotlib\n"
        "matplotlib.use('Agg')\n"
        "import matplotlib.pyplot as plt\n"
        "fig, ax = plt.subplots()\n"
        "ax.plot([0, 1], [0, 1])\n"
        "assert type(fig).__name__ == 'Figure'\n"
        "print('ok')\n"
    )
    out = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, check=False)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "ok"
