"""The recording of a run, read back with the rerun SDK: TYPE lines at their simulated
times, the program-line trace, the blueprint, the cell's annotations and entity paths, and
parked parts sent once rather than every frame."""

from __future__ import annotations

import numpy as np
import pytest
from rerun.chunk import RrdReader

from twin.runner import run_program

from test_recorder import read_rrd, timed

PROGRAM = """.PROGRAM rec()
    TYPE "start"
    TIMER 1 = 0
    WAIT TIMER(1) >= 1.0
    TYPE "one ", /S
    TYPE "second"
    MOVE place
    MOVE start
    TYPE "back to start"
.END
"""


@pytest.fixture(scope="module")
def recorded(tmp_path_factory):
    folder = tmp_path_factory.mktemp("rec")
    program = folder / "rec.pg"
    program.write_text(PROGRAM)
    path = folder / "rec.rrd"
    result = run_program(program, rrd_path=path)
    assert result.report.errors == []
    return path, read_rrd(path), result


def test_type_output_line_by_line_at_its_time(recorded):
    _, rrd, result = recorded
    log = timed(rrd["/program/log"])
    texts = [t[0] for t in log["TextLog:text"]]
    times = [t * 1e-9 for t in log["sim_time"]]
    assert texts[1:] == ["start", "one second", "back to start"] and texts[0].startswith("twin run ")
    assert times[1] == pytest.approx(0.0, abs=0.017)
    assert 1.0 <= times[2] <= 1.0 + 0.033                    # after the WAIT, to the 16 ms cycle
    assert times[3] > times[2] + 0.2      # MOVE start waits for MOVE place (one motion planned ahead)


def test_the_program_line_trace(recorded):
    _, rrd, _ = recorded
    lines = timed(rrd["/program/task0/line"])
    texts = [t[0] for t in lines["TextLog:text"]]
    assert texts[0] == "rec line 4: WAIT TIMER(1) >= 1.0"    # lines that run through in a cycle are not seen
    assert texts[1] == "rec line 8: MOVE start"
    numbers = [v[0] for v in timed(rrd["/program/task0/line_number"])["Scalars:scalars"]]
    assert numbers == [4.0, 8.0]
    assert 1.0 <= lines["sim_time"][1] * 1e-9 <= 1.0 + 0.033


def test_the_blueprint_and_the_entity_paths(recorded):
    path, rrd, _ = recorded
    reader = RrdReader(path)
    (store,) = reader.blueprints()
    origins = set()
    for chunk in reader.stream(store=store):
        batch = chunk.to_record_batch()
        if "ViewBlueprint:space_origin" in batch.schema.names:
            origins |= {v[0] for v in batch.column("ViewBlueprint:space_origin").to_pylist()}
    assert origins == {"world", "robot/joints", "signals", "program"}
    assert {"/world/tcp", "/world/regions", "/world/locations/pick", "/world/locations/place",
            "/gripper/closed", "/gripper/force_n", "/robot/joints/j1", "/cell/events"} <= set(rrd)
    tcp = timed(rrd["/world/tcp"])
    assert len(tcp["sim_time"]) > 30                        # one point per frame: the tool tip's path


def test_parked_parts_are_sent_once(recorded):
    _, rrd, result = recorded
    presented = {p["id"] for p in result.report.parts}
    parked = [p for p in rrd if p.startswith("/world/part_") and p.count("/") == 2
              and int(p.rsplit("_", 1)[1]) not in presented]
    assert len(parked) > 20  # of the pool's 24 bodies (MAX_RECYCLED_BODIES), all but the few presented
    for entity in parked:
        rows = sum(len(cols["sim_time"]) for static, cols in rrd[entity] if not static)
        assert rows == 1, entity
    moving = timed(rrd["/world/link2"])
    assert len(moving["sim_time"]) > 10 and np.ptp(np.array(moving["Transform3D:translation"])[:, 0, 0]) > 0
