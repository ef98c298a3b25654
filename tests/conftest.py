"""What several test modules share: the repository's paths, the Cobra s600
kinematics, tool-down poses and a `twin run` of the demo scene.

Test modules import the constants and helpers with `from conftest import ...`
(the tests folder is on the import path, as for vplus_helpers); the fixtures
reach them by name, as usual."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from twin.cli import main as twin_main
from twin.controller.kinematics import RobotKinematics
from twin.controller.location import Location

ROOT = Path(__file__).resolve().parent.parent
COBRA = ROOT / "models" / "robots" / "cobra_s600.xml"
SCARA_SCENE = ROOT / "scenes" / "scara_pick.toml"
SCARA_EXPECT = ROOT / "scenes" / "scara_pick.expect.toml"


@pytest.fixture(scope="module")
def kin() -> RobotKinematics:
    """The Cobra s600's kinematics, read from its MJCF model."""
    return RobotKinematics.from_mjcf(COBRA)


def tool_down_pose(x: float, y: float, z: float, roll: float) -> np.ndarray:
    """Flange pose (m) of a tool-down SCARA location (x, y, z m; 0, 180, roll)."""
    T = Location(x * 1e3, y * 1e3, z * 1e3, 0, 180, roll).matrix()
    T[:3, 3] /= 1e3
    return T


def twin_run(source: Path, out: Path) -> tuple[int, dict, Path]:
    """`twin run source --scene scenes/scara_pick.toml --report out/report.json`:
    the exit code, the report and the report's path."""
    report = out / "report.json"
    code = twin_main(["run", str(source), "--scene", str(SCARA_SCENE), "--report", str(report)])
    return code, json.loads(report.read_text()), report
