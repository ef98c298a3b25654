"""Named axis-aligned boxes of the cell (world frame)."""

from __future__ import annotations

import numpy as np

MM = 1000.0


class Regions:
    """Regions from the scene's ``[regions.*]`` tables; lo/hi corners in mm there, m here.

    ``region_of`` answers with the first region (scene order) containing the point.
    """

    def __init__(self, table: dict):
        self.names: list[str] = list(table)
        self.lo = np.array([table[n]["lo"] for n in self.names], dtype=float).reshape(-1, 3) / MM
        self.hi = np.array([table[n]["hi"] for n in self.names], dtype=float).reshape(-1, 3) / MM
        self.place = {n: bool(table[n].get("place", False)) for n in self.names}

    def index(self, name: str) -> int:
        return self.names.index(name)

    def region_of(self, position) -> str | None:
        """Name of the first region containing ``position`` (world, m), or None."""
        p = np.asarray(position, dtype=float)
        inside = np.all((p >= self.lo) & (p <= self.hi), axis=1)
        hits = np.flatnonzero(inside)
        return self.names[hits[0]] if len(hits) else None

    def contains(self, name: str, points: np.ndarray) -> np.ndarray:
        """Boolean per row of ``points`` (N x 3, m): inside region ``name``."""
        i = self.index(name)
        return np.all((points >= self.lo[i]) & (points <= self.hi[i]), axis=-1)

    def first_index(self, points: np.ndarray) -> np.ndarray:
        """Per row of ``points`` (N x 3, m): index of the first region containing it, -1 if none."""
        inside = np.all((points[:, None, :] >= self.lo) & (points[:, None, :] <= self.hi), axis=-1)
        return np.where(inside.any(axis=1), inside.argmax(axis=1), -1)

    def is_place(self, name: str | None) -> bool:
        return name is not None and self.place.get(name, False)
