"""Parts lying on a mat at seeded random poses (``[[scatter]]``): what a camera-guided
robot picks from when there is no feeder, as in a vision cell's first station.

    [[scatter]]
    name = "mat"
    parts = ["plate", "plate", "square"]  # part types, drawn per part with equal chances
    count = 5
    area = [180.0, -290.0, 420.0, -110.0]  # world x, y lo and hi of the part centres, mm
    mat = [150.0, -320.0, 450.0, -80.0]    # the dark mat they lie on (world x, y lo, hi), mm
    mat_height = 2.0                        # mm above the table
    min_distance = 60.0                     # mm between part centres at least
    upside_down = 0.2                       # chance that a part lies upside down

At the first check the parts appear on the mat at rest (one seeded stream of the cell's
random generator: positions uniform in ``area`` at least ``min_distance`` apart, yaw
uniform over the full turn, upside down with the given chance).  ``twin run --seed`` lays
out another table.
"""

from __future__ import annotations

import math

import mujoco
import numpy as np

from .components.base import CellContext, Component
from .geometry import MM, yaw_quat

FLIP = np.array([0.0, 1.0, 0.0, 0.0])  # 180 degrees about x: upside down
MAT_RGBA = [0.1, 0.1, 0.11, 1.0]
TRIES = 10000


class Scatter(Component):
    section = "scatter"

    def __init__(self, config, ctx: CellContext):
        super().__init__(config, ctx)
        self._rng = ctx.rng()
        self.bodies = None
        self.laid = False
        self.layout: list[dict] = []  # per part: type, x, y (mm), yaw (deg), upside_down

    def reserve_parts(self, pool) -> None:
        c = self.config
        self.kinds = list(c.parts)
        self.bodies = {t: pool.reserve(self, [t], c.count, recycled=False) for t in dict.fromkeys(self.kinds)}

    def derived_regions(self):
        x0, y0, x1, y1 = self.config.mat
        top = self.ctx.table_top_z * MM + self.config.mat_height
        return [(self.name, [x0, y0, top - 5.0], [x1, y1, top + 60.0], False)]

    def build(self, spec: mujoco.MjSpec, ctx: CellContext) -> None:
        x0, y0, x1, y1 = (v / MM for v in self.config.mat)
        h = self.config.mat_height / MM
        spec.add_material(name=f"{self.name}_matte", specular=0.0, shininess=0.0, rgba=MAT_RGBA)
        spec.worldbody.add_geom(name=self.name, type=mujoco.mjtGeom.mjGEOM_BOX, material=f"{self.name}_matte",
                                pos=[(x0 + x1) / 2, (y0 + y1) / 2, ctx.table_top_z + h / 2],
                                size=[(x1 - x0) / 2, (y1 - y0) / 2, h / 2])

    def bind(self, model, data, ctx: CellContext) -> None:
        self.parts = ctx.parts

    def check(self, t: float) -> None:
        if self.laid:
            return
        self.laid = True
        c, rng = self.config, self._rng
        x0, y0, x1, y1 = c.area
        placed: list[tuple[float, float]] = []
        for _ in range(TRIES):
            if len(placed) == c.count:
                break
            x, y = rng.uniform(x0, x1), rng.uniform(y0, y1)
            if all(math.hypot(x - px, y - py) >= c.min_distance for px, py in placed):
                placed.append((float(x), float(y)))
        if len(placed) < c.count:
            raise ValueError(f"scatter {self.name!r}: {c.count} parts do not fit {c.min_distance} mm apart in {list(c.area)}")
        surface = self.ctx.table_top_z + c.mat_height / MM
        for x, y in placed:
            kind = self.kinds[int(rng.integers(len(self.kinds)))]
            yaw = float(rng.uniform(-180.0, 180.0))
            flipped = bool(rng.random() < c.upside_down)
            i = self.parts.take(self, kind)
            quat = yaw_quat(math.radians(yaw))
            if flipped:
                q = np.zeros(4)
                mujoco.mju_mulQuat(q, quat, FLIP)
                quat = q
            self.parts.activate(i, [x / MM, y / MM, surface + self.parts.half_height(i) + 0.0002], quat,
                                where=self.name)
            self.layout.append({"type": kind, "x": round(x, 3), "y": round(y, 3), "yaw": round(yaw, 3),
                                "upside_down": flipped})

    def report(self) -> dict:
        return {"layout": self.layout}
