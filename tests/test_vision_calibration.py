"""Camera-to-robot calibration from images only: residual, recovered camera, the file the
vision server loads, and the plan's mistakes."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from conftest import ROOT
from twin.physics.camera import TargetPlan, cameras_of
from twin.physics.cell import Cell
from twin.vision.calibrate import calibrate
from twin.vision.calibration import PRINCIPAL_STD_PX, CameraModel, solve
from vision_helpers import CAMERA, build_bench


@pytest.fixture(scope="module")
def calibrated():
    model, data = build_bench([])
    result, record = calibrate(model, data, CAMERA, np.eye(4))
    return model, data, result, record


def test_residual_is_under_0_2_mm(calibrated):
    _, _, result, record = calibrated
    assert result.points == len(record) >= 30
    assert result.residual_mm < 0.2 and result.residual_max_mm < 0.2
    assert result.residual_px < 0.3


def test_the_camera_it_finds_is_the_camera_of_the_cell(calibrated):
    model, data, result, _ = calibrated
    # Checked against the simulator's camera (the calibration itself never reads it).
    assert result.K[0, 0] == pytest.approx(CAMERA.focal, rel=0.01)
    cam = model.camera("camera/top").id
    assert np.linalg.norm(result.center_mm - data.cam_xpos[cam] * 1000) < 3.0
    # Robot points on the table land where the true camera sees them, across the view.
    grid = np.array([[x, y] for x in (-120, 0, 120) for y in (-90, 0, 90)], float)
    true = CameraModel(K=CAMERA.matrix(), dist=np.array(CAMERA.distortion),
                       R=np.diag([0.0, 0.0, 0.0]), t=np.zeros(3), size=CAMERA.resolution)
    R_true = (data.cam_xmat[cam].reshape(3, 3) @ np.diag([1.0, -1.0, -1.0])).T
    true.R, true.t = R_true, -R_true @ (data.cam_xpos[cam] * 1000)
    assert np.abs(result.plane_to_pixels(grid, 8.0) - true.plane_to_pixels(grid, 8.0)).max() < 0.3


def test_the_principal_point_is_estimated_where_the_sightings_pin_it_down(calibrated):
    # The bench's two post heights leave it uncertain (over 1.5 px): held at the centre.
    result = calibrated[2]
    assert result.principal == "held" and max(result.principal_std_px) > PRINCIPAL_STD_PX
    assert (result.K[0, 2], result.K[1, 2]) == ((CAMERA.width - 1) / 2, (CAMERA.height - 1) / 2)
    # The conveyor camera's three post heights pin it within 1.5 px: estimated, and within
    # a pixel of the renderer's (a centred pinhole; read here only to check).
    cell = Cell.from_scene(ROOT / "scenes" / "conveyor_vision.toml")
    config = cameras_of(cell)[0]
    belt, _ = calibrate(cell.model, cell.data, config, cell.robot_base_pose())
    assert belt.principal == "estimated" and max(belt.principal_std_px) <= PRINCIPAL_STD_PX
    assert np.hypot(belt.K[0, 2] - config.matrix()[0, 2], belt.K[1, 2] - config.matrix()[1, 2]) < 1.0
    assert belt.residual_mm < 0.2 and belt.residual_max_mm < 0.2


def test_the_result_file_round_trips(calibrated, tmp_path):
    result = calibrated[2]
    path = tmp_path / "cam.calib.json"
    result.save(path)
    loaded = CameraModel.load(path)
    assert np.allclose(loaded.pixels_to_plane([[100.0, 200.0]], 8.0), result.pixels_to_plane([[100.0, 200.0]], 8.0))
    assert loaded.residual_mm == result.residual_mm
    assert (loaded.principal, loaded.principal_std_px) == (result.principal, result.principal_std_px)


def test_pixels_and_plane_are_inverse(calibrated):
    result = calibrated[2]
    xy = np.array([[-100.0, 50.0], [30.0, -70.0]])
    assert np.allclose(result.pixels_to_plane(result.plane_to_pixels(xy, 20.0), 20.0), xy, atol=1e-6)


def test_a_plan_on_one_height_or_too_few_sightings_is_refused():
    with pytest.raises(ValueError, match="two post heights"):
        TargetPlan.from_table("top", {"file": "c.json", "x": [0.0], "y": [0.0], "heights": [20.0]})
    with pytest.raises(ValueError, match="at least 8"):
        solve(np.zeros((4, 3)), np.zeros((4, 2)), (640, 480))
    model, data = build_bench([])
    outside = replace(CAMERA, calibration=replace(CAMERA.calibration, x=(900.0,), y=(900.0,)))
    with pytest.raises(ValueError, match="at least 8"):
        calibrate(model, data, outside, np.eye(4))
