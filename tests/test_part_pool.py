"""The part pool in long runs (issue 14): a feeder's or source's `pool` builds at most
MAX_RECYCLED_BODIES bodies per part type (every body costs every physics step), a
scatter all it lays out; recycled bodies keep every part's report entry."""

from __future__ import annotations

import numpy as np

from twin.physics.cell import Cell
from twin.physics.parts import MAX_RECYCLED_BODIES, RETIRED

from conftest import SCARA_SCENE


def _cell(tmp_path, pool: int) -> Cell:
    path = tmp_path / "scene.toml"
    path.write_text(SCARA_SCENE.read_text().replace("pool = 120", f"pool = {pool}", 1))
    return Cell.from_scene(path)


def test_a_huge_feeder_pool_builds_a_bounded_number_of_bodies(tmp_path):
    assert _cell(tmp_path, 2000).parts.size == MAX_RECYCLED_BODIES
    assert _cell(tmp_path, 120).parts.size == MAX_RECYCLED_BODIES  # the demo's pool
    assert _cell(tmp_path, 5).parts.size == 5  # a smaller pool as asked


def test_recycled_bodies_keep_every_parts_report_entry(tmp_path):
    """Three bodies for seven parts, each dropped in a corner of the bin by hand: every
    one is reported in the bin, the recycled ones frozen where they came to rest."""
    cell = _cell(tmp_path, 3)
    parts, feeder = cell.parts, cell.ctx.component("feeder", "nest")
    floor_z = cell.ctx.regions.lo[cell.ctx.regions.index("bin")][2] + 0.01  # m
    ids = []
    for k in range(7):
        i = parts.take(feeder)
        assert i is not None
        # a corner of the bin, off the spreader cone
        ids += [parts.activate(i, [0.17 + 0.03 * (k % 3), 0.59 + 0.025 * (k // 3), floor_z + 0.03], [1, 0, 0, 0], where="bin")]
        cell.step(500)  # 1 s: falls, comes to rest, retires
    entries = cell.parts_report()
    assert [e["id"] for e in entries] == list(range(len(entries)))
    mine = [entries[i] for i in ids]
    assert all(e["region"] == "bin" and not e["dropped"] for e in mine), mine
    assert len({tuple(e["pose"][:2]) for e in mine}) == 7  # each where it came to rest
    assert parts.size == 3


def test_a_part_landing_on_a_retired_one_neither_moves_nor_wakes_it(tmp_path):
    """A retired part is a static copy of it (a mocap body) where it came to rest: a part
    dropped onto it lands and rests on it, leaves it exactly where it was and is an island
    of its own (before, it woke the retired part and pushed it about a millimetre)."""
    cell = _cell(tmp_path, 3)
    parts, feeder = cell.parts, cell.ctx.component("feeder", "nest")
    d, m = cell.data, cell.model
    floor_z = cell.ctx.regions.lo[cell.ctx.regions.index("bin")][2] + 0.01  # m
    first = parts.take(feeder)
    parts.activate(first, [0.18, 0.6, floor_z + 0.02], [1, 0, 0, 0], where="bin")
    cell.step(500)  # 1 s: falls, comes to rest, retires
    assert parts.state[first] == RETIRED
    resting = parts.position(first)
    assert resting[2] < floor_z + 0.02
    second = parts.take(feeder)
    parts.activate(second, resting + [0.005, 0.0, 0.05], [1, 0, 0, 0], where="bin")
    heap_tree = m.body_treeid[parts.body[first]]
    touched = False
    for _ in range(500):
        cell.step(1)
        touched |= any(set(c.geom) == {parts.geom[second], parts.rest_geom[first]} for c in d.contact[:d.ncon])
        assert d.tree_asleep[heap_tree] >= 0  # the retired part's free body sleeps under the floor
    assert touched
    assert np.array_equal(parts.position(first), resting)
    assert parts.state[second] == RETIRED
    assert parts.position(second)[2] > resting[2] + 0.015  # on top of the first (parts are 20 mm tall)
