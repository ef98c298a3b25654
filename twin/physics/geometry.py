"""Pose helpers: V+ locations, homogeneous matrices, quaternions.

V+ locations are ``[x, y, z, yaw, pitch, roll]`` in millimetres and degrees with
R = Rz(yaw) * Ry(pitch) * Rz(roll). Matrices here are 4x4 in metres.
"""

from __future__ import annotations

import math

import mujoco
import numpy as np

MM = 1000.0


def rot_z(a: float) -> np.ndarray:
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def rot_y(a: float) -> np.ndarray:
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def vplus_to_matrix(loc) -> np.ndarray:
    """V+ location [x, y, z mm, yaw, pitch, roll deg] -> 4x4 matrix in metres."""
    x, y, z, yaw, pitch, roll = (float(v) for v in loc)
    T = np.eye(4)
    T[:3, :3] = rot_z(math.radians(yaw)) @ rot_y(math.radians(pitch)) @ rot_z(math.radians(roll))
    T[:3, 3] = (x / MM, y / MM, z / MM)
    return T


def matrix_to_quat(R: np.ndarray) -> np.ndarray:
    """Rotation matrix -> unit quaternion (w, x, y, z), MuJoCo order."""
    q = np.zeros(4)
    mujoco.mju_mat2Quat(q, np.ascontiguousarray(R, dtype=float).ravel())
    return q


def yaw_quat(yaw_rad: float) -> np.ndarray:
    return np.array([math.cos(yaw_rad / 2), 0.0, 0.0, math.sin(yaw_rad / 2)])
