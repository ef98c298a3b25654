"""A metric top view: the camera image resampled onto a horizontal plane of the robot frame.

The vision tools work here rather than on raw pixels: through the calibration, view pixel
(column c, row r) is robot point (x0 + c * scale, y0 + r * scale) on the plane z, so lens
distortion and perspective are gone, lengths are millimetres and an angle measured in the
view (atan2 of rows over columns) is a yaw in the robot frame.  Built once per (camera
model, plane, area, scale) and reused: a remap of the grey image costs a few milliseconds.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import cv2
import numpy as np

from .calibration import CameraModel

GRID = 8  # view pixels between exactly projected points
EDGE_PX = 3  # image pixels at the border not trusted to show the scene


@dataclass
class PlaneView:
    camera: CameraModel
    z: float  # mm, robot frame
    lo: tuple[float, float]  # robot x, y of the view's first pixel, mm
    hi: tuple[float, float]
    scale: float = 0.25  # mm per view pixel
    _maps: tuple[np.ndarray, np.ndarray] | None = field(default=None, repr=False)
    _unseen: np.ndarray | None = field(default=None, repr=False)

    @property
    def shape(self) -> tuple[int, int]:
        """Rows, columns."""
        return (int(round((self.hi[1] - self.lo[1]) / self.scale)) + 1,
                int(round((self.hi[0] - self.lo[0]) / self.scale)) + 1)

    def maps(self) -> tuple[np.ndarray, np.ndarray]:
        """Where each view pixel is in the camera image: projected exactly on a grid of every
        GRID-th view pixel, bilinear in between (the lens model is smooth: the difference is
        under a thousandth of a pixel, and the full projection costs a second)."""
        if self._maps is None:
            rows, cols = self.shape
            gr, gc = np.arange(0, rows + GRID, GRID), np.arange(0, cols + GRID, GRID)
            c, r = np.meshgrid(gc, gr)
            xy = np.stack([self.lo[0] + c.ravel() * self.scale, self.lo[1] + r.ravel() * self.scale], axis=1)
            px = self.camera.plane_to_pixels(xy, self.z).reshape(len(gr), len(gc), 2)
            # Bilinear upsampling that keeps grid nodes at exact multiples of GRID.
            fine_r, fine_c = np.arange(rows) / GRID, np.arange(cols) / GRID
            full = [cv2.remap(px[..., k].astype(np.float32), *np.meshgrid(fine_c.astype(np.float32), fine_r.astype(np.float32)),
                              cv2.INTER_LINEAR) for k in range(2)]
            self._maps = (full[0], full[1])
        return self._maps

    def resample(self, gray: np.ndarray) -> np.ndarray:
        """The view of a grey image (outside the picture: 0)."""
        return cv2.remap(gray, *self.maps(), cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT, borderValue=0)

    def unseen(self) -> np.ndarray:
        """Boolean mask of the view pixels the picture does not cover: outside the image or
        within EDGE_PX of its border (the lens remap leaves the outermost pixels black),
        grown by one view pixel: a blob that touches it is cut by the picture's edge."""
        if self._unseen is None:
            mx, my = self.maps()
            w, h = self.camera.size
            e = EDGE_PX
            outside = ((mx < e) | (my < e) | (mx > w - 1 - e) | (my > h - 1 - e)).astype(np.uint8)
            self._unseen = cv2.dilate(outside, np.ones((3, 3), np.uint8)).astype(bool)
        return self._unseen

    def to_robot(self, cr: np.ndarray) -> np.ndarray:
        """View (column, row) points -> robot (x, y) mm."""
        cr = np.asarray(cr, dtype=np.float64).reshape(-1, 2)
        return np.array(self.lo) + cr * self.scale

    def to_image(self, cr: np.ndarray) -> np.ndarray:
        """View (column, row) points -> camera image pixels (for drawing on the picture)."""
        return self.camera.plane_to_pixels(self.to_robot(cr), self.z)
