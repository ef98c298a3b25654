"""The calibration routine of a fixed camera (``twin calibrate``): the robot sets the
calibration targets down on the grid of ``[camera.calibration]``, the camera takes a
picture of each, and ``calibration.solve`` fits the camera model.  A camera on the robot
(``mount``) is calibrated hand-eye instead (twin/vision/handeye.py).

The twin performs the robot's part by putting each target where the robot would set it
down (the commanded grid point, robot frame, carried into the world by the robot's base
pose: the physical act, not information given to the vision side), with the robot left
where it stands, out of the camera's view.  The vision side gets only the pictures and
the grid points in robot coordinates, as on a real cell.
"""

from __future__ import annotations

from pathlib import Path

import mujoco
import numpy as np

from ..physics.camera import PARKED, CameraConfig, cameras_of, target_body
from ..physics.geometry import MM
from .calibration import CameraModel, find_target, solve
from .camera import Camera


def calibration_file(config: CameraConfig, scene_path: Path) -> Path:
    return (Path(scene_path).parent / config.calibration.file).resolve()


def calibrate(model: mujoco.MjModel, data: mujoco.MjData, config: CameraConfig,
              base_pose: np.ndarray) -> tuple[CameraModel, list[dict]]:
    """Run the plan on a copy of the cell's state; returns the camera model and one entry per
    sighting (robot point mm, pixel) for the record.  Raises ValueError when the plan has
    too few sightings."""
    plan = config.calibration
    if plan is None:
        raise ValueError(f"camera {config.name!r} has no [camera.calibration] plan")
    scratch = mujoco.MjData(model)
    scratch.qpos[:] = data.qpos
    scratch.time = data.time
    camera = Camera(config, model, calibration_targets=True)
    mocap = [model.body_mocapid[model.body(target_body(config.name, k)).id] for k in range(len(plan.heights))]
    points, pixels, record = [], [], []
    try:
        for k, height in enumerate(plan.heights):
            for x in plan.x:
                for y in plan.y:
                    robot_point = np.array([x, y, plan.plane_z + height])
                    world = base_pose[:3, :3] @ (robot_point / MM) + base_pose[:3, 3]
                    scratch.mocap_pos[:] = PARKED
                    scratch.mocap_pos[mocap[k]] = world - [0, 0, height / MM]  # the post stands on the plane
                    mujoco.mj_forward(model, scratch)
                    image = camera.shoot(scratch)
                    pixel = find_target(image.rgb, plan.hsv_low, plan.hsv_high)
                    if pixel is None:
                        continue
                    points.append(robot_point)
                    pixels.append(pixel)
                    record.append({"robot_mm": robot_point.tolist(), "pixel": pixel.tolist()})
    finally:
        camera.close()
    result = solve(np.array(points), np.array(pixels), (config.width, config.height))
    return result, record


def calibrate_scene(scene_path: str | Path, camera: str | None = None) -> list[tuple[CameraConfig, CameraModel, Path]]:
    """``twin calibrate``: calibrate every camera of a cell file that has a plan (or the
    one named), write each result to its plan's file; returns (camera, model, file)."""
    from ..physics.cell import Cell

    cell = Cell.from_scene(scene_path)
    done = []
    for config in cameras_of(cell):
        if config.calibration is None or (camera is not None and config.name != camera):
            continue
        if (config.calibration.plate is None) != (config.mount is None):
            raise ValueError(f"{scene_path}: camera {config.name!r} calibration: " + (
                "a camera on the robot (mount) is calibrated hand-eye: give plate = [x, y, z, yaw]"
                if config.calibration.plate is None else "plate is the hand-eye plan of a camera on the robot "
                                                         "(give mount)"))
        if config.mount is not None:  # a camera on the robot: hand-eye, over the plate
            from .handeye import calibrate_hand_eye

            model, _ = calibrate_hand_eye(cell, config)
        else:
            model, _ = calibrate(cell.model, cell.data, config, cell.robot_base_pose())
        path = calibration_file(config, Path(scene_path))
        model.save(path)
        done.append((config, model, path))
    if not done:
        raise ValueError(f"{scene_path}: no camera with a [camera.calibration] plan"
                         + (f" named {camera!r}" if camera else ""))
    return done
