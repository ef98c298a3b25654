"""Static furniture: the table, bins (a floor and four walls, optional stand and spreader
cone) and trays (a plate with a rim and a grid of cells with known centres)."""

from __future__ import annotations

import math

import mujoco
import numpy as np

from ..geometry import MM, rot_z, yaw_quat
from .base import RETIRED, CellContext, Component

TRAY_REGION_HEIGHT = 0.06  # m above a tray's floor that count as "in the tray"
SWAP_CHECK_S = 0.5  # s between looks at a tray that is swapped when full
SPREADER_SECTIONS = 32  # sides of the spreader cone's rim


class Table(Component):
    section = "table"

    def __init__(self, config, ctx: CellContext):
        super().__init__(config, ctx)
        ctx.table_top_z = (config.center[2] + config.size[2] / 2) / MM

    def build(self, spec: mujoco.MjSpec, ctx: CellContext) -> None:
        c = self.config
        spec.worldbody.add_geom(name="table", type=mujoco.mjtGeom.mjGEOM_BOX, pos=np.array(c.center) / MM,
                                size=np.array(c.size) / MM / 2, rgba=[0.62, 0.5, 0.38, 1])


class Bin(Component):
    """Parts at rest inside a bin retire (see `PartPool._retire`); its inside is a place region."""

    section = "bin"

    def derived_regions(self):
        c = self.config
        fc, (ix, iy, ih) = np.array(c.floor_center), c.inner_size
        return [(self.name, list(fc - [ix / 2, iy / 2, c.wall]), list(fc + [ix / 2, iy / 2, ih]), c.place)]

    def build(self, spec: mujoco.MjSpec, ctx: CellContext) -> None:
        c, n, wb = self.config, self.name, spec.worldbody
        fc = np.array(c.floor_center, dtype=float) / MM
        ix, iy, ih = (v / MM for v in c.inner_size)
        w = c.wall / MM
        col = [0.2, 0.3, 0.6, 1]
        wb.add_geom(name=f"{n}_floor", type=mujoco.mjtGeom.mjGEOM_BOX, pos=fc + [0, 0, w / 2 - w],
                    size=[ix / 2 + w, iy / 2 + w, w / 2], rgba=col)
        for side, pos, size in (
            ("xn", [-(ix + w) / 2, 0, ih / 2], [w / 2, iy / 2 + w, ih / 2]),
            ("xp", [(ix + w) / 2, 0, ih / 2], [w / 2, iy / 2 + w, ih / 2]),
            ("yn", [0, -(iy + w) / 2, ih / 2], [ix / 2, w / 2, ih / 2]),
            ("yp", [0, (iy + w) / 2, ih / 2], [ix / 2, w / 2, ih / 2]),
        ):
            wb.add_geom(name=f"{n}_wall_{side}", type=mujoco.mjtGeom.mjGEOM_BOX, pos=fc + pos, size=size, rgba=col)
        if c.spreader is not None:
            self._add_spreader(spec, fc, c.spreader)
        if c.stand and fc[2] - w > 0.01:
            hs = fc[2] - w
            wb.add_geom(name=f"{n}_stand", type=mujoco.mjtGeom.mjGEOM_BOX, pos=[fc[0], fc[1], hs / 2],
                        size=[ix / 2, iy / 2, hs / 2], rgba=[0.45, 0.45, 0.48, 1])

    def _add_spreader(self, spec: mujoco.MjSpec, floor_center: np.ndarray, cfg) -> None:
        """A spreader cone on the bin floor under the drop point (as in hoppers and bins fed
        from one spout): a part landing on the apex slides off in the direction its centre of
        mass leans, so the parts heap around the cone instead of stacking into one column
        that grows back up to the belt."""
        radius, height = cfg.radius / MM, cfg.height / MM
        centre = np.array(cfg.center if cfg.center is not None else floor_center[:2] * MM, dtype=float) / MM
        # The apex and a 32-gon rim; a mesh given without faces is the convex hull of its
        # vertices (MuJoCo computes it, as it does for every mesh it collides).
        angle = 2 * math.pi * np.arange(SPREADER_SECTIONS) / SPREADER_SECTIONS
        rim = np.column_stack([radius * np.cos(angle), radius * np.sin(angle), np.zeros(SPREADER_SECTIONS)])
        name = f"{self.name}_spreader"
        spec.add_mesh(name=name, uservert=np.vstack([[0.0, 0.0, height], rim]).flatten())
        spec.worldbody.add_geom(name=name, type=mujoco.mjtGeom.mjGEOM_MESH, meshname=name,
                                pos=[centre[0], centre[1], floor_center[2]], rgba=[0.3, 0.4, 0.7, 1])


class Tray(Component):
    """A grid of ``rows`` x ``cols`` cells, ``pitch`` apart, centred on ``center`` and turned by
    ``yaw``. Cell index = row * cols + col (0-based), row along the tray's y, col along its
    x, cell 0 at the tray's (-x, -y) corner. A part in the tray's region is reported with
    the index of the cell whose centre is within half a pitch of it.

    With ``swap_when_full``, once every cell holds a part at rest (retired), the tray is
    swapped for an empty one: its parts' report entries are frozen where they lie (tray,
    cell) and their bodies go back to the pool ("tray_swapped" event), so a long run can
    fill the same tray again and again."""

    section = "tray"
    _next_swap_check = SWAP_CHECK_S
    swaps = 0

    def __init__(self, config, ctx: CellContext):
        super().__init__(config, ctx)
        c = config
        self.R = rot_z(math.radians(c.yaw))
        self.centre = np.array(c.center, dtype=float) / MM
        cols = (np.arange(c.cols) - (c.cols - 1) / 2) * c.pitch[0] / MM
        rows = (np.arange(c.rows) - (c.rows - 1) / 2) * c.pitch[1] / MM
        local = np.array([[x, y, 0.0] for y in rows for x in cols])
        self.cell_centres = self.centre + local @ self.R.T  # (n, 3) world m, on the floor's top
        self.half = np.array([c.cols * c.pitch[0] / 2 + c.margin, c.rows * c.pitch[1] / 2 + c.margin]) / MM

    def derived_regions(self):
        corners = np.array([[sx * self.half[0], sy * self.half[1], 0.0] for sx in (-1, 1) for sy in (-1, 1)])
        xy = self.centre + corners @ self.R.T
        lo = list((xy.min(axis=0) - [0, 0, 0.005]) * MM)
        hi = list((xy.max(axis=0) + [0, 0, TRAY_REGION_HEIGHT]) * MM)
        return [(self.name, lo, hi, True)]

    def build(self, spec: mujoco.MjSpec, ctx: CellContext) -> None:
        c, wb, n = self.config, spec.worldbody, self.name
        q = yaw_quat(math.radians(c.yaw))
        w, h = c.wall / MM, c.wall_height / MM
        hx, hy = self.half
        col = [0.3, 0.55, 0.35, 1]
        wb.add_geom(name=f"{n}_floor", type=mujoco.mjtGeom.mjGEOM_BOX, pos=self.centre - [0, 0, w / 2], quat=q,
                    size=[hx, hy, w / 2], rgba=col)
        if h > 0:
            for side, off, size in (("xn", [-hx - w / 2, 0], [w / 2, hy + w, h / 2]),
                                    ("xp", [hx + w / 2, 0], [w / 2, hy + w, h / 2]),
                                    ("yn", [0, -hy - w / 2], [hx, w / 2, h / 2]),
                                    ("yp", [0, hy + w / 2], [hx, w / 2, h / 2])):
                pos = self.centre + self.R @ np.array([off[0], off[1], h / 2])
                wb.add_geom(name=f"{n}_rim_{side}", type=mujoco.mjtGeom.mjGEOM_BOX, pos=pos, quat=q,
                            size=size, rgba=col)
        stand = self.centre[2] - w - ctx.table_top_z
        if stand > 0.002:
            wb.add_geom(name=f"{n}_stand", type=mujoco.mjtGeom.mjGEOM_BOX, contype=0, conaffinity=0,
                        pos=[self.centre[0], self.centre[1], ctx.table_top_z + stand / 2], quat=q,
                        size=[hx * 0.9, hy * 0.9, stand / 2], rgba=[0.4, 0.4, 0.45, 1])

    def bind(self, model, data, ctx: CellContext) -> None:
        self.parts = ctx.parts
        self._region = ctx.regions.index(self.name)

    def check(self, t: float) -> None:
        if not self.config.swap_when_full or t + 1e-9 < self._next_swap_check:
            return
        self._next_swap_check = t + SWAP_CHECK_S
        parts = self.parts
        retired = parts.live[parts.state[parts.live] == RETIRED]
        if not len(retired):
            return
        pos = parts.data.xpos[parts.shown[retired]]
        here = retired[self.ctx.regions.first_index(pos) == self._region]
        cells = {self.cell_of(parts.data.xpos[parts.shown[i]]) for i in here.tolist()} - {None}
        if len(cells) == len(self.cell_centres):
            for i in here.tolist():
                parts.park(i)
            self.swaps += 1
            self.ctx.event("tray_swapped", tray=self.name, parts=int(len(here)))

    def cell_of(self, position) -> int | None:
        """Index of the cell whose centre is within half a pitch (x and y, tray frame) of
        `position` (world, m), or None."""
        local = (np.asarray(position, dtype=float) - self.centre) @ self.R
        c = self.config
        col = round(local[0] * MM / c.pitch[0] + (c.cols - 1) / 2)
        row = round(local[1] * MM / c.pitch[1] + (c.rows - 1) / 2)
        if 0 <= col < c.cols and 0 <= row < c.rows:
            return int(row * c.cols + col)
        return None

    def cell_centre_mm(self, index: int) -> list[float]:
        """World position (mm) of cell `index` on the tray floor."""
        return [round(float(v) * MM, 3) for v in self.cell_centres[index]]

    def report(self) -> dict:
        return {"rows": self.config.rows, "swaps": self.swaps, "cols": self.config.cols,
                "cell_centres_mm": [self.cell_centre_mm(i) for i in range(len(self.cell_centres))]}
