"""The vision tools against the simulator's ground truth (read here only to check; the
tools see the pictures and the calibration): pose errors at 640 x 480, upside-down and
wrong parts."""

from __future__ import annotations

import math

import numpy as np
import pytest

from twin.vision.calibrate import calibrate
from twin.vision.camera import Camera
from twin.vision.locators import BlobLocator, Inspection, PatternLocator
from twin.vision.process import Process
from twin.vision.view import PlaneView
from vision_helpers import CAMERA, PLATE_HEIGHT, PLATE_OUTLINE, build_bench, plate_layout

BOX = (30.0, 30.0, 8.0)  # a part of the wrong type


@pytest.fixture(scope="module")
def camera_model():
    model, data = build_bench([])
    return calibrate(model, data, CAMERA, np.eye(4))[0]


def _picture(poses, boxes=()):
    model, data = build_bench(poses, extra_boxes=boxes)
    camera = Camera(CAMERA, model)
    image = camera.shoot(data)
    camera.close()
    return image


def _angle_error(a: float, b: float, period: float = 360.0) -> float:
    return abs((a - b + period / 2) % period - period / 2)


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_pattern_locator_pose_error_under_half_a_millimetre_and_degree(camera_model, seed):
    poses = plate_layout(seed, 5, flipped=(1,))
    image = _picture(poses)
    view = PlaneView(camera_model, PLATE_HEIGHT, (-130, -170), (130, 170))
    found = PatternLocator(outline=PLATE_OUTLINE, mirror=True, min_score=0.85).run(view, view.resample(image.gray))
    assert len(found) == 5
    for x, y, yaw, flipped in poses:
        f = min(found, key=lambda i: math.hypot(i.x - x, i.y - y))
        assert math.hypot(f.x - x, f.y - y) < 0.5
        # Upside down, the plate is its mirror image: the angle of the mirrored model is
        # measured in the plate's flipped frame (x unchanged, y reversed).
        assert _angle_error(f.angle, yaw) < 0.5
        assert f.model == ("pattern mirrored" if flipped else "pattern")
        assert f.score > 0.95


def test_blob_locator_and_inspection_tell_a_wrong_part(camera_model):
    poses = plate_layout(4, 3, keep_clear=((0.0, 0.0),))
    image = _picture(poses, boxes=[(0.0, 0.0, 17.0, BOX)])
    view = PlaneView(camera_model, PLATE_HEIGHT, (-130, -170), (130, 170))
    blobs = BlobLocator(threshold=150, min_area=300).run(view, view.resample(image.gray))
    assert len(blobs) == 4
    box = min(blobs, key=lambda b: math.hypot(b.x, b.y))
    assert math.hypot(box.x, box.y) < 0.5 and _angle_error(box.angle, 17.0, 90.0) < 0.5
    assert box.width == pytest.approx(30.0, abs=1.0) and box.length == pytest.approx(30.0, abs=1.0)
    inspected = Inspection("blobs", "width", 20.0, 28.0).run(blobs)
    assert [i.passed for i in inspected].count(False) == 1
    assert next(i for i in inspected if not i.passed).actual == pytest.approx(30.0, abs=1.0)


def test_a_process_chains_its_tools(camera_model):
    process = Process.from_table({
        "name": "Main", "camera": "top", "plane_z": PLATE_HEIGHT, "area": [-130, -170, 130, 170],
        "tool": [{"name": "blobs", "type": "blob", "threshold": 150, "min_area": 300},
                 {"name": "part1", "type": "pattern", "near": "blobs", "outline": PLATE_OUTLINE,
                  "mirror": True, "min_score": 0.9},
                 {"name": "ok", "type": "inspection", "source": "part1",
                  "checks": [["score", 0.9, 1.0], ["upright", 1, 1]]}]})
    poses = plate_layout(5, 3, flipped=(0,), keep_clear=((0.0, 0.0),))
    image = _picture(poses, boxes=[(0.0, 0.0, 0.0, BOX)])
    _, results = process.run(image.rgb, camera_model)
    assert [t.name for t in process.tools] == ["acquire", "blobs", "part1", "ok"]
    assert len(results["part1"]) == len(results["ok"]) == 4
    verdict = {round(i.x): i.passed for i in results["ok"]}
    expected = {round(x): not flipped for x, y, yaw, flipped in poses}
    expected[0] = False  # the box matches no plate
    assert verdict == expected


def test_process_mistakes_are_named():
    with pytest.raises(ValueError, match="unknown key"):
        Process.from_table({"name": "M", "camera": "top", "plane_z": 0, "area": [0, 0, 1, 1],
                            "tool": [{"name": "b", "type": "blob", "treshold": 3}]})
    with pytest.raises(ValueError, match="not an earlier tool"):
        Process.from_table({"name": "M", "camera": "top", "plane_z": 0, "area": [0, 0, 1, 1],
                            "tool": [{"name": "p", "type": "pattern", "near": "x", "outline": PLATE_OUTLINE}]})
    with pytest.raises(ValueError, match="missing area"):
        Process.from_table({"name": "M", "camera": "top", "plane_z": 0})
