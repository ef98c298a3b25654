"""The simulated camera: headless RGB and depth, lens distortion, exposure, seeded noise."""

from __future__ import annotations

import math

import cv2
import mujoco
from dataclasses import replace

import numpy as np
import pytest

from conftest import ROOT
from twin.physics.camera import CameraConfig, cameras_of
from twin.physics.cell import Cell
from twin.vision.calibration import find_target
from twin.vision.camera import Camera
from vision_helpers import CAMERA, PLATE_HEIGHT, build_bench, plate_layout

CLEAN = replace(CAMERA, noise=0.0, distortion=(0.0,) * 5)


def _true_pixel(model, data, config: CameraConfig, world_mm) -> np.ndarray:
    """Where the model's camera images a world point (ground truth, for checking)."""
    cam = model.camera(f"camera/{config.name}").id
    R = data.cam_xmat[cam].reshape(3, 3) @ np.diag([1.0, -1.0, -1.0])
    p = R.T @ (np.array(world_mm) / 1000.0 - data.cam_xpos[cam])
    px, _ = cv2.projectPoints(p.reshape(1, 3), np.zeros(3), np.zeros(3), config.matrix(), np.array(config.distortion))
    return px.ravel()


def test_rgb_and_depth_render_headless():
    model, data = build_bench(plate_layout(1, 2), CLEAN)
    camera = Camera(CLEAN, model)
    image = camera.shoot(data, depth=True)
    assert image.rgb.shape == (480, 640, 3) and image.rgb.dtype == np.uint8
    assert image.depth.shape == (480, 640)
    # The table is 650 mm from the camera along the optical axis; a plate's top 8 mm closer.
    assert image.depth[5, 5] == pytest.approx(650.0, abs=0.5)
    assert image.depth.min() == pytest.approx(650.0 - PLATE_HEIGHT, abs=0.5)
    assert image.frame == 0 and camera.shoot(data).frame == 1
    camera.close()


def test_noise_is_seeded_per_frame():
    model, data = build_bench(plate_layout(1, 2))
    a, b = Camera(CAMERA, model), Camera(CAMERA, model)
    first = a.shoot(data).rgb
    assert np.array_equal(first, b.shoot(data).rgb)  # same camera seed and frame: same picture
    second = a.shoot(data).rgb
    assert not np.array_equal(first, second)  # the next frame has its own noise
    clean = Camera(replace(CAMERA, noise=0.0), model).shoot(data).rgb.astype(float)
    assert np.std(first - clean) == pytest.approx(CAMERA.noise, rel=0.2)
    # Each pixel takes a new draw in each frame: the two frames' noise is uncorrelated.
    unclipped = (clean > 3 * CAMERA.noise) & (clean < 255 - 3 * CAMERA.noise)
    noise_1, noise_2 = (first - clean)[unclipped], (second - clean)[unclipped]
    assert abs(np.corrcoef(noise_1, noise_2)[0, 1]) < 0.02
    assert abs(noise_1.mean()) < 0.05


def test_distortion_moves_points_as_the_lens_model_says():
    plan = CAMERA.calibration
    model, data = build_bench([])
    for config in (CLEAN, replace(CLEAN, distortion=(-0.15, 0.05, 0.001, -0.001, 0.0))):
        camera = Camera(config, model, calibration_targets=True)
        target = model.body_mocapid[model.body("camera/top/target0").id]
        for x, y in ((100.0, 70.0), (-110.0, 40.0), (0.0, 0.0)):
            data.mocap_pos[target] = [x / 1000, y / 1000, 0.0]
            mujoco.mj_forward(model, data)
            seen = find_target(camera.shoot(data).rgb, plan.hsv_low, plan.hsv_high)
            expected = _true_pixel(model, data, config, [x, y, plan.heights[0]])
            assert np.linalg.norm(seen - expected) < 0.2
        camera.close()
    # A camera of the running cell does not draw the calibration targets, in view or not.
    assert find_target(Camera(CLEAN, model).shoot(data).rgb, plan.hsv_low, plan.hsv_high) is None


def test_exposure_scales_the_light():
    model, data = build_bench(plate_layout(1, 3), CLEAN)
    levels = [Camera(replace(CLEAN, exposure=e), model).shoot(data).gray.mean() for e in (0.5, 1.0)]
    assert levels[0] < 0.7 * levels[1]


def test_camera_settings_are_checked():
    with pytest.raises(ValueError, match="unknown key"):
        CameraConfig.from_table({"name": "c", "focal_px": 900.0, "fovy": 40})
    with pytest.raises(ValueError, match="focal_px or fov_deg"):
        CameraConfig.from_table({"name": "c"})
    assert CameraConfig.from_table({"name": "c", "fov_deg": 60.0}).focal == pytest.approx(240 / math.tan(math.radians(30)))


def test_a_camera_on_the_robot_moves_with_it(tmp_path):
    """A camera mounted on the Cobra's outer link: its model camera follows the link, and
    what it sees changes when the arm turns."""
    scene = tmp_path / "arm.toml"
    scene.write_text((ROOT / "scenes" / "scara_vision.toml").read_text() + """
[[camera]]
name = "arm"
resolution = [320, 240]
fov_deg = 60.0
mount = "link2"
pose = [275.0, 0.0, -60.0, 0.0, 180.0, 0.0]
""")
    cell = Cell.from_scene(scene)
    m, d = cell.model, cell.data
    cam, link = m.camera("camera/arm").id, m.body("link2").id
    camera = Camera(next(c for c in cameras_of(cell) if c.name == "arm"), m)

    def offset_mm() -> np.ndarray:
        return d.xmat[link].reshape(3, 3).T @ (d.cam_xpos[cam] - d.xpos[link]) * 1000

    before = camera.shoot(d).rgb
    assert np.allclose(offset_mm(), [275.0, 0.0, -60.0], atol=1e-6)
    d.qpos[m.jnt_qposadr[m.joint("j1").id]] += 0.5
    mujoco.mj_forward(m, d)
    assert np.allclose(offset_mm(), [275.0, 0.0, -60.0], atol=1e-6)
    assert not np.array_equal(before, camera.shoot(d).rgb)
    camera.close()
