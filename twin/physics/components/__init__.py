"""The kinds of component a scene can list, in build order (see `base` for the protocol).

``REGISTRY`` maps a scene section to the factory that makes a component from one entry of
it (``factory(config, ctx)``). ``[robot]`` and ``[gripper]`` are single tables, the others
arrays of tables (``[[conveyor]]``); a kind's components are built in the order the scene
lists them, kinds in the order below.
"""

from __future__ import annotations

from .base import CellContext, Component
from .conveyor import Conveyor, Encoder
from .feeder import NestFeeder
from .fixtures import Bin, Table, Tray
from .gripper import FingerGripper, SuctionGripper, WeldGripper, make_gripper
from .robot import Robot
from .sensor import PhotoEye, PresenceSensor, make_sensor
from .source import Source

def _camera(config, ctx: CellContext) -> Component:
    from ..camera import Camera  # twin/physics/camera.py imports this package's base

    return Camera(config, ctx)


def _scatter(config, ctx: CellContext) -> Component:
    from ..scatter import Scatter  # as for the camera

    return Scatter(config, ctx)


REGISTRY = {
    "robot": Robot,
    "gripper": make_gripper,
    "table": Table,
    "feeder": NestFeeder,
    "conveyor": Conveyor,
    "source": Source,
    "sensor": make_sensor,
    "bin": Bin,
    "tray": Tray,
    "scatter": _scatter,
    "camera": _camera,
}

__all__ = ["REGISTRY", "CellContext", "Component", "Conveyor", "Encoder", "NestFeeder", "Bin", "Table",
           "Tray", "FingerGripper", "SuctionGripper", "WeldGripper", "Robot", "PhotoEye",
           "PresenceSensor", "Source"]
