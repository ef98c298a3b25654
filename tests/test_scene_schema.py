"""Scene validation (twin/physics/schema.py, docs/scene.md): a mistake in a scene file is one
clear message naming the file, the key path and what was expected; `twin run` prints it
and exits 2, never with a traceback, never running with a default instead."""

from __future__ import annotations

import tomllib

import pytest

from twin.cli import main as twin_main
from twin.errors import SceneError
from twin.physics.scene import load_scene

from conftest import ROOT, SCARA_SCENE

PROGRAM = ROOT / "programs" / "vplus" / "move_parts.pg"


def _edited(tmp_path, old: str, new: str, source=SCARA_SCENE):
    text = source.read_text()
    assert old in text
    path = tmp_path / "scene.toml"
    path.write_text(text.replace(old, new, 1))
    return path


CASES = [
    # (what is wrong, text replaced, replacement, words the message must contain)
    ("unknown section", "[[conveyor]]", "[[convayor]]",
     ["unknown section [convayor]", "did you mean conveyor?"]),
    ("unknown key", "speed = 200.0", "sped = 200.0",
     ["unknown key 'sped' in conveyor[0]", "speed"]),
    ("wrong type", "speed = 200.0", 'speed = "fast"', ["conveyor[0].speed", "expected a number", "'fast'"]),
    ("NaN", "speed = 200.0", "speed = nan", ["conveyor[0].speed", "finite number"]),
    ("infinite", "mass = 0.05", "mass = inf", ["part[0].mass", "finite number"]),
    ("zero direction", "direction = [0.0, 1.0]", "direction = [0.0, 0.0]",
     ["conveyor[0].direction", "zero vector"]),
    ("missing location", 'home = "start"', 'home = "strat"',
     ["robot.home", "'strat'", "not in [locations]"]),
    ("non-positive size", "size = [100.0, 620.0, 10.0]", "size = [100.0, 0.0, 10.0]",
     ["conveyor[0].size[1]", "greater than 0"]),
    ("unknown gripper type", 'prefix = "gripper/"', 'prefix = "gripper/"\ntype = "magnet"',
     ["gripper.type", '"fingers" or "suction"']),
    ("missing required key", "inner_size = [300.0, 300.0, 280.0]", "", ["bin[0].inner_size", "missing"]),
    ("unknown part type", 'part = "block"', 'part = "blok"', ["feeder[0].part", "'blok'", "[[part]]"]),
    ("misspelt region key", "740.0]\nplace = true", "740.0]\nplase = true", ["unknown key 'plase' in regions.bin", "place"]),
]


@pytest.mark.parametrize("what, old, new, words", CASES, ids=[c[0] for c in CASES])
def test_a_bad_scene_gives_one_clear_message(tmp_path, what, old, new, words):
    path = _edited(tmp_path, old, new)
    with pytest.raises(SceneError) as err:
        load_scene(path)
    text = str(err.value)
    assert text.startswith(f"{path}: ")
    for word in words:
        assert word in text, text
    assert "\n" not in text and "pydantic" not in text


def test_the_demo_scenes_are_valid():
    for name in ("scara_pick", "cartesian_pick", "scara_conveyor", "scara_conveyor_suction"):
        path = ROOT / "scenes" / f"{name}.toml"
        assert load_scene(path) == tomllib.loads(path.read_text())


def test_a_toml_syntax_error_names_the_file(tmp_path):
    path = _edited(tmp_path, "speed = 200.0", "speed = = 200.0")
    with pytest.raises(SceneError, match="not valid TOML"):
        load_scene(path)


@pytest.mark.parametrize("what, old, new, words", CASES[:3], ids=[c[0] for c in CASES[:3]])
def test_twin_run_prints_the_error_and_exits_2(tmp_path, capsys, what, old, new, words):
    path = _edited(tmp_path, old, new)
    assert twin_main(["run", str(PROGRAM), "--scene", str(path)]) == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err and err.count("\n") == 1
    assert err.startswith(str(path)) and words[0] in err
