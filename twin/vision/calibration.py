"""Camera-to-robot calibration from images only, and the camera model it produces.

The routine is the one of a real cell with a fixed camera: the robot carries a target (a
coloured disc on its tool, at a known offset from the flange) to a grid of poses at two or
more heights; at each pose the camera takes a picture and the target's centre is found in
it (colour threshold, sub-pixel centroid).  The target's 3-D position in the robot frame is
what the robot's controller knows: its forward kinematics of the joint positions, plus the
target's offset.  Nothing is read from the simulator but the pictures.

From the correspondences (3-D point in the robot frame, pixel) OpenCV's ``calibrateCamera``
estimates the focal length (pixels, square pixels), the radial and tangential distortion
(k1, k2, p1, p2) and the camera pose in the robot frame, starting from a direct linear
transform.  The principal point is estimated too when the sightings pin it down (its
standard deviation from the fit within PRINCIPAL_STD_PX); otherwise it is held at the image
centre (one view of targets at a few heights often does not: the principal point trades
off against the camera's tilt; a plate tilted in front of the camera would pin it, which a
SCARA cannot do).  The residual is reported both in pixels
(reprojection) and in millimetres: each observed pixel is cast back onto the horizontal
plane of its target and compared with where the robot put the target.

The result is a JSON file (``save`` / ``load``) that the vision server reads at start.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np

PRINCIPAL_STD_PX = 1.5  # the principal point is estimated when known this well (1 sigma, pixels)


@dataclass
class CameraModel:
    """A calibrated camera: intrinsics ``K`` (3x3), ``dist`` (k1 k2 p1 p2 k3) and the pose of
    the robot frame in the camera frame (``R``, ``t`` in mm), for images of ``size``
    (width, height).  Converts pixels to robot coordinates on a horizontal plane."""

    K: np.ndarray
    dist: np.ndarray
    R: np.ndarray
    t: np.ndarray
    size: tuple[int, int]
    residual_mm: float = 0.0
    residual_max_mm: float = 0.0
    residual_px: float = 0.0
    points: int = 0
    flange_T: np.ndarray | None = None  # a camera on the robot: its pose in the flange frame (4x4, mm)
    principal: str = "held"  # the principal point: "estimated", or "held" at the image centre
    principal_std_px: tuple[float, float] | None = None  # its standard deviations as estimated

    def at_flange(self, flange_mm: np.ndarray) -> "CameraModel":
        """A camera on the robot with the flange at `flange_mm` (4x4 in the robot frame, mm):
        the same camera with R, t of that moment."""
        cam = np.asarray(flange_mm, dtype=float) @ self.flange_T  # camera -> robot
        R = cam[:3, :3].T
        return CameraModel(K=self.K, dist=self.dist, R=R, t=-R @ cam[:3, 3], size=self.size,
                           residual_mm=self.residual_mm, residual_max_mm=self.residual_max_mm,
                           residual_px=self.residual_px, points=self.points, flange_T=self.flange_T,
                           principal=self.principal, principal_std_px=self.principal_std_px)

    @property
    def center_mm(self) -> np.ndarray:
        """The camera's optical centre in the robot frame, mm."""
        return -self.R.T @ self.t

    def pixels_to_plane(self, pixels: np.ndarray, z_mm: float) -> np.ndarray:
        """Image points (N x 2, distorted pixel coordinates) -> robot (x, y) on the plane z."""
        pixels = np.asarray(pixels, dtype=np.float64).reshape(-1, 1, 2)
        rays = cv2.undistortPoints(pixels, self.K, self.dist, None, None,
                                       criteria=(cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 30, 1e-9))
        rays = np.concatenate([rays.reshape(-1, 2), np.ones((len(rays), 1))], axis=1)
        world = rays @ self.R  # each ray's direction in the robot frame (R.T @ ray)
        c = self.center_mm
        s = (z_mm - c[2]) / world[:, 2]
        return c[:2] + world[:, :2] * s[:, None]

    def plane_to_pixels(self, xy_mm: np.ndarray, z_mm: float) -> np.ndarray:
        """Robot (x, y) on the plane z -> image points (N x 2): OpenCV's camera model
        (radial k1 k2 k3, tangential p1 p2), vectorised for whole view grids."""
        xy = np.asarray(xy_mm, dtype=np.float64).reshape(-1, 2)
        cam = xy @ self.R[:, :2].T + (self.R[:, 2] * z_mm + self.t)
        xn, yn = cam[:, 0] / cam[:, 2], cam[:, 1] / cam[:, 2]
        k1, k2, p1, p2, k3 = (list(self.dist) + [0.0] * 5)[:5]
        r2 = xn * xn + yn * yn
        radial = 1 + r2 * (k1 + r2 * (k2 + r2 * k3))
        xd = xn * radial + 2 * p1 * xn * yn + p2 * (r2 + 2 * xn * xn)
        yd = yn * radial + p1 * (r2 + 2 * yn * yn) + 2 * p2 * xn * yn
        K = self.K
        return np.stack([K[0, 0] * xd + K[0, 1] * yd + K[0, 2], K[1, 1] * yd + K[1, 2]], axis=1)

    def to_dict(self) -> dict:
        return {"K": self.K.tolist(), "dist": self.dist.tolist(), "R": self.R.tolist(),
                "t_mm": self.t.tolist(), "size": list(self.size),
                "residual_mm": self.residual_mm, "residual_max_mm": self.residual_max_mm,
                "residual_px": self.residual_px, "points": self.points, "principal": self.principal,
                **({} if self.principal_std_px is None else {"principal_std_px": list(self.principal_std_px)}),
                **({} if self.flange_T is None else {"flange_T_mm": self.flange_T.tolist()})}

    def save(self, path: str | Path) -> None:
        Path(path).write_text(json.dumps(self.to_dict(), indent=1) + "\n")

    @classmethod
    def load(cls, path: str | Path) -> "CameraModel":
        d = json.loads(Path(path).read_text())
        return cls(K=np.array(d["K"]), dist=np.array(d["dist"]), R=np.array(d["R"]),
                   t=np.array(d["t_mm"]), size=tuple(d["size"]), residual_mm=d["residual_mm"],
                   residual_max_mm=d["residual_max_mm"], residual_px=d["residual_px"],
                   points=d["points"], flange_T=np.array(d["flange_T_mm"]) if "flange_T_mm" in d else None,
                   principal=d.get("principal", "held"),
                   principal_std_px=tuple(d["principal_std_px"]) if "principal_std_px" in d else None)


def find_target(rgb: np.ndarray, hsv_low, hsv_high, min_area_px: float = 20.0) -> np.ndarray | None:
    """Centre (u, v) of the largest blob of the target colour: the centroid of its outer
    contour, filled (a highlight inside does not move it); None when the target is not in
    the picture or is cut by the image border."""
    hsv = cv2.cvtColor(rgb, cv2.COLOR_RGB2HSV)
    mask = cv2.inRange(hsv, np.array(hsv_low, np.uint8), np.array(hsv_high, np.uint8))
    contours, _ = cv2.findContours(mask, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_NONE)
    if not contours:
        return None
    best = max(contours, key=cv2.contourArea)
    x, y, w, h = cv2.boundingRect(best)
    height, width = mask.shape
    if cv2.contourArea(best) < min_area_px or x <= 2 or y <= 2 or x + w >= width - 2 or y + h >= height - 2:
        return None
    m = cv2.moments(best.astype(np.float32))
    return np.array([m["m10"] / m["m00"], m["m01"] / m["m00"]])


def _dlt_guess(points: np.ndarray, pixels: np.ndarray, size: tuple[int, int]) -> np.ndarray:
    """A first camera matrix from the direct linear transform of non-coplanar points,
    with the principal point put at the image centre."""
    rows = []
    for (X, Y, Z), (u, v) in zip(points, pixels):
        rows.append([X, Y, Z, 1, 0, 0, 0, 0, -u * X, -u * Y, -u * Z, -u])
        rows.append([0, 0, 0, 0, X, Y, Z, 1, -v * X, -v * Y, -v * Z, -v])
    _, _, vt = np.linalg.svd(np.array(rows))
    P = vt[-1].reshape(3, 4)
    K, _, _, _, _, _, _ = cv2.decomposeProjectionMatrix(P)
    K = K / K[2, 2]
    f = (abs(K[0, 0]) + abs(K[1, 1])) / 2
    w, h = size
    return np.array([[f, 0, (w - 1) / 2], [0, f, (h - 1) / 2], [0, 0, 1.0]])


def solve(points_mm: np.ndarray, pixels: np.ndarray, size: tuple[int, int]) -> CameraModel:
    """Calibrate from target positions in the robot frame (N x 3, mm, at two heights or
    more) and where the target was seen (N x 2 pixels)."""
    points = np.asarray(points_mm, dtype=np.float64)
    pixels = np.asarray(pixels, dtype=np.float64)
    if len(points) < 8:
        raise ValueError(f"calibration needs at least 8 target sightings, got {len(points)}")
    if np.ptp(points[:, 2]) < 1.0:
        raise ValueError("calibration needs target poses at two heights or more")
    K0 = _dlt_guess(points, pixels, size)
    flags = cv2.CALIB_USE_INTRINSIC_GUESS | cv2.CALIB_FIX_ASPECT_RATIO | cv2.CALIB_FIX_K3
    criteria = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 200, 1e-12)
    views = ([points.astype(np.float32)], [pixels.astype(np.float32).reshape(-1, 1, 2)])
    # The principal point too, when the sightings pin it down (its standard deviation, from
    # the fit's covariance, within PRINCIPAL_STD_PX); otherwise held at the image centre.
    rms, K, dist, rvecs, tvecs, std, _, _ = cv2.calibrateCameraExtended(*views, size, K0.copy(), np.zeros(5),
                                                                        flags=flags, criteria=criteria)
    principal_std = (float(std[2, 0]), float(std[3, 0]))
    principal = "estimated"
    if max(principal_std) > PRINCIPAL_STD_PX or not np.all(np.isfinite(principal_std)):
        principal = "held"
        rms, K, dist, rvecs, tvecs = cv2.calibrateCamera(*views, size, K0, np.zeros(5),
                                                         flags=flags | cv2.CALIB_FIX_PRINCIPAL_POINT,
                                                         criteria=criteria)
    R, _ = cv2.Rodrigues(rvecs[0])
    model = CameraModel(K=K, dist=dist.ravel(), R=R, t=tvecs[0].ravel(), size=tuple(size),
                        principal=principal, principal_std_px=principal_std)
    errors = np.array([np.linalg.norm(model.pixels_to_plane(px, p[2])[0] - p[:2])
                       for p, px in zip(points, pixels)])
    model.residual_mm = float(np.sqrt(np.mean(errors ** 2)))
    model.residual_max_mm = float(errors.max())
    model.residual_px = float(rms)
    model.points = len(points)
    return model
