"""What a vision run sends to the recording: the picture at the simulated time it was taken,
with every tool's instances drawn on it (outline, found pose, score), and the calibration's
residual as a scalar."""

from __future__ import annotations

import numpy as np

from .calibration import CameraModel
from .server import Run


def record_run(recorder, run: Run, camera: CameraModel) -> None:
    view = run.process.view(camera)
    strips, points, labels = [], [], []
    for tool, instances in run.results.items():
        for k, inst in enumerate(instances, start=1):
            if len(inst.outline):
                outline = view.to_image(np.asarray(inst.outline, dtype=np.float64))
                strips.append(np.vstack([outline, outline[:1]]))
            points.append(camera.plane_to_pixels([[inst.x, inst.y]], inst.z)[0])
            verdict = "" if inst.passed is None else (" pass" if inst.passed else " FAIL")
            labels.append(f"{tool} {k}: {inst.x:.1f}, {inst.y:.1f}, {inst.angle:.1f} deg, {inst.score:.2f}{verdict}")
    path = f"vision/{run.process.camera}"
    recorder.log_image(path, run.image.time, run.image.rgb, strips, np.array(points) if points else None, labels)
    recorder.log_scalar(f"{path}/calibration_residual_mm", run.image.time, camera.residual_mm)
