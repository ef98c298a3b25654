"""The images a camera takes: RGB and depth, rendered headless by MuJoCo on the CPU.

An image is taken only when asked (a vision process, the recorder): nothing renders per
step.  The renderer is a pinhole with square pixels and the principal point at the image
centre.  The exposure scales every light of the scene as the camera renders it (the light
that reaches the sensor, before it saturates); lens distortion (OpenCV's k1, k2, p1, p2,
k3 model) is applied to the rendered image with ``cv2.remap``, then seeded Gaussian
noise.  The noise of a frame is a window of a bank of Gaussian draws (each rounded to a
grey level) made once per camera from ``default_rng(seed)``, at an offset drawn for frame
n from ``default_rng([seed, n])``: the same run gives the same images bit for bit, each
pixel's noise is N(0, noise) as if drawn for it, and a pixel takes a different draw in
each frame (the pattern repeats across frames only shifted).  Drawing a frame's 921,600
normals was 10-13 ms a frame on the CPU, the window 0.3 ms.  Headless rendering needs
``MUJOCO_GL=egl`` (Mesa llvmpipe on a machine without a GPU) or ``MUJOCO_GL=osmesa``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import cv2
import mujoco
import numpy as np

from ..physics.camera import CALIBRATION_GROUP, CameraConfig
from ..physics.geometry import MM


@dataclass
class Image:
    """One picture: RGB (height x width x 3, uint8), depth (mm, float32, along the optical
    axis) when asked for, the simulated time it was taken and its frame number."""

    rgb: np.ndarray
    time: float
    frame: int
    depth: np.ndarray | None = None

    @property
    def gray(self) -> np.ndarray:
        return cv2.cvtColor(self.rgb, cv2.COLOR_RGB2GRAY)


@dataclass
class Camera:
    """The renderer of one camera of a compiled model.  ``shoot`` takes a picture of the
    cell as it is in ``data``; the MuJoCo renderer is created by the first picture."""

    config: CameraConfig
    model: mujoco.MjModel
    calibration_targets: bool = False  # draw the calibration targets and plate (the routines' own pictures)
    frames: int = 0
    _renderer: mujoco.Renderer | None = field(default=None, repr=False)
    _depth: mujoco.Renderer | None = field(default=None, repr=False)
    _distort_map: tuple[np.ndarray, np.ndarray] | None = field(default=None, repr=False)
    _noise: tuple[np.ndarray, np.ndarray] | None = field(default=None, repr=False)  # bank, sum (reused)
    _option: mujoco.MjvOption = field(default_factory=mujoco.MjvOption, repr=False)

    def __post_init__(self) -> None:
        self._option.geomgroup[CALIBRATION_GROUP] = self.calibration_targets

    @property
    def model_name(self) -> str:
        return f"camera/{self.config.name}"

    def _renderers(self, depth: bool) -> tuple[mujoco.Renderer, mujoco.Renderer | None]:
        c = self.config
        if self._renderer is None:
            near, far = c.depth_range_mm
            extent = float(self.model.stat.extent)
            self.model.vis.map.znear = near / MM / extent
            self.model.vis.map.zfar = far / MM / extent
            self._renderer = mujoco.Renderer(self.model, c.height, c.width)
        if depth and self._depth is None:
            self._depth = mujoco.Renderer(self.model, c.height, c.width)
            self._depth.enable_depth_rendering()
        return self._renderer, self._depth

    def shoot(self, data: mujoco.MjData, depth: bool = False) -> Image:
        """Render a picture now (the simulated time is ``data.time``)."""
        rgb_renderer, depth_renderer = self._renderers(depth)
        self._update(rgb_renderer, data)
        rgb = rgb_renderer.render()
        depth_mm = None
        if depth:
            self._update(depth_renderer, data)
            depth_mm = (depth_renderer.render() * MM).astype(np.float32)
        rgb = self._develop(rgb)
        if depth_mm is not None and self._lens() is not None:
            depth_mm = cv2.remap(depth_mm, *self._lens(), cv2.INTER_NEAREST)
        image = Image(rgb=rgb, time=float(data.time), frame=self.frames, depth=depth_mm)
        self.frames += 1
        return image

    def _update(self, renderer: mujoco.Renderer, data: mujoco.MjData) -> None:
        """The scene as this camera sees it, without shadows: the cell light's shadow map
        costs about 0.25 s a frame on llvmpipe (23 ms without), and a vision cell's lights
        are diffuse anyway."""
        renderer.update_scene(data, camera=self.model_name, scene_option=self._option)
        scene = renderer.scene
        scene.flags[mujoco.mjtRndFlag.mjRND_SHADOW] = 0
        gain = float(self.config.exposure)
        if gain != 1.0:  # exposure: all light reaching the sensor scales, before it clips
            for light in scene.lights[:scene.nlight]:
                light.ambient = np.asarray(light.ambient) * gain
                light.diffuse = np.asarray(light.diffuse) * gain
                light.specular = np.asarray(light.specular) * gain

    def _lens(self) -> tuple[np.ndarray, np.ndarray] | None:
        """Remap tables that distort a pinhole image: for each pixel of the distorted
        image, where its ray lands in the pinhole image (None without distortion)."""
        c = self.config
        if not any(c.distortion):
            return None
        if self._distort_map is None:
            K = c.matrix()
            u, v = np.meshgrid(np.arange(c.width, dtype=np.float64), np.arange(c.height, dtype=np.float64))
            pixels = np.stack([u.ravel(), v.ravel()], axis=1).reshape(-1, 1, 2)
            ideal = cv2.undistortPoints(pixels, K, np.array(c.distortion), None, K,
                                            criteria=(cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 20, 1e-6))
            ideal = ideal.reshape(c.height, c.width, 2).astype(np.float32)
            self._distort_map = (ideal[..., 0].copy(), ideal[..., 1].copy())
        return self._distort_map

    def _develop(self, rgb: np.ndarray) -> np.ndarray:
        """Lens and sensor noise on a rendered picture."""
        c = self.config
        lens = self._lens()
        if lens is not None:
            rgb = cv2.remap(rgb, *lens, cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT)
        if c.noise == 0.0:
            return rgb
        # rgb is integer, so rgb + rint(n * noise) is the rint(rgb + n * noise) of fresh draws.
        size = rgb.size
        if self._noise is None:
            draws = np.random.default_rng(int(c.seed)).standard_normal(2 * size, dtype=np.float32)
            draws *= np.float32(c.noise)
            self._noise = (np.rint(draws).astype(np.int16), np.empty(size, np.int16))
        bank, total = self._noise
        offset = int(np.random.default_rng([int(c.seed), self.frames]).integers(size + 1))
        np.add(rgb.reshape(-1), bank[offset:offset + size], out=total)
        np.clip(total, 0, 255, out=total)
        return total.astype(np.uint8).reshape(rgb.shape)

    def close(self) -> None:
        for renderer in (self._renderer, self._depth):
            if renderer is not None:
                renderer.close()
        self._renderer = self._depth = None
