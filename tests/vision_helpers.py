"""A small vision bench for the tests: a dark table, a top light, a calibrated camera looking
down, and flat parts at seeded poses (no robot: the world frame is the robot frame)."""

from __future__ import annotations

import math
from pathlib import Path

import mujoco
import numpy as np

from twin.physics.camera import CameraConfig, TargetPlan, add_camera
from twin.physics.geometry import MM, yaw_quat

REPO = Path(__file__).resolve().parent.parent
PLATE = REPO / "models" / "parts" / "chamfered_plate.obj"
PLATE_OUTLINE = [[-20, -12], [20, -12], [20, 0], [8, 12], [-20, 12]]  # mm, as in the OBJ
PLATE_HEIGHT = 8.0  # mm

CAMERA = CameraConfig(
    name="top", resolution=(640, 480), focal_px=1250.0, pose=(0.0, 0.0, 650.0, 90.0, 180.0, 0.0),
    distortion=(-0.08, 0.02, 0.0, 0.0, 0.0), noise=2.0, seed=7,
    calibration=TargetPlan(file="unused.json", x=(-120.0, -60.0, 0.0, 60.0, 120.0),
                           y=(-90.0, -45.0, 0.0, 45.0, 90.0), heights=(5.0, 80.0)))


def plate_layout(seed: int, count: int = 5, flipped: tuple[int, ...] = (),
                 keep_clear: tuple[tuple[float, float], ...] = ()) -> list[tuple[float, float, float, bool]]:
    """Seeded non-overlapping plate poses (x, y mm, yaw deg, upside down) inside the view,
    away from the points of keep_clear."""
    rng = np.random.default_rng(seed)
    poses: list[tuple[float, float, float, bool]] = [(x, y, 0.0, False) for x, y in keep_clear]
    while len(poses) < count + len(keep_clear):
        x, y = rng.uniform(-90, 90), rng.uniform(-120, 120)
        if all(math.hypot(x - p[0], y - p[1]) > 55 for p in poses):
            poses.append((float(x), float(y), float(rng.uniform(-180, 180)), len(poses) - len(keep_clear) in flipped))
    return poses[len(keep_clear):]


def build_bench(poses, camera: CameraConfig = CAMERA, extra_boxes=()) -> tuple[mujoco.MjModel, mujoco.MjData]:
    """The bench with one plate per pose and, for each (x, y, yaw, size) in extra_boxes, a
    box part of another type."""
    spec = mujoco.MjSpec()
    spec.visual.headlight.ambient = [0.3, 0.3, 0.3]
    spec.visual.headlight.diffuse = [0.2, 0.2, 0.2]
    wb = spec.worldbody
    spec.add_material(name="matte", specular=0.0, shininess=0.0, rgba=[0.12, 0.12, 0.14, 1])
    wb.add_geom(name="table", type=mujoco.mjtGeom.mjGEOM_PLANE, size=[1, 1, 0.05], material="matte")
    wb.add_light(name="top_light", pos=[0, 0, 1.5], dir=[0, 0, -1], diffuse=[0.45, 0.45, 0.45], castshadow=False)
    spec.add_mesh(name="plate", file=str(PLATE), scale=[1 / MM] * 3)
    for k, (x, y, yaw, flipped) in enumerate(poses):
        body = wb.add_body(name=f"plate{k}", pos=[x / MM, y / MM, PLATE_HEIGHT / 2 / MM])
        q = yaw_quat(math.radians(yaw))
        if flipped:
            qx = np.zeros(4)
            mujoco.mju_mulQuat(qx, q, np.array([0.0, 1.0, 0.0, 0.0]))
            q = qx
        body.quat = q
        body.add_geom(type=mujoco.mjtGeom.mjGEOM_MESH, meshname="plate", rgba=[0.85, 0.8, 0.7, 1])
    for k, (x, y, yaw, size) in enumerate(extra_boxes):
        body = wb.add_body(name=f"box{k}", pos=[x / MM, y / MM, size[2] / 2 / MM], quat=yaw_quat(math.radians(yaw)))
        body.add_geom(type=mujoco.mjtGeom.mjGEOM_BOX, size=np.array(size) / 2 / MM, rgba=[0.85, 0.8, 0.7, 1])
    add_camera(spec, camera)
    model = spec.compile()
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    return model, data
