"""`twin sweep`: seeds x scene parameters in local processes and on a Ray cluster, one
summary with the failures first (issue "Fast on one core, and many runs").  Runs are a
short V+ program on the demo cell, so the scene parameters show in the simulated time."""

from __future__ import annotations

import csv
import json
import os
import shutil
import socket
import subprocess
import sys
from pathlib import Path

import pytest

from twin.cli import main
from twin.errors import SceneError
from twin.physics.scene import apply_overrides
from twin.sweep import cases, parse_param, run_sweep, write_summary

ROOT = Path(__file__).resolve().parents[1]
SCENE = ROOT / "scenes" / "scara_pick.toml"
PROGRAM = """.PROGRAM shuttle()
    APPRO pick, 50
    APPRO place, 50
    TYPE "done"
.END
"""


@pytest.fixture()
def program(tmp_path: Path) -> Path:
    path = tmp_path / "shuttle.pg"
    path.write_text(PROGRAM)
    return path


def test_param_values_are_toml_values():
    assert parse_param("controller.monitor_speed=50,100") == ("controller.monitor_speed", [50, 100])
    assert parse_param("conveyor.belt.speed=2.5, 3") == ("conveyor.belt.speed", [2.5, 3])
    assert parse_param('physics.sleep=true,false') == ("physics.sleep", [True, False])
    assert parse_param("gripper.kind=suction")[1] == ["suction"]
    for bad in ("monitor_speed", "=5", "a.b="):
        with pytest.raises(ValueError):
            parse_param(bad)


def test_every_seed_meets_every_combination():
    runs = cases([0, 1], [("a", [1, 2]), ("b", ["x", "y", "z"])])
    assert len(runs) == 12 and [c.run for c in runs] == list(range(1, 13))
    assert {(c.seed, c.params["a"], c.params["b"]) for c in runs} == {
        (s, a, b) for s in (0, 1) for a in (1, 2) for b in "xyz"}


def test_overrides_reach_tables_and_named_array_elements(tmp_path: Path):
    scene = {"controller": {"monitor_speed": 50}, "conveyor": [{"name": "infeed", "speed": 100.0},
                                                               {"name": "outfeed", "speed": 50.0}]}
    out = apply_overrides(scene, {"controller.monitor_speed": 80, "conveyor.outfeed.speed": 70.0,
                                  "conveyor.0.speed": 90.0, "physics.timestep": 0.001}, tmp_path / "s.toml")
    assert out["controller"]["monitor_speed"] == 80 and out["physics"] == {"timestep": 0.001}
    assert [c["speed"] for c in out["conveyor"]] == [90.0, 70.0]
    assert scene["controller"]["monitor_speed"] == 50  # the scene itself is not changed
    with pytest.raises(SceneError, match="no element named 'sideways'.*infeed, outfeed"):
        apply_overrides(scene, {"conveyor.sideways.speed": 1.0}, tmp_path / "s.toml")
    with pytest.raises(SceneError, match="is a value, not a table"):
        apply_overrides(scene, {"controller.monitor_speed.x": 1}, tmp_path / "s.toml")


def test_local_sweep_summary_failures_first(tmp_path: Path, program: Path, capsys):
    out = tmp_path / "sweep"
    code = main(["sweep", str(SCENE), str(program), "--seeds", "2", "--workers", "2", "--out", str(out),
                 "--param", "controller.monitor_speed=25,100,fast", "--max-sim-time", "60"])
    assert code == 1  # monitor_speed = "fast" is refused by the scene schema: those runs fail
    summary = json.loads((out / "summary.json").read_text())
    assert (summary["runs"], summary["passed"], summary["failed"]) == (6, 4, 2)
    rows = summary["rows"]
    assert [r["status"] for r in rows] == ["fail", "fail", "pass", "pass", "pass", "pass"]
    assert all(r["params"]["controller.monitor_speed"] == "fast" for r in rows[:2])
    assert "monitor_speed" in rows[0]["failures"][0]
    by_speed = {}
    for r in rows[2:]:
        assert Path(r["report"]).exists() and r["errors"] == 0
        by_speed.setdefault(r["params"]["controller.monitor_speed"], set()).add(r["sim_time_s"])
    # the same moves at a quarter of full monitor speed take longer; seeds do not change the robot's time
    assert len(by_speed[25]) == 1 and len(by_speed[100]) == 1
    assert min(by_speed[25]) > min(by_speed[100]) + 0.3
    with (out / "summary.csv").open() as f:
        table = list(csv.DictReader(f))
    assert [t["run"] for t in table] == [str(r["run"]) for r in rows]
    assert table[0]["params"] == "controller.monitor_speed=fast" and table[0]["first_failure"]
    assert "6 runs: 4 passed, 2 failed" in capsys.readouterr().err


@pytest.mark.slow
def test_hundred_seeds_in_local_processes(tmp_path: Path, program: Path):
    rows = run_sweep([str(program)], str(SCENE), cases(list(range(100)), []), tmp_path, workers=2,
                     max_sim_time=60.0)
    assert len(rows) == 100 and all(r["status"] == "pass" for r in rows)
    assert len({r["seed"] for r in rows}) == 100
    json_path, _ = write_summary(rows, tmp_path)
    assert json.loads(json_path.read_text())["passed"] == 100


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.mark.slow
def test_ray_cluster_gives_the_local_summary(tmp_path: Path, program: Path):
    pytest.importorskip("ray")
    ray_cli = Path(sys.executable).with_name("ray")
    port = _free_port()
    env = {**os.environ, "RAY_USAGE_STATS_ENABLED": "0"}
    subprocess.run([str(ray_cli), "start", "--head", "--node-ip-address=127.0.0.1", f"--port={port}",
                    "--num-cpus=2", "--include-dashboard=false", "--disable-usage-stats"],
                   check=True, capture_output=True, env=env, timeout=180)
    try:
        all_cases = cases([3, 4, 5], [("controller.monitor_speed", [50, 100])])
        on_ray = run_sweep([str(program)], str(SCENE), all_cases, tmp_path / "ray", max_sim_time=60.0,
                           ray_address=f"127.0.0.1:{port}")
    finally:
        subprocess.run([str(ray_cli), "stop", "--force"], capture_output=True, env=env, timeout=120)
    local = run_sweep([str(program)], str(SCENE), all_cases, tmp_path / "local", workers=2, max_sim_time=60.0)
    strip = [{k: v for k, v in r.items() if k not in ("wall_time_s", "report")} for r in on_ray]
    assert strip == [{k: v for k, v in r.items() if k not in ("wall_time_s", "report")} for r in local]
    assert all(r["status"] == "pass" for r in on_ray)
    for ray_row, local_row in zip(on_ray, local):  # bit for bit the same runs
        assert json.loads(Path(ray_row["report"]).read_text())["parts"] == \
            json.loads(Path(local_row["report"]).read_text())["parts"]
    shutil.rmtree(tmp_path, ignore_errors=True)


@pytest.mark.parametrize("extra, says", [
    (["--first-seed", "-1"], "negative"), (["--max-sim-time", "nan"], "finite"),
])
def test_sweep_arguments_are_checked_as_twin_runs_are(tmp_path: Path, program: Path, capsys, extra, says):
    assert main(["sweep", str(SCENE), str(program), "--out", str(tmp_path / "o"), *extra]) == 2
    assert says in capsys.readouterr().err
    assert not (tmp_path / "o").exists()


def test_sweep_refuses_a_missing_program_or_scene_before_any_run(tmp_path: Path, program: Path, capsys):
    assert main(["sweep", str(SCENE), str(tmp_path / "nope.pg"), "--out", str(tmp_path / "o")]) == 2
    assert main(["sweep", str(tmp_path), str(program), "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert "nope.pg" in err and "not a file" in err
    assert not (tmp_path / "o").exists()
