"""V+ transformations (twin.controller.location).

Line numbers refer to the V+ Language User's Guide v17,
/work/shared/seeds/vplus-language-users-guide-v17.txt.
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from twin.controller.location import NULL, Location, approach, trans


def _rz(a):
    c, s = np.cos(np.radians(a)), np.sin(np.radians(a))
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])


def _ry(a):
    c, s = np.cos(np.radians(a)), np.sin(np.radians(a))
    return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])


def _close(a: Location, b: Location, tol=1e-9):
    return np.allclose(a.matrix(), b.matrix(), atol=tol)


def test_rotation_is_zyz_intrinsic():
    # L5989 "ZYZ' Euler values"; L6048-6052: yaw, then pitch, then roll, in that order.
    loc = trans(30, 100, 125, 30, 40, 20)  # the guide's example values, L6010-6025
    R = _rz(30) @ _ry(40) @ _rz(20)
    assert np.allclose(loc.matrix()[:3, :3], R, atol=1e-15)
    assert np.allclose(loc.matrix()[:3, 3], [30, 100, 125])
    p = np.array([1.0, 2.0, 3.0])
    assert np.allclose((loc.matrix() @ np.append(p, 1))[:3], [30, 100, 125] + R @ p)


def test_trans_defaults_and_null():
    # TRANS(0,50): missing components are 0 (L6164).
    assert trans(0, 50) == Location(0, 50, 0, 0, 0, 0)
    assert trans(-50, 20, 30).components() == (-50.0, 20.0, 30.0, 0.0, 0.0, 0.0)
    assert NULL.components() == (0.0,) * 6
    assert np.array_equal(NULL.matrix(), np.eye(4))


def test_guide_relative_transformation_example():
    # L6143-6183: loc_a = TRANS(300,50,350,0,180,0); loc_a:TRANS(-50,20,30) is
    # 350, 70, 320, 0, 180, 0; HERE loc_a:loc_b gives loc_b = -50,20,30,0,0,0.
    loc_a = trans(300, 50, 350, 0, 180, 0)
    loc_b = trans(-50, 20, 30)
    loc_c = loc_a * loc_b
    assert loc_c.components() == pytest.approx((350, 70, 320, 0, 180, 0), abs=1e-12)
    here = loc_c
    assert (loc_a.inverse() * here).components() == pytest.approx((-50, 20, 30, 0, 0, 0), abs=1e-12)
    # MOVE loc_c:INVERSE(loc_b) returns to loc_a (L6179-6183).
    assert _close(loc_c * loc_b.inverse(), loc_a)
    # loc_a:loc_b:loc_d with loc_d = TRANS(0,50): x=-50, y=70, z=30 relative to loc_a (L6164-6170).
    rel = loc_a.inverse() * (loc_a * loc_b * trans(0, 50))
    assert rel.components() == pytest.approx((-50, 70, 30, 0, 0, 0), abs=1e-12)


def test_composition_and_inverse_identities():
    rng = np.random.default_rng(1)
    for _ in range(200):
        a, b, c = (Location(*rng.uniform(-500, 500, 3), *rng.uniform(-180, 180, 3)) for _ in range(3))
        assert _close(a * a.inverse(), NULL, 1e-9)
        assert _close(a.inverse() * a, NULL, 1e-9)
        assert _close((a * b) * c, a * (b * c), 1e-8)
        assert _close((a * b).inverse(), b.inverse() * a.inverse(), 1e-8)
        assert _close(a * NULL, a) and _close(NULL * a, a)
        assert np.allclose((a * b).matrix(), a.matrix() @ b.matrix(), atol=1e-9)


def test_euler_round_trip_generic():
    rng = np.random.default_rng(2)
    for _ in range(500):
        yaw, roll = rng.uniform(-179.9, 180, 2)
        pitch = rng.uniform(0.01, 179.99)
        loc = Location(1, 2, 3, yaw, pitch, roll)
        back = Location.from_matrix(loc.matrix())
        assert back.components() == pytest.approx(loc.components(), abs=1e-8)


@pytest.mark.parametrize("yaw,roll", [(0, 0), (0, 37), (30, 40), (-90, 90), (170, -170), (180, 180), (45, -135)])
def test_pitch_180_scara_puts_everything_in_roll(yaw, roll):
    # L6033-6037: four-axis SCARA, quill rotation "in the roll component ..., and the yaw
    # component is forced to 0 degrees"; tool straight down, pitch = 180 (L6044-6045).
    loc = Location(100, 0, 50, yaw, 180, roll)
    assert loc.yaw == 0.0 and loc.pitch == 180.0
    R = _rz(yaw) @ _ry(180) @ _rz(roll)
    assert np.allclose(loc.matrix()[:3, :3], R, atol=1e-12)  # same rotation as asked for
    dec = Location.from_matrix(loc.matrix())
    assert dec.yaw == 0.0 and dec.pitch == 180.0
    assert dec.roll == pytest.approx(loc.roll, abs=1e-9)
    expect = ((roll - yaw + 180) % 360) - 180
    assert np.isclose(np.cos(np.radians(dec.roll - expect)), 1.0)


def test_pitch_0_sums_yaw_into_roll():
    loc = Location(0, 0, 0, 30, 0, 40)
    assert loc.components() == (0.0, 0.0, 0.0, 0.0, 0.0, 70.0)
    assert Location.from_matrix(trans(yaw=30, roll=40).matrix()).components() == pytest.approx((0, 0, 0, 0, 0, 70))


def test_near_singular_matrix_decomposes_deterministically():
    # A SCARA pose with float noise off pitch 180 must still read yaw 0, pitch 180.
    T = Location(0, 0, 0, 0, 180, 25).matrix()
    T[:3, :3] = T[:3, :3] @ _ry(1e-9)
    dec = Location.from_matrix(T)
    assert dec.yaw == 0.0 and dec.pitch == 180.0 and dec.roll == pytest.approx(25, abs=1e-6)


def test_angles_normalised():
    # L6018: "a positive rotation of 190 deg is shown as -170 degrees"; range (-180, 180].
    loc = Location(0, 0, 0, 190, 40, -190)
    assert loc.yaw == pytest.approx(-170) and loc.roll == pytest.approx(170)
    assert Location(0, 0, 0, -180, 40, 540).components()[3:] == (180.0, 40.0, 180.0)
    # A negative pitch is the same rotation as (yaw+180, -pitch, roll+180): pitch shows in [0, 180].
    neg = Location(0, 0, 0, 10, -40, 20)
    assert neg.components()[3:] == pytest.approx((-170, 40, -160))
    assert np.allclose(neg.matrix()[:3, :3], _rz(10) @ _ry(-40) @ _rz(20), atol=1e-12)
    for angles in itertools.product([-180, -90, 0, 90, 180, 270], repeat=3):
        c = Location(0, 0, 0, *angles).components()[3:]
        assert all(-180 < a <= 180 for a in c) and 0 <= c[1] <= 180


def test_shift_is_in_world_axes():
    # SHIFT(loc BY dx, dy, dz) alters the Cartesian components (L6105-6111), orientation kept.
    loc = Location(300, 50, 350, 0, 180, 30)
    s = loc.shifted(5, -5, 10)
    assert s.components() == (305.0, 45.0, 360.0, 0.0, 180.0, 30.0)
    assert loc.shifted() == loc


def test_approach_point_is_above_a_scara_location():
    # L6360-6364: APPRO place, 50 goes to "a point 50 mm above place" on a four-axis robot;
    # L6369-6372: along the tool Z axis, so pitch 135 approaches at 45 deg to the world.
    place = Location(350, 20, 100, 0, 180, 73)
    a = approach(place, 50)
    assert a.components() == pytest.approx((350, 20, 150, 0, 180, 73), abs=1e-12)
    tilted = Location(0, 0, 0, 0, 135, 0)
    p = approach(tilted, 10).matrix()[:3, 3]
    assert np.allclose(p, -10 * tilted.matrix()[:3, 2])
    assert np.degrees(np.arccos(abs(p[2]) / 10)) == pytest.approx(45)
    assert approach(place, 0) == place
