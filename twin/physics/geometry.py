"""Pose helpers: V+ locations, homogeneous matrices, a small numeric flange IK.

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


def flange_ik(model: mujoco.MjModel, T_world_flange: np.ndarray, joint_names: list[str],
              site: str = "flange", q0: np.ndarray | None = None, righty: bool = True,
              tol: float = 1e-9, iterations: int = 100) -> np.ndarray:
    """Joint positions (rad, m) that put ``site`` at the WORLD pose ``T_world_flange``.

    Damped Newton on the site position and the heading of its x axis (a 4-axis SCARA
    controls x, y, z and one rotation about the vertical). Works on a scratch MjData,
    so the caller's state is untouched. Raises ValueError when it does not converge.
    """
    data = mujoco.MjData(model)
    sid = model.site(site).id
    jids = [model.joint(n).id for n in joint_names]
    qadr = np.array([model.jnt_qposadr[j] for j in jids])
    dadr = np.array([model.jnt_dofadr[j] for j in jids])
    target_p = T_world_flange[:3, 3]
    target_x = T_world_flange[:3, 0]
    target_h = math.atan2(target_x[1], target_x[0])
    guesses = [q0] if q0 is not None else []
    sign = 1.0 if righty else -1.0
    guesses += [np.array([a, sign * b, 0.1, 0.0]) for a in (0.0, -1.0, 1.0) for b in (1.5, 0.8, 2.3)]
    jacp = np.zeros((3, model.nv))
    jacr = np.zeros((3, model.nv))
    for guess in guesses:
        q = np.array(guess, dtype=float)
        for _ in range(iterations):
            data.qpos[qadr] = q
            mujoco.mj_kinematics(model, data)
            mujoco.mj_comPos(model, data)
            p = data.site_xpos[sid]
            xm = data.site_xmat[sid].reshape(3, 3)
            h = math.atan2(xm[1, 0], xm[0, 0])
            err = np.concatenate([target_p - p, [math.remainder(target_h - h, 2 * math.pi)]])
            if np.max(np.abs(err)) < tol:
                break
            mujoco.mj_jacSite(model, data, jacp, jacr, sid)
            J = np.vstack([jacp[:, dadr], jacr[2:3, dadr]])
            dq = np.linalg.solve(J.T @ J + 1e-9 * np.eye(len(q)), J.T @ err)
            q += dq
        lo = model.jnt_range[jids, 0]
        hi = model.jnt_range[jids, 1]
        ok = np.max(np.abs(err)) < 1e-6 and np.all(q >= lo - 1e-9) and np.all(q <= hi + 1e-9)
        if ok and (q[1] > 0) == righty:
            return q
    raise ValueError("flange_ik: no solution in the joint limits for the requested configuration")
