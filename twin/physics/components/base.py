"""The component protocol: what every piece of a cell (robot, gripper, conveyor, sensor,
tray, camera...) is to the cell that holds it.

A component is built from its scene section (a pydantic model from `schema.py`) and the
shared `CellContext`, then takes part in the cell's life through five hooks, each doing
nothing when nothing changed (the defaults here do nothing):

* ``build(spec, ctx)``: add bodies, geoms, sites, actuators and sensors to the
  ``mujoco.MjSpec`` (names prefixed with the component's name, so several fit);
* ``bind(model, data, ctx)``: after compiling, look up the ids the hooks need;
* ``check(t)``: every check interval (``[physics] check_interval``, 16 ms by default, and
  every physics step while any component's ``busy`` is true): read signals, move belts,
  spawn parts, detect beams, append events to ``ctx.events``;
* ``report()``: a small JSON-able dict for the run report (``components.<name>``), or None;
* ``record(recorder, t)``: time series for the recording (``recorder.log_scalar``), called
  when the recorder takes a frame.

``derived_regions()`` may name regions the component defines by its geometry (a bin's
inside, a tray, a belt) so that a scene need not repeat them under ``[regions]``;
``reserve_parts(pool)`` is where a feeder or source reserves its bodies in the part pool
(before the build).

To add a kind: a section model in `schema.py` (a field of `Scene`), a class here with
``section`` set, and one entry in `components.REGISTRY`.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, ClassVar

import mujoco
import numpy as np

if TYPE_CHECKING:
    from ...controller.io import DigitalIO
    from ..parts import PartPool
    from ..regions import Regions
    from ..schema import Scene

PARKED, LIVE, RETIRED, FINISHED = 0, 1, 2, 3  # states of a pooled part body (`PartPool.state`)
# Contact bits (MuJoCo: two geoms touch when contype of one & conaffinity of the other).
# The static cell keeps MuJoCo's 1/1. Live parts touch the cell, the robot, live and retired
# parts; retired parts (at rest in a bin or tray) touch only live parts; the moving robot
# touches the cell, live parts and itself; the part a grasp holds touches everything but
# the robot (the weld holds it: the jaws' or the cup's contacts would only squeeze it, at
# the cost of a dozen contacts every step, see docs/performance.md).
LIVE_CONTYPE, LIVE_CONAFFINITY = 1, 3
RETIRED_CONTYPE, RETIRED_CONAFFINITY = 2, 0
ROBOT_CONTYPE, ROBOT_CONAFFINITY = 4, 5
HELD_CONTYPE, HELD_CONAFFINITY = 8, 3


@dataclass
class CellContext:
    """What components share: the scene, the I/O, the event list, the part pool, the regions,
    and the components by kind (filled in construction order)."""
    scene: "Scene"
    scene_path: Path
    seed: int
    io: "DigitalIO"
    events: list[dict] = field(default_factory=list)
    parts: "PartPool | None" = None
    regions: "Regions | None" = None
    table_top_z: float = 0.0  # m
    by_kind: dict[str, dict[str, "Component"]] = field(default_factory=dict)
    request_check: Any = None  # callable: check at the next physics step
    held_part: Any = None  # callable: body index of the part the gripper holds, or None
    retire_regions: list[str] = field(default_factory=list)  # bins and trays: parts at rest there retire
    model: mujoco.MjModel | None = None
    data: mujoco.MjData | None = None
    _streams: int = 0

    def rng(self) -> np.random.Generator:
        """A random stream of its own for each component that asks (construction order): the
        first is ``default_rng(seed)``, the k-th (k >= 1) ``default_rng([seed, k])``."""
        k, self._streams = self._streams, self._streams + 1
        return np.random.default_rng(self.seed if k == 0 else [self.seed, k])

    def event(self, kind: str, **fields) -> dict:
        event = {"t": round(float(self.data.time) if self.data is not None else 0.0, 4), "kind": kind, **fields}
        self.events.append(event)
        return event

    def component(self, kind: str, name: str) -> "Component":
        return self.by_kind[kind][name]


class Component:
    """Base of every cell component (see the module docstring)."""

    section: ClassVar[str] = ""
    busy: bool = False  # True: the cell runs the checks every physics step

    def __init__(self, config, ctx: CellContext):
        self.config = config
        self.ctx = ctx
        self.name: str = getattr(config, "name", None) or self.section

    def derived_regions(self) -> list[tuple[str, list[float], list[float], bool]]:
        """(name, lo mm, hi mm, place) of the regions this component defines."""
        return []

    def reserve_parts(self, pool: "PartPool") -> None:
        pass

    def build(self, spec: mujoco.MjSpec, ctx: CellContext) -> None:
        pass

    def bind(self, model: mujoco.MjModel, data: mujoco.MjData, ctx: CellContext) -> None:
        pass

    def check(self, t: float) -> None:
        pass

    def report(self) -> dict | None:
        return None

    def record(self, recorder, t: float) -> None:
        pass
