"""The conveyor demo programs (programs/vplus/conveyor_pick.pg, programs/gpl/conveyor_pick/)
on the conveyor cells (scenes/scara_conveyor.toml: fingers; scara_conveyor_suction.toml:
suction cup): parts arrive at random spacing at 100 mm/s, one every 2 s on average; the
photo-eye latches each one; the robot tracks, picks and places it in the tray grid.

The normal suite runs the first 40 simulated seconds; the slow tests (pytest -m slow) the
programs' full 5 minutes, and a source beyond the robot's capacity.
"""

from __future__ import annotations

import json
import math
import re
from pathlib import Path

import pytest

from twin.runner import run_program

from conftest import ROOT

VPLUS = ROOT / "programs" / "vplus" / "conveyor_pick.pg"
GPL = ROOT / "programs" / "gpl" / "conveyor_pick"
CELLS = {"fingers": ROOT / "scenes" / "scara_conveyor.toml", "suction": ROOT / "scenes" / "scara_conveyor_suction.toml"}
PROGRAMS = {"vplus": VPLUS, "gpl": GPL}
TIME_LIMIT = "*Simulation time limit reached*"


def run_cell(program: Path, scene: Path, tmp_path: Path, max_sim_time: float) -> dict:
    report = tmp_path / "report.json"
    run_program(program, scene=scene, report_path=report, max_sim_time=max_sim_time)
    return json.loads(report.read_text())


def tray_errors_mm(report: dict) -> list[float]:
    """How far each part in the tray is from the centre of its cell, in the tray's plane."""
    centres = report["components"]["tray.tray"]["cell_centres_mm"]
    return [math.dist(p["pose"][:2], centres[p["cell"]][:2]) for p in report["parts"] if p.get("cell") is not None]


def _check_every_part_placed(report: dict, least: int) -> None:
    counts = report["counts"]
    assert counts["missed"] == 0 and counts["dropped"] == 0
    assert counts["placed"] >= least
    assert counts["picked"] - counts["placed"] <= 1  # at most one in the gripper when the run stops
    errors = tray_errors_mm(report)
    assert len(errors) == counts["placed"] and max(errors) < 1.0
    # The tray's cells fill in order (the pallet pattern), the full tray swapped for an empty one.
    cells = [p["cell"] for p in report["parts"] if p.get("cell") is not None]
    assert cells == [i % 20 for i in range(len(cells))]


@pytest.mark.parametrize("cell", CELLS)
@pytest.mark.parametrize("language", PROGRAMS)
def test_the_first_40_seconds_pick_and_place_every_part(language, cell, tmp_path):
    report = run_cell(PROGRAMS[language], CELLS[cell], tmp_path, max_sim_time=40.0)
    assert [e["message"].split(" (")[0] for e in report["errors"]] == [TIME_LIMIT]  # the 5-minute run is cut
    _check_every_part_placed(report, least=10)


def _overloaded_scene(tmp_path: Path, scene: Path, mean_interval: float) -> Path:
    """The same cell with parts coming faster (the scene's source interval changed)."""
    text = re.sub(r"mean_interval = [0-9.]+", f"mean_interval = {mean_interval}", scene.read_text())
    text = re.sub(r'model = "models/', f'model = "{ROOT.as_posix()}/models/', text)
    path = tmp_path / scene.name
    path.write_text(text)
    return path


def test_beyond_the_robots_capacity_parts_pass_the_window_and_are_counted_missed(tmp_path):
    scene = _overloaded_scene(tmp_path, CELLS["fingers"], mean_interval=0.6)
    report = run_cell(VPLUS, scene, tmp_path, max_sim_time=40.0)
    counts = report["counts"]
    assert counts["missed"] > 0 and counts["dropped"] == 0
    # The program's own window strategy skipped them (and said so) ...
    skipped = report["output"].count("skipped: past the window")
    assert skipped > 0
    # ... and the robot kept picking and placing the others, each in its cell.
    assert counts["placed"] >= 15
    assert max(tray_errors_mm(report)) < 1.0


@pytest.mark.slow
@pytest.mark.parametrize("cell", CELLS)
@pytest.mark.parametrize("language", PROGRAMS)
def test_five_minutes_at_100_mm_s_every_part_is_picked_and_placed(language, cell, tmp_path):
    report = run_cell(PROGRAMS[language], CELLS[cell], tmp_path, max_sim_time=400.0)
    assert report["errors"] == []
    _check_every_part_placed(report, least=100)
    assert re.search(r"[Mm]issed 0", report["output"])


@pytest.mark.slow
@pytest.mark.parametrize("language", PROGRAMS)
def test_beyond_capacity_both_programs_skip_and_count_parts(language, tmp_path):
    scene = _overloaded_scene(tmp_path, CELLS["suction"], mean_interval=0.6)
    report = run_cell(PROGRAMS[language], scene, tmp_path, max_sim_time=60.0)
    counts = report["counts"]
    assert counts["missed"] > 0 and counts["dropped"] == 0
    assert "skipped" in report["output"]
    assert max(tray_errors_mm(report)) < 1.0
