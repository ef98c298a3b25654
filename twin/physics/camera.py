"""The camera component: a ``[[camera]]`` of the cell file and its place in the MuJoCo model.

Conventions.  A camera's ``pose`` is the pose of its OpenCV optical frame (x right, y down
in the image, z along the optical axis), in V+ form [x, y, z mm, yaw, pitch, roll deg] with
R = Rz(yaw) Ry(pitch) Rz(roll): a camera looking straight down has pitch 180.  The pose is
in the world frame for a fixed camera, in the frame of the body named by ``mount`` for a
camera carried by the robot.  MuJoCo cameras look along their -z with y up, so the model
camera is the optical frame turned 180 degrees about x.

A camera may have a calibration plan (``[camera.calibration]``, twin/vision/calibrate.py):
the component adds the targets the robot sets down (visual only, they touch nothing).  The images themselves
are taken by twin/vision/camera.py.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import mujoco
import numpy as np

from ..errors import SceneError
from .components.base import CellContext, Component
from .geometry import MM, matrix_to_quat, vplus_to_matrix

# Optical frame (OpenCV) -> MuJoCo camera frame: 180 degrees about x.
_CV_TO_MJ = np.diag([1.0, -1.0, -1.0])


@dataclass(frozen=True)
class CameraConfig:
    """One ``[[camera]]`` of the cell file (lengths mm, angles deg)."""

    name: str
    resolution: tuple[int, int] = (640, 480)  # width, height in pixels
    focal_px: float | None = None  # focal length in pixels (square pixels) ...
    fov_deg: float | None = None  # ... or the vertical field of view
    pose: tuple[float, ...] = (0.0, 0.0, 1000.0, 0.0, 180.0, 0.0)
    mount: str | None = None  # body the camera is fixed to; None: the world
    distortion: tuple[float, ...] = (0.0, 0.0, 0.0, 0.0, 0.0)  # k1 k2 p1 p2 k3
    exposure: float = 1.0  # gain on the light reaching the sensor (before it saturates)
    noise: float = 0.0  # standard deviation of the image noise, grey levels
    seed: int = 0
    light: dict | None = None  # {pos = [x, y, z] mm world, diffuse = [r, g, b]}
    depth_range_mm: tuple[float, float] = (50.0, 5000.0)  # near and far clipping
    calibration: "TargetPlan | None" = None  # [camera.calibration]

    @property
    def width(self) -> int:
        return int(self.resolution[0])

    @property
    def height(self) -> int:
        return int(self.resolution[1])

    @property
    def focal(self) -> float:
        """Focal length in pixels."""
        if self.focal_px is not None:
            return float(self.focal_px)
        if self.fov_deg is not None:
            return (self.height / 2) / math.tan(math.radians(self.fov_deg) / 2)
        raise ValueError(f"camera {self.name!r}: give focal_px or fov_deg")

    @property
    def fovy_deg(self) -> float:
        return math.degrees(2 * math.atan((self.height / 2) / self.focal))

    def matrix(self) -> np.ndarray:
        """The nominal camera matrix K of the renderer (not known to the vision server,
        which uses its calibration)."""
        f = self.focal
        return np.array([[f, 0.0, (self.width - 1) / 2], [0.0, f, (self.height - 1) / 2],
                         [0.0, 0.0, 1.0]])

    @classmethod
    def from_table(cls, table: dict) -> "CameraConfig":
        known = {f for f in cls.__dataclass_fields__}
        unknown = sorted(set(table) - known)
        if unknown:
            raise ValueError(f"camera {table.get('name', '?')!r}: unknown key(s) {', '.join(unknown)}; "
                             f"expected {', '.join(sorted(known))}")
        values = dict(table)
        if "calibration" in values:
            values["calibration"] = TargetPlan.from_table(values["name"], values["calibration"])
        for key in ("resolution", "pose", "distortion", "depth_range_mm"):
            if key in values:
                values[key] = tuple(float(v) if key != "resolution" else int(v) for v in values[key])
        config = cls(**values)
        if len(config.pose) != 6:
            raise ValueError(f"camera {config.name!r}: pose must be [x, y, z, yaw, pitch, roll]")
        if len(config.distortion) != 5:
            raise ValueError(f"camera {config.name!r}: distortion must be [k1, k2, p1, p2, k3]")
        config.focal  # noqa: B018 (validates focal_px / fov_deg)
        return config


@dataclass(frozen=True)
class TargetPlan:
    """How the camera is calibrated (``[camera.calibration]``): the robot sets a target, a
    coloured disc on a post, down at every point of the grid ``x`` x ``y`` (robot frame,
    mm) on the work plane (robot-frame height ``plane_z``), once per post height in
    ``heights`` (mm; two or more, so the camera sees depth), and moves out of view before
    each picture.  ``file`` is where the result goes (relative to the cell file)."""

    file: str
    x: tuple[float, ...]
    y: tuple[float, ...]
    heights: tuple[float, ...] = (0.0, 60.0)
    plane_z: float = 0.0
    radius: float = 9.0  # mm
    rgba: tuple[float, ...] = (0.0, 1.0, 0.0, 1.0)
    hsv_low: tuple[int, int, int] = (45, 170, 60)  # OpenCV HSV range that finds it
    hsv_high: tuple[int, int, int] = (75, 255, 255)
    # Hand-eye plan of a camera on the robot (twin/vision/handeye.py): the dot plate's world
    # pose (x, y, z of the top face mm, yaw deg), the flange's yaws, the dots' pitch and radius.
    plate: tuple[float, ...] | None = None
    angles: tuple[float, ...] = (0.0,)
    pitch: float = 10.0
    dot_radius: float = 3.0

    @classmethod
    def from_table(cls, camera: str, table: dict) -> "TargetPlan":
        known = set(cls.__dataclass_fields__)
        unknown = sorted(set(table) - known)
        if unknown:
            raise ValueError(f"camera {camera!r} calibration: unknown key(s) {', '.join(unknown)}; "
                             f"expected {', '.join(sorted(known))}")
        values = {k: (tuple(v) if isinstance(v, list) else v) for k, v in table.items()}
        plan = cls(**values)
        if len(plan.heights) < 2 or min(plan.heights) < 1.0:
            raise ValueError(f"camera {camera!r} calibration: heights needs two post heights "
                             f"or more, each at least 1 mm (got {list(plan.heights)})")
        return plan


PARKED = (0.0, 0.0, -2.0)  # m: where calibration targets wait, under the floor
# The geom group of the calibration targets and the hand-eye plate: only the calibration
# routines' pictures draw it.  Parked under the floor they cannot be seen, yet drawing their
# 48 cylinders was a third of every picture's rendering (MuJoCo's viewer and the recorder
# draw groups 0-2, so they leave them out too).
CALIBRATION_GROUP = 5
DISC_THICKNESS = 0.0004  # m


def target_body(camera: str, k: int) -> str:
    return f"camera/{camera}/target{k}"


def add_targets(spec: mujoco.MjSpec, config: CameraConfig) -> None:
    """One calibration target per post height: a mocap body (the calibration routine sets
    its pose) with a grey post and the coloured disc on top, visual only (no contacts)."""
    plan = config.calibration
    matte = spec.add_material(name=f"camera/{config.name}/matte", specular=0.0, shininess=0.0,
                              rgba=list(plan.rgba))
    for k, h in enumerate(plan.heights):
        body = spec.worldbody.add_body(name=target_body(config.name, k), mocap=True, pos=list(PARKED))
        post = float(h) / MM - DISC_THICKNESS  # the disc's top face is at the post height
        body.add_geom(type=mujoco.mjtGeom.mjGEOM_CYLINDER, size=[plan.radius * 1.6 / MM, post / 2, 0],
                      pos=[0, 0, post / 2], rgba=[0.3, 0.3, 0.32, 1], contype=0, conaffinity=0,
                      group=CALIBRATION_GROUP)
        body.add_geom(type=mujoco.mjtGeom.mjGEOM_CYLINDER, size=[plan.radius / MM, DISC_THICKNESS / 2, 0],
                      pos=[0, 0, post + DISC_THICKNESS / 2], material=matte.name, contype=0, conaffinity=0,
                      group=CALIBRATION_GROUP)


PLATE_GRID = (4, 11)  # OpenCV's asymmetric circles grid: dots per row, rows
PLATE_THICKNESS = 0.001  # m


def plate_body(camera: str) -> str:
    return f"camera/{camera}/plate"


def plate_dots(plan: "TargetPlan") -> np.ndarray:
    """The dot centres of the hand-eye plate in its own frame (mm, z 0 on the top face, up;
    the origin at the grid's centre), in the order cv2.findCirclesGrid reports them.  OpenCV
    numbers a grid seen from the front with its rows down the board and its z into it, away
    from the camera: with z up, the rows run along -y."""
    cols, rows = PLATE_GRID
    s = plan.pitch
    pts = np.array([[(2 * j + i % 2) * s, -i * s] for i in range(rows) for j in range(cols)], dtype=float)
    pts -= (pts.min(axis=0) + pts.max(axis=0)) / 2
    return np.column_stack([pts, np.zeros(len(pts))])


def add_plate(spec: mujoco.MjSpec, config: CameraConfig) -> None:
    """The hand-eye routine's plate: white, with the grid's dark dots, visual only; a mocap
    body parked under the floor until the routine lays it at ``plate``."""
    plan = config.calibration
    dots = plate_dots(plan) / MM
    half = (np.ptp(dots[:, :2], axis=0) / 2 + 2.5 * plan.dot_radius / MM)
    body = spec.worldbody.add_body(name=plate_body(config.name), mocap=True, pos=list(PARKED))
    white = spec.add_material(name=f"camera/{config.name}/plate_white", specular=0.0, shininess=0.0,
                              rgba=[0.92, 0.92, 0.9, 1])
    body.add_geom(type=mujoco.mjtGeom.mjGEOM_BOX, size=[half[0], half[1], PLATE_THICKNESS / 2],
                  pos=[0, 0, -PLATE_THICKNESS / 2], material=white.name, contype=0, conaffinity=0,
                  group=CALIBRATION_GROUP)
    for x, y, _ in dots:
        body.add_geom(type=mujoco.mjtGeom.mjGEOM_CYLINDER, size=[plan.dot_radius / MM, DISC_THICKNESS / 2, 0],
                      pos=[x, y, 0.00005 - DISC_THICKNESS / 2], rgba=[0.05, 0.05, 0.06, 1],
                      contype=0, conaffinity=0,
                      group=CALIBRATION_GROUP)  # flush with the top face (0.05 mm proud: drawn over it)


def add_camera(spec: mujoco.MjSpec, config: CameraConfig, scene_path: str | None = None) -> None:
    """Add the camera (its light, its calibration target) to a model being built; enlarge
    the offscreen buffer."""
    T = vplus_to_matrix(config.pose)
    parent = spec.worldbody if config.mount is None else spec.body(config.mount)
    if parent is None:
        raise SceneError(f"camera {config.name!r}: mount: {config.mount!r}: no body of that name to mount it on",
                         file=scene_path)
    parent.add_camera(name=f"camera/{config.name}", pos=T[:3, 3],
                      quat=matrix_to_quat(T[:3, :3] @ _CV_TO_MJ), fovy=config.fovy_deg)
    if config.light is not None:
        light = config.light
        spec.worldbody.add_light(name=f"camera/{config.name}/light",
                                 pos=np.array(light["pos"], dtype=float) / MM, dir=[0, 0, -1],
                                 diffuse=light.get("diffuse", [0.5, 0.5, 0.5]), castshadow=False)
    if config.calibration is not None and config.calibration.plate is not None:
        add_plate(spec, config)
    elif config.calibration is not None:
        add_targets(spec, config)
    vis = spec.visual.global_
    vis.offwidth = max(vis.offwidth, config.width)
    vis.offheight = max(vis.offheight, config.height)


# ---------------------------------------------------------------------- the component
# The cell file's tables are validated with the rest of the scene (schema.py: CameraSection).


class Camera(Component):
    """A camera of the cell: its model camera, light and calibration targets."""

    section = "camera"

    def __init__(self, config, ctx: CellContext):
        """`config`: the scene's validated CameraSection."""
        super().__init__(config, ctx)
        self.camera = CameraConfig.from_table(config.model_dump(exclude_none=True))

    def build(self, spec: mujoco.MjSpec, ctx: CellContext) -> None:
        add_camera(spec, self.camera, str(ctx.scene_path))


def cameras_of(cell) -> list[CameraConfig]:
    """The cameras of a built cell."""
    return [c.camera for c in cell.ctx.by_kind.get("camera", {}).values()]
