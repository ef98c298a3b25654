"""An example a CI user copies into their own tests/: run a program on the cell and assert
on where the parts ended.  Needs only `pip install twin` (the twin_run fixture comes with
it, through pytest's plugin entry point).  Run it with:

    pytest examples/test_pick_three.py
"""

from pathlib import Path

HERE = Path(__file__).resolve().parent
PROGRAM = HERE / "pick_three.pg"
SCENE = "scenes/scara_pick.toml"       # the bundled demo cell (or a path to your own)


def test_the_run_meets_its_expectation_file(twin_run):
    run = twin_run(PROGRAM, scene=SCENE)
    run.expect(HERE / "pick_three.expect.toml")


def test_the_fourth_part_waits_in_the_nest(twin_run):
    run = twin_run(PROGRAM, scene=SCENE)
    run.expect({"parts": {"pose": {"id": 3, "position": [300.0, -180.0, 860.0], "tolerance_mm": 2.0}}})
    assert run.report.regions["bin"] == 3
