"""The broken-scene corpus (issue 14): every kind of mistake a careless or hostile user can
make in a scene file (unknown sections and keys, wrong types, NaN and infinities, zero
directions, impossible or huge sizes, missing locations and models, bad references
between components, files that are not TOML, empty, a folder, binary) is one message
naming the file, the key, the offending value and what was expected, and `twin run` exits
2 with it, never with a traceback; plus the scene loader fuzzed (bounded, derandomized):
nothing but SceneError comes out of it."""

from __future__ import annotations

import copy
import os
import subprocess
import sys
import tomllib

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from twin.cli import main as twin_main
from twin.errors import SceneError
from twin.physics.scene import load_scene
from twin.physics.schema import validate_scene

from conftest import ROOT

SCENES = ROOT / "scenes"
PICK, BELT, VISION = "scara_pick", "scara_conveyor", "scara_vision"
# A program that ends at once: a scene that wrongly passed would cost no run.
PROGRAM_TEXT = ".PROGRAM nothing()\n    TYPE \"ran\"\n.END\n"

# (id, scene, text replaced, replacement, words the message must contain: key, value, expected)
CASES = [
    # unknown sections and keys
    ("unknown-section", PICK, "[[conveyor]]", "[[convayor]]", ["unknown section [convayor]", "did you mean conveyor?"]),
    ("unknown-table", PICK, "[physics]", "[phisics]\ntimestep = 0.002\n[physics]",
     ["unknown section [phisics]", "did you mean physics?"]),
    ("unknown-top-level-key", PICK, "[physics]", "speed = 3\n[physics]", ["unknown key 'speed' at the top level", "physics"]),
    ("unknown-physics-key", PICK, "timestep = 0.002", "time_step = 0.002",
     ["unknown key 'time_step' in physics", "did you mean timestep?"]),
    ("unknown-robot-key", PICK, "base = [0.0, 0.0, 750.0", "bse = [0.0, 0.0, 750.0", ["unknown key 'bse' in robot", "base"]),
    ("unknown-part-key", PICK, "mass = 0.05", "mas = 0.05", ["unknown key 'mas' in part[0]", "did you mean mass?"]),
    ("unknown-feeder-key", PICK, "pool = 120", "pool = 120\npoll = 3", ["unknown key 'poll' in feeder[0]", "pool"]),
    ("unknown-spreader-key", PICK, "radius = 100.0", "radus = 100.0",
     ["unknown key 'radus' in bin[0].spreader", "did you mean radius?"]),
    ("unknown-region-key", PICK, "740.0]\nplace = true", "740.0]\nplase = true", ["unknown key 'plase' in regions.bin", "place"]),
    ("unknown-encoder-key", BELT, "counts_per_mm = 10.0", "counts_mm = 10.0",
     ["unknown key 'counts_mm' in conveyor[0].encoder", "counts_per_mm"]),
    ("unknown-gripper-key", PICK, 'site = "flange"', 'site = "flange"\nforce = 40', ["unknown key 'force' in gripper"]),
    ("physics-as-array", PICK, "[physics]", "[[physics]]", ["physics: expected a table", "got [{"]),
    ("gripper-as-array", PICK, "[gripper]", "[[gripper]]", ["gripper: expected a table"]),
    # wrong types
    ("string-for-number", PICK, "speed = 200.0", 'speed = "fast"', ["conveyor[0].speed", "expected a number", "'fast'"]),
    ("quoted-number", PICK, "timestep = 0.002", 'timestep = "0.002"', ["physics.timestep", "expected a number", "'0.002'"]),
    ("bool-for-number", PICK, "speed = 200.0", "speed = true", ["conveyor[0].speed", "expected a number", "True"]),
    ("date-for-number", PICK, "speed = 200.0", "speed = 1979-05-27", ["conveyor[0].speed", "expected a number", "1979"]),
    ("string-for-bool", PICK, "sleep = true", 'sleep = "yes"', ["physics.sleep", "expected true or false", "'yes'"]),
    ("int-for-bool", PICK, "stand = true", "stand = 1", ["bin[0].stand", "expected true or false", "1"]),
    ("float-for-int", PICK, "seed = 1 ", "seed = 1.5 ", ["physics.seed", "expected an integer", "1.5"]),
    ("float-pool", PICK, "pool = 120", "pool = 120.0", ["feeder[0].pool", "expected an integer", "120.0"]),
    ("number-for-name", PICK, 'name = "nest"', "name = 3", ["feeder[0].name", "expected a string", "3"]),
    ("number-for-model", PICK, 'model = "models/robots/cobra_s600.xml"', "model = 7",
     ["robot.model", "expected a string", "7"]),
    ("string-for-pose", PICK, "base = [0.0, 0.0, 750.0, 0.0, 0.0, 0.0]", 'base = "origin"',
     ["robot.base", "expected a list", "'origin'"]),
    ("short-pose", PICK, "base = [0.0, 0.0, 750.0, 0.0, 0.0, 0.0]", "base = [0.0, 0.0, 750.0]",
     ["robot.base", "at least 6 items", "[0.0, 0.0, 750.0]"]),
    ("long-vector", PICK, "nest = [300.0, -180.0, 850.0]", "nest = [300.0, -180.0, 850.0, 1.0]",
     ["feeder[0].nest", "at most 3 items", "850.0, 1.0]"]),
    ("string-in-vector", PICK, "nest = [300.0, -180.0, 850.0]", 'nest = [300.0, "y", 850.0]',
     ["feeder[0].nest[1]", "expected a number", "'y'"]),
    ("rgba-above-1", PICK, "rgba = [0.9, 0.55, 0.1, 1.0]", "rgba = [0.9, 0.55, 0.1, 2.0]",
     ["part[0].rgba[3]", "less than or equal to 1", "2.0"]),
    ("unknown-integrator", PICK, 'integrator = "implicitfast"', 'integrator = "verlet"',
     ["physics.integrator", '"implicitfast", "implicit", "euler" or "rk4"', "'verlet'"]),
    ("unknown-shape", PICK, 'shape = "box"', 'shape = "sphere"', ["part[0].shape", '"box", "cylinder" or "mesh"', "'sphere'"]),
    ("unknown-gripper-type", PICK, 'prefix = "gripper/"', 'prefix = "gripper/"\ntype = "magnet"',
     ["gripper.type", '"fingers" or "suction"', "'magnet'"]),
    ("string-location", PICK, "start = [300.0, 0.0, 300.0, 0.0, 180.0, 180.0]", 'start = "here"',
     ["locations.start", "expected a list", "'here'"]),
    ("short-location", PICK, "pick = [300.0, -180.0, 218.0, 0.0, 180.0, 180.0]", "pick = [300.0, -180.0]",
     ["locations.pick", "at least 6 items", "[300.0, -180.0]"]),
    ("number-for-table", PICK, "spreader = { center = [300.0, 745.0], radius = 100.0, height = 100.0 }", "spreader = 5",
     ["bin[0].spreader", "expected a table", "5"]),
    ("number-for-region", PICK, "[regions.nest]\n", "[regions]\nnest = 3\n[regions.x]\n", ["regions.nest", "expected a table", "3"]),
    ("suction-key-on-fingers", PICK, 'prefix = "gripper/"', 'prefix = "gripper/"\nvacuum_output = 3',
     ["gripper", "vacuum_output", 'only for type = "suction"']),
    ("output-out-of-range", BELT, "input = 1001", "input = 1", ["sensor[0].input", "greater than or equal to 1001", "1"]),
    # NaN and infinities
    ("nan-speed", PICK, "speed = 200.0", "speed = nan", ["conveyor[0].speed", "a finite number", "nan"]),
    ("inf-mass", PICK, "mass = 0.05", "mass = inf", ["part[0].mass", "a finite number", "inf"]),
    ("minus-inf-timestep", PICK, "timestep = 0.002", "timestep = -inf", ["physics.timestep", "-inf"]),
    ("nan-in-pose", PICK, "base = [0.0, 0.0, 750.0", "base = [0.0, 0.0, nan", ["robot.base[2]", "a finite number", "nan"]),
    ("inf-in-nest", PICK, "nest = [300.0, -180.0, 850.0]", "nest = [300.0, -180.0, inf]",
     ["feeder[0].nest[2]", "a finite number", "inf"]),
    ("nan-location", PICK, "pick = [300.0, -180.0, 218.0", "pick = [300.0, nan, 218.0",
     ["locations.pick[1]", "a finite number", "nan"]),
    ("nan-region", PICK, "lo = [150.0, 575.0, 440.0]", "lo = [150.0, nan, 440.0]", ["regions.bin.lo[1]", "a finite number", "nan"]),
    ("nan-jitter", PICK, "jitter_xy = 1.0", "jitter_xy = nan", ["feeder[0].jitter_xy", "a finite number", "nan"]),
    ("nan-colour", PICK, "rgba = [0.9, 0.55, 0.1, 1.0]", "rgba = [nan, 0.55, 0.1, 1.0]", ["part[0].rgba[0]", "nan"]),
    ("nan-monitor-speed", PICK, "[robot]", "[controller]\nmonitor_speed = nan\n[robot]", ["controller.monitor_speed", "nan"]),
    ("inf-tray-yaw", BELT, "\nyaw = 0.0\n", "\nyaw = inf\n",
     ["tray[0].yaw", "a finite number", "inf"]),
    ("nan-direction", PICK, "direction = [0.0, 1.0]", "direction = [nan, 1.0]", ["conveyor[0].direction[0]", "finite", "nan"]),
    # zero directions
    ("zero-direction", PICK, "direction = [0.0, 1.0]", "direction = [0.0, 0.0]", ["conveyor[0].direction", "zero vector", "got [0.0, 0.0]"]),
    ("zero-direction-3d", PICK, "direction = [0.0, 1.0]", "direction = [0.0, 0.0, 0.0]", ["conveyor[0].direction", "zero vector"]),
    ("tiny-direction", PICK, "direction = [0.0, 1.0]", "direction = [1e-12, 0.0]", ["conveyor[0].direction", "zero vector"]),
    ("one-axis-direction", PICK, "direction = [0.0, 1.0]", "direction = [1.0]", ["conveyor[0].direction", "at least 2 items", "[1.0]"]),
    # impossible sizes
    ("zero-belt-length", PICK, "size = [100.0, 620.0, 10.0]", "size = [100.0, 0.0, 10.0]",
     ["conveyor[0].size[1]", "greater than 0", "0.0"]),
    ("negative-bin", PICK, "inner_size = [300.0, 300.0, 280.0]", "inner_size = [300.0, -300.0, 280.0]",
     ["bin[0].inner_size[1]", "greater than 0", "-300.0"]),
    ("negative-table", PICK, "size = [900.0, 1010.0, 750.0]", "size = [900.0, -1.0, 750.0]",
     ["table.size[1]", "greater than 0", "-1.0"]),
    ("zero-wall", PICK, "wall = 8.0 ", "wall = 0.0 ", ["bin[0].wall", "greater than 0", "0.0"]),
    ("zero-nest", PICK, "nest_size = [44.0, 44.0]", "nest_size = [0.0, 44.0]", ["feeder[0].nest_size[0]", "greater than 0"]),
    ("negative-part", PICK, "size = [30.0, 30.0, 20.0]", "size = [30.0, 30.0, -20.0]",
     ["part[0].size[2]", "greater than 0", "-20.0"]),
    ("zero-timestep", PICK, "timestep = 0.002", "timestep = 0.0", ["physics.timestep", "greater than 0", "0.0"]),
    ("negative-check-interval", PICK, "check_interval = 0.016", "check_interval = -0.01",
     ["physics.check_interval", "greater than 0", "-0.01"]),
    ("zero-pool", PICK, "pool = 120", "pool = 0", ["feeder[0].pool", "greater than or equal to 1", "0"]),
    ("negative-speed", PICK, "speed = 200.0", "speed = -200.0", ["conveyor[0].speed", "greater than or equal to 0", "-200.0"]),
    ("negative-delay", PICK, "delay = 0.3", "delay = -0.3", ["feeder[0].delay", "greater than or equal to 0", "-0.3"]),
    ("zero-spreader", PICK, "radius = 100.0", "radius = 0.0", ["bin[0].spreader.radius", "greater than 0", "0.0"]),
    ("region-inside-out", PICK, "lo = [150.0, 575.0, 440.0]", "lo = [450.0, 575.0, 440.0]",
     ["regions.bin", "lo must be below hi"]),
    ("zero-tray-rows", BELT, "rows = 4 ", "rows = 0 ", ["tray[0].rows", "greater than or equal to 1", "0"]),
    ("zero-tray-pitch", BELT, "pitch = [45.0, 45.0]", "pitch = [45.0, 0.0]", ["tray[0].pitch[1]", "greater than 0"]),
    ("box-without-size", PICK, "size = [30.0, 30.0, 20.0]", "", ["part[0]", "shape 'box' needs size"]),
    ("cylinder-with-size", PICK, 'shape = "box"', 'shape = "cylinder"\nradius = 10.0\nheight = 5.0',
     ["part[0]", "size: not used by shape 'cylinder'"]),
    # huge values
    ("huge-pool", PICK, "pool = 120", "pool = 100000", ["feeder[0].pool", "less than or equal to 10000", "100000"]),
    ("huge-timestep", PICK, "timestep = 0.002", "timestep = 1e300", ["physics.timestep", "less than or equal to", "1e+300"]),
    ("huge-check-interval", PICK, "check_interval = 0.016", "check_interval = 1e9",
     ["physics.check_interval", "less than or equal to", "1000000000.0"]),
    ("huge-speed", PICK, "speed = 200.0", "speed = 1e300", ["conveyor[0].speed", "less than or equal to", "1e+300"]),
    ("huge-mass", PICK, "mass = 0.05", "mass = 1e300", ["part[0].mass", "less than or equal to", "1e+300"]),
    ("huge-table", PICK, "size = [900.0, 1010.0, 750.0]", "size = [9e200, 1010.0, 750.0]",
     ["table.size[0]", "less than or equal to", "9e+200"]),
    ("huge-location", PICK, "pick = [300.0, -180.0, 218.0", "pick = [3e100, -180.0, 218.0",
     ["locations.pick[0]", "less than or equal to", "3e+100"]),
    ("huge-seed", PICK, "seed = 1 ", "seed = 123456789012345678901234567890 ", ["physics.seed", "less than or equal to"]),
    ("negative-seed", PICK, "seed = 1 ", "seed = -1 ", ["physics.seed", "greater than or equal to 0", "-1"]),
    ("huge-tray", BELT, "rows = 4 ", "rows = 100000 ", ["tray[0].rows", "less than or equal to 100", "100000"]),
    # missing locations, sections and models
    ("missing-home", PICK, 'home = "start"', 'home = "strat"', ["robot.home", "'strat'", "not in [locations]", "start"]),
    ("no-locations", PICK, "[locations]\nstart", "[x_locations]\nstart", ["unknown section [x_locations]"]),
    ("missing-robot", PICK, "[robot]\nmodel", "[x_robot]\nmodel", ["unknown section [x_robot]"]),
    ("missing-required-key", PICK, "inner_size = [300.0, 300.0, 280.0]", "", ["bin[0].inner_size", "missing (required)"]),
    ("missing-robot-model", PICK, 'model = "models/robots/cobra_s600.xml"', "",
     ["robot.model", "missing (required)"]),
    ("robot-model-not-found", PICK, "models/robots/cobra_s600.xml", "models/robots/nope.xml",
     ["robot.model", "'models/robots/nope.xml'", "not found"]),
    ("gripper-model-not-found", PICK, 'model = "models/grippers/parallel_gripper.xml"', 'model = "models/grippers/claw.xml"',
     ["gripper.model", "'models/grippers/claw.xml'", "not found"]),
    ("robot-model-a-folder", PICK, "models/robots/cobra_s600.xml", "models/robots",
     ["robot.model", "'models/robots'", "not a file"]),
    ("robot-model-not-mjcf", PICK, "models/robots/cobra_s600.xml", "scenes/scara_pick.toml",
     ["robot.model", "'scenes/scara_pick.toml'", "not a MuJoCo model"]),
    ("mesh-not-found", PICK, 'shape = "box"\nsize = [30.0, 30.0, 20.0]', 'shape = "mesh"\nmesh = "nope.stl"',
     ["part[0].mesh", "'nope.stl'", "not found"]),
    ("gripper-site-unknown", PICK, 'site = "flange"', 'site = "flang"', ["gripper.site", "'flang'", "no site"]),
    # bad references between components
    ("unknown-part-type", PICK, 'part = "block"', 'part = "blok"', ["feeder[0].part", "'blok'", "[[part]]", "block"]),
    ("source-unknown-conveyor", BELT, 'conveyor = "infeed"\nparts', 'conveyor = "outfeed"\nparts',
     ["source[0].conveyor", "'outfeed'", "[[conveyor]]", "infeed"]),
    ("source-unknown-part", BELT, 'parts = ["block"]', 'parts = ["brick"]', ["source[0].parts[0]", "'brick'", "[[part]]"]),
    ("sensor-unknown-conveyor", BELT, 'conveyor = "infeed"\nposition = 200.0', 'conveyor = "belt"\nposition = 200.0',
     ["sensor[0].conveyor", "'belt'", "[[conveyor]]"]),
    ("latch-unknown-encoder", BELT, "latch_encoder = 1", "latch_encoder = 2", ["sensor[0].latch_encoder", "encoder 2"]),
    ("duplicate-names", PICK, "\n[[part]]", '\n[[bin]]\nname = "bin"\nfloor_center = [0.0, 0.0, 800.0]\n'
     'inner_size = [10.0, 10.0, 10.0]\n[[part]]', ["bin[1].name", "'bin'", "used twice"]),
    ("source-beyond-belt", BELT, "position = 40.0", "position = 4000.0", ["source[0].position", "4000", "beyond the belt"]),
    ("sensor-off-belt", BELT, "position = 200.0", "position = -5.0", ["sensor[0].position", "-5", "off the belt"]),
    ("weights-mismatch", BELT, 'parts = ["block"]', 'parts = ["block"]\nweights = [1.0, 2.0]',
     ["source[0]", "weights needs one value per entry of parts"]),
    ("input-wired-twice", BELT, "[[bin]]", '[[sensor]]\nname = "eye2"\ntype = "presence"\ninput = 1001\n'
     "lo = [0.0, 0.0, 0.0]\nhi = [1.0, 1.0, 1.0]\n[[bin]]", ["sensor[0].input", "input 1001 is wired twice"]),
    ("scatter-unknown-part", VISION, 'parts = ["plate", "plate", "plate", "square"]', 'parts = ["plate", "disc"]',
     ["scatter[0].parts[1]", "'disc'", "[[part]]"]),
    ("camera-unknown-mount", VISION, 'name = "top"', 'name = "top"\nmount = "robot/nowhere"', ["camera 'top': mount", "'robot/nowhere'", "no body"]),
    # not TOML
    ("toml-syntax", PICK, "speed = 200.0", "speed = = 200.0", ["not valid TOML", "line", "column"]),
    ("toml-duplicate-key", PICK, "speed = 200.0", "speed = 200.0\nspeed = 100.0", ["not valid TOML", "Cannot overwrite a value", "at line"]),
    ("toml-unclosed-string", PICK, 'name = "nest"', 'name = "nest', ["not valid TOML", "line"]),
    ("toml-unclosed-table", PICK, "[physics]", "[physics", ["not valid TOML", "Expected ']'", "at line"]),
]


def _broken(tmp_path, scene: str, old: str, new: str):
    text = (SCENES / f"{scene}.toml").read_text()
    assert old in text, old
    path = tmp_path / f"{scene}.toml"
    path.write_text(text.replace(old, new, 1))
    if scene == VISION:  # its calibration file, beside it
        (tmp_path / "scara_vision.top.calib.json").write_text((SCENES / "scara_vision.top.calib.json").read_text())
    return path


@pytest.fixture
def program(tmp_path):
    path = tmp_path / "nothing.pg"
    path.write_text(PROGRAM_TEXT)
    return path


def _twin_run(program, scene, capsys) -> str:
    """`twin run` on the scene: exit status 2 and one line on standard error, no traceback."""
    status = twin_main(["run", str(program), "--scene", str(scene)])
    out, err = capsys.readouterr()
    assert status == 2, (status, out, err)
    assert "Traceback" not in err and "ran" not in out
    assert err.count("\n") == 1, err
    assert f"{scene}: " in err, err  # the loader's "<file>: ..." or the command line's "scene <file>: ..."
    return err


@pytest.mark.parametrize("what, scene, old, new, words", CASES, ids=[c[0] for c in CASES])
def test_a_broken_scene_names_file_key_value_and_expectation(tmp_path, capsys, program, what, scene, old, new, words):
    path = _broken(tmp_path, scene, old, new)
    err = _twin_run(program, path, capsys)
    for word in words:
        assert word in err, err
    assert "pydantic" not in err and "Error" not in err.split(": ", 1)[1][:12]


def test_the_corpus_is_large_enough():
    assert len(CASES) + len(FILE_CASES) >= 60


def _empty(tmp_path):
    path = tmp_path / "empty.toml"
    path.write_text("")
    return path, ["robot: missing (required)"]


def _directory(tmp_path):
    path = tmp_path / "scene.toml"
    path.mkdir()
    return path, ["not a file"]


def _binary(tmp_path):
    path = tmp_path / "scene.toml"
    path.write_bytes(bytes(range(256)) * 4)
    return path, ["not valid TOML", "UTF-8"]


def _missing(tmp_path):
    return tmp_path / "nowhere.toml", ["no such"]


def _fifo(tmp_path):
    path = tmp_path / "scene.toml"
    os.mkfifo(path)  # opening it for reading would wait for a writer forever
    return path, ["not a file"]


def _comments_only(tmp_path):
    path = tmp_path / "scene.toml"
    path.write_text("# a scene\n# nothing else\n")
    return path, ["robot: missing (required)"]


def _array_top(tmp_path):
    path = tmp_path / "scene.toml"
    path.write_text("[[robot]]\nmodel = 'a'\n[[robot]]\nmodel = 'b'\n")
    return path, ["robot: expected a table"]


def _bom(tmp_path):
    """A byte order mark (as some Windows editors write) is not an error: the scene loads."""
    path = tmp_path / "scara_pick.toml"
    path.write_bytes(b"\xef\xbb\xbf" + (SCENES / "scara_pick.toml").read_bytes().replace(b"pool = 120", b"poll = 120"))
    return path, ["unknown key 'poll' in feeder[0]"]


FILE_CASES = [_empty, _directory, _binary, _missing, _fifo, _comments_only, _array_top, _bom]


@pytest.mark.parametrize("make", FILE_CASES, ids=[f.__name__[1:] for f in FILE_CASES])
def test_a_file_that_is_no_scene_is_a_clear_error(tmp_path, capsys, program, make):
    path, words = make(tmp_path)
    err = _twin_run(program, path, capsys)
    for word in words:
        assert word in err, err


def test_a_scene_with_a_byte_order_mark_loads():
    path = SCENES / "scara_pick.toml"
    assert load_scene(path) == tomllib.loads(path.read_text())


@pytest.mark.parametrize("what, scene, old, new, words", [CASES[0], CASES[40]], ids=["section", "nan"])
def test_by_subprocess_twin_run_exits_2_without_a_traceback(tmp_path, program, what, scene, old, new, words):
    path = _broken(tmp_path, scene, old, new)
    done = subprocess.run([sys.executable, "-m", "twin.cli", "run", str(program), "--scene", str(path)],
                          capture_output=True, text=True, timeout=120, cwd=tmp_path)
    assert done.returncode == 2, done.stderr
    assert "Traceback" not in done.stderr and all(w in done.stderr for w in words)


# ------------------------------------------------------------------ fuzzing
_BASE = tomllib.loads((SCENES / "scara_pick.toml").read_text())
_VALUES = st.one_of(st.none(), st.booleans(), st.integers(), st.floats(), st.text(max_size=8),
                    st.lists(st.floats(), max_size=7), st.lists(st.integers(), max_size=7),
                    st.dictionaries(st.text(max_size=6), st.floats(), max_size=3))


def _paths(value, prefix=()):
    if isinstance(value, dict):
        for k, v in value.items():
            yield prefix + (k,)
            yield from _paths(v, prefix + (k,))
    elif isinstance(value, list):
        for i, v in enumerate(value):
            yield prefix + (i,)
            yield from _paths(v, prefix + (i,))


_KEY_PATHS = list(_paths(_BASE))


def _has(node, key) -> bool:
    return (isinstance(node, dict) and isinstance(key, str)) or (
        isinstance(node, list) and isinstance(key, int) and key < len(node))


def _put(scene: dict, path: tuple, value) -> None:
    """scene[path] = value where the path still leads somewhere (an earlier edit may
    have replaced a table by a number)."""
    node = scene
    for key in path[:-1]:
        if not _has(node, key) or key not in (node if isinstance(node, dict) else range(len(node))):
            return
        node = node[key]
    if _has(node, path[-1]):
        node[path[-1]] = value


@settings(max_examples=300, derandomize=True, deadline=None, suppress_health_check=list(HealthCheck))
@given(st.lists(st.tuples(st.sampled_from(_KEY_PATHS), _VALUES), min_size=1, max_size=4))
def test_fuzzed_scenes_load_or_raise_scene_error(edits):
    """Values of every type put at random key paths of the demo scene: the loader returns
    the scene or raises SceneError, nothing else."""
    scene = copy.deepcopy(_BASE)
    for path, value in edits:
        _put(scene, path, value)
    try:
        validate_scene(scene, "fuzzed.toml")
    except SceneError as err:
        assert str(err).startswith("fuzzed.toml: ")


@settings(max_examples=300, derandomize=True, deadline=None, suppress_health_check=list(HealthCheck))
@given(st.binary(max_size=300) | st.text(alphabet=st.sampled_from(list('[]{}="., \n#abcdefpyrotsize0123456789.-+einaf\\\'\x00')),
                                         max_size=300).map(str.encode))
def test_fuzzed_bytes_load_or_raise_scene_error(tmp_path_factory, data):
    """Random bytes and TOML-like text as a scene file: SceneError or a scene."""
    path = tmp_path_factory.mktemp("bytes") / "scene.toml"
    path.write_bytes(data)
    try:
        load_scene(path)
    except SceneError as err:
        assert str(err).startswith(str(path))
