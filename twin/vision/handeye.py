"""Hand-eye calibration of a camera on the robot, from images only.

The routine of a real cell: a calibration plate (OpenCV's asymmetric circles grid) lies on
the work plane; the robot moves the camera over it to a grid of flange poses (positions,
heights, yaws: ``[camera.calibration]`` of a camera with ``mount``) and takes a picture at
each.  What the solve gets is what a controller and a camera give: the flange pose of each
picture from the robot's own kinematics (its joint positions), the dots found in the
picture, the dots' layout (the plate's drawing) and the height of the plate's top face in
the robot frame (the work plane).  Nothing of the camera or of where the plate lies is read
from the simulator.

A SCARA's flange turns about the vertical only, so the camera's height above the flange and
the plate's height cannot both be found from the pictures (moving both by the same amount
changes no picture): the plate's height is given, as it is on a real cell (the robot
touches the plane), and its position and yaw on the plane are solved for.

The solve, with OpenCV's projection and a Levenberg-Marquardt loop of our own over: focal
length (square pixels, principal point at the image centre), k1, k2, the camera's pose in
the flange frame (6) and the plate's x, y and yaw.  Its start: from each picture's
homography, the scale (pixels per mm) against the flange height gives the focal length and
the camera's height (a straight line); the camera's turn about its axis and its offset from
the flange come from a linear least-squares fit of where the plate's centre is seen, tried
at every degree of turn.  The residual is in pixels and in mm (each dot's pixel cast back
onto the plate's plane against where the solved plate has it).
"""

from __future__ import annotations

import math

import cv2
import mujoco
import numpy as np

from ..physics.camera import PARKED, PLATE_GRID, CameraConfig, plate_body, plate_dots
from ..physics.geometry import MM, rot_z, vplus_to_matrix
from .calibration import CameraModel
from .camera import Camera

LM_ITERATIONS = 100


def find_plate(gray: np.ndarray) -> np.ndarray | None:
    """The plate's dot centres (N x 2 pixels) in the grid's order, or None when the whole
    grid is not in the picture."""
    found, centres = cv2.findCirclesGrid(gray, PLATE_GRID, flags=cv2.CALIB_CB_ASYMMETRIC_GRID)
    return centres.reshape(-1, 2).astype(np.float64) if found else None


def flange_poses(plan) -> list[np.ndarray]:
    """The plan's flange poses (robot frame, 4x4 m): tool pointing down, at every x, y,
    height and yaw."""
    return [vplus_to_matrix([x, y, z, yaw, 180.0, 0.0]) for z in plan.heights for yaw in plan.angles
            for x in plan.x for y in plan.y]


def calibrate_hand_eye(cell, config: CameraConfig) -> tuple[CameraModel, list[dict]]:
    """Run the plan on a copy of the cell's state; returns the camera model (with its pose in
    the flange frame) and one record per picture (flange pose, dots found)."""
    plan = config.calibration
    model, kin = cell.model, cell.kinematics
    scratch = mujoco.MjData(model)
    scratch.qpos[:] = cell.data.qpos
    mocap = model.body_mocapid[model.body(plate_body(config.name)).id]
    x, y, z, yaw = plan.plate
    scratch.mocap_pos[:] = PARKED
    scratch.mocap_pos[mocap] = np.array([x, y, z]) / MM
    scratch.mocap_quat[mocap] = [math.cos(math.radians(yaw) / 2), 0.0, 0.0, math.sin(math.radians(yaw) / 2)]
    qadr = cell.robot.qadr
    q = cell.robot_qpos()
    camera = Camera(config, model, calibration_targets=True)
    flanges, pixels, record = [], [], []
    try:
        for target in flange_poses(plan):
            q = kin.ik(target, q)
            scratch.qpos[qadr] = q
            mujoco.mj_forward(model, scratch)
            dots = find_plate(camera.shoot(scratch).gray)
            if dots is None:
                continue
            flange = kin.fk(q)  # what the controller knows: its kinematics of the joints
            flange[:3, 3] *= MM
            flanges.append(flange)
            pixels.append(dots)
            record.append({"flange_mm": flange.tolist(), "dots": len(dots)})
    finally:
        camera.close()
    return solve_hand_eye(flanges, pixels, plate_dots(plan), plan.plane_z, (config.width, config.height)), record


# ---------------------------------------------------------------------- the solve
def _unpack(p: np.ndarray, plate_z: float, size) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Parameters -> K, dist, camera in the flange frame (4x4), plate in the robot frame (4x4)."""
    w, h = size
    K = np.array([[p[0], 0.0, (w - 1) / 2], [0.0, p[0], (h - 1) / 2], [0.0, 0.0, 1.0]])
    dist = np.array([p[1], p[2], 0.0, 0.0, 0.0])
    X = np.eye(4)
    X[:3, :3] = cv2.Rodrigues(p[3:6])[0]
    X[:3, 3] = p[6:9]
    P = np.eye(4)
    P[:3, :3] = rot_z(p[11])
    P[:3, 3] = [p[9], p[10], plate_z]
    return K, dist, X, P


def _residuals(p, flanges, pixels, dots, plate_z, size) -> np.ndarray:
    K, dist, X, P = _unpack(p, plate_z, size)
    out = []
    for F, seen in zip(flanges, pixels):
        plate_in_cam = np.linalg.inv(F @ X) @ P
        rvec = cv2.Rodrigues(plate_in_cam[:3, :3])[0]
        projected, _ = cv2.projectPoints(dots, rvec, plate_in_cam[:3, 3], K, dist)
        out.append((projected.reshape(-1, 2) - seen).ravel())
    return np.concatenate(out)


def _levenberg_marquardt(fun, p0: np.ndarray, steps: np.ndarray) -> np.ndarray:
    """Minimise |fun(p)|^2 from p0 (forward-difference Jacobian with the given steps)."""
    p, lam = p0.astype(float), 1e-3
    r = fun(p)
    cost = r @ r
    for _ in range(LM_ITERATIONS):
        J = np.column_stack([(fun(p + np.eye(len(p))[k] * steps[k]) - r) / steps[k] for k in range(len(p))])
        A, g = J.T @ J, J.T @ r
        improved = False
        while lam < 1e12:
            dp = np.linalg.solve(A + lam * np.diag(np.diag(A) + 1e-12), -g)
            r_new = fun(p + dp)
            if r_new @ r_new < cost:
                p, r, lam, improved = p + dp, r_new, lam / 10, True
                break
            lam *= 10
        if not improved or abs(cost - r @ r) < 1e-14 * max(cost, 1.0):
            cost = r @ r
            break
        cost = r @ r
    return p


def _start(flanges, pixels, dots, plate_z, size) -> np.ndarray:
    """A first guess of the parameters (see the module docstring)."""
    w, h = size
    homographies = [cv2.findHomography(dots[:, :2], px)[0] for px in pixels]
    scale = np.array([math.sqrt(abs(np.linalg.det(H[:2, :2]))) / abs(H[2, 2]) for H in homographies])
    heights = np.array([F[2, 3] for F in flanges])
    slope, intercept = np.polyfit(heights, 1.0 / scale, 1)  # 1/scale = (z_flange + offset - plate_z) / f
    f = 1.0 / slope
    distance = heights + intercept * f - plate_z  # camera to plate along the optical axis, per picture
    centre_px = np.array([H @ [0.0, 0.0, 1.0] for H in homographies])
    centre_px = centre_px[:, :2] / centre_px[:, 2:]
    rays = np.column_stack([(centre_px[:, 0] - (w - 1) / 2) / f, (centre_px[:, 1] - (h - 1) / 2) / f,
                            np.ones(len(centre_px))]) * distance[:, None]
    best = None
    for deg in range(360):  # the camera's turn about its optical axis (along the flange's z)
        Xr = rot_z(math.radians(deg))
        rows, rhs = [], []
        for F, c in zip(flanges, rays):
            R, t = F[:3, :3], F[:3, 3]
            rows.append(np.column_stack([R, -np.eye(3)[:, :2]]))  # R Xt - (Px, Py, 0)
            rhs.append(np.array([0.0, 0.0, plate_z]) - R @ Xr @ c - t)
        A, b = np.vstack(rows), np.concatenate(rhs)
        sol, *_ = np.linalg.lstsq(A, b, rcond=None)
        err = float(np.sum((A @ sol - b) ** 2))
        if best is None or err < best[0]:
            best = (err, deg, sol)
    _, deg, sol = best
    Xr = rot_z(math.radians(deg))
    # The plate's yaw: its x axis as seen in each picture, carried into the robot frame.
    yaws = []
    for F, H in zip(flanges, homographies):
        a, b = H @ [0.0, 0.0, 1.0], H @ [10.0, 0.0, 1.0]
        d = b[:2] / b[2] - a[:2] / a[2]
        v = F[:3, :3] @ Xr @ np.array([d[0], d[1], 0.0])
        yaws.append(math.atan2(v[1], v[0]))
    yaw = math.atan2(np.mean(np.sin(yaws)), np.mean(np.cos(yaws)))
    return np.concatenate([[f, 0.0, 0.0], cv2.Rodrigues(Xr)[0].ravel(), sol[:3], sol[3:5], [yaw]])


def solve_hand_eye(flanges: list[np.ndarray], pixels: list[np.ndarray], dots: np.ndarray, plate_z: float,
                   size: tuple[int, int]) -> CameraModel:
    """Calibrate a camera on the robot from flange poses (4x4, mm, robot frame), the plate's
    dots found at each (N x 2 pixels, the grid's order), the dots' layout (N x 3 mm, plate
    frame) and the plate's top-face height in the robot frame."""
    if len(flanges) < 6:
        raise ValueError(f"hand-eye calibration needs at least 6 pictures of the whole plate, got {len(flanges)}")
    heights = [F[2, 3] for F in flanges]
    if np.ptp(heights) < 10.0:
        raise ValueError("hand-eye calibration needs flange heights at least 10 mm apart")
    dots = np.asarray(dots, dtype=np.float64)
    p0 = _start(flanges, pixels, dots, plate_z, size)
    steps = np.array([1e-2, 1e-5, 1e-5, 1e-6, 1e-6, 1e-6, 1e-4, 1e-4, 1e-4, 1e-4, 1e-4, 1e-6])
    p = _levenberg_marquardt(lambda v: _residuals(v, flanges, pixels, dots, plate_z, size), p0, steps)
    K, dist, X, P = _unpack(p, plate_z, size)
    model = CameraModel(K=K, dist=dist, R=np.eye(3), t=np.zeros(3), size=tuple(size), flange_T=X)
    r = _residuals(p, flanges, pixels, dots, plate_z, size).reshape(-1, 2)
    errors = []
    world_dots = (P @ np.column_stack([dots, np.ones(len(dots))]).T).T[:, :3]
    for F, seen in zip(flanges, pixels):
        at = model.at_flange(F)
        errors.append(np.linalg.norm(at.pixels_to_plane(seen, plate_z) - world_dots[:, :2], axis=1))
    errors = np.concatenate(errors)
    model.residual_px = float(np.sqrt(np.mean(np.sum(r ** 2, axis=1))))
    model.residual_mm = float(np.sqrt(np.mean(errors ** 2)))
    model.residual_max_mm = float(errors.max())
    model.points = int(len(errors))
    return model
