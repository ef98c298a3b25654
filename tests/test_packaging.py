"""The wheel carries everything `twin run` needs and works outside the repository.

A wheel is built from (a copy of) the checkout, installed into a fresh virtual environment
whose only other contents are this environment's third-party packages (a .pth file points at
them: no download, and neither the repository nor the editable install of twin is on the
path), and the bundled demo runs from an empty temporary directory.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import sysconfig
from pathlib import Path

import pytest

from twin.resources import bundled, find_user_file, resource_root

from conftest import ROOT

SOURCES = ["pyproject.toml", "setup.py", "MANIFEST.in", "README.md", "constraints.txt",
           "twin", "models", "scenes", "programs"]


def test_a_checkout_reads_its_resources_where_they_are():
    assert resource_root() == ROOT
    assert bundled("scenes/scara_pick.toml") == ROOT / "scenes" / "scara_pick.toml"


def test_a_relative_path_that_does_not_exist_is_looked_up_among_the_resources(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert find_user_file("programs/vplus/move_parts.pg") == ROOT / "programs" / "vplus" / "move_parts.pg"
    (tmp_path / "programs" / "vplus").mkdir(parents=True)
    own = tmp_path / "programs" / "vplus" / "move_parts.pg"
    own.write_text(".PROGRAM x()\n.END\n")
    assert find_user_file("programs/vplus/move_parts.pg").resolve() == own   # the user's file wins
    assert find_user_file("nothing/here.pg") == Path("nothing/here.pg")


def build_wheel(work: Path) -> Path:
    """The wheel of (a copy of) this checkout, built in `work` without build isolation."""
    src = work / "src"
    src.mkdir()
    for name in SOURCES:
        item = ROOT / name
        if item.is_dir():
            shutil.copytree(item, src / name, ignore=shutil.ignore_patterns("__pycache__", "*.egg-info"))
        else:
            shutil.copy2(item, src / name)
    dist = work / "dist"
    subprocess.run([sys.executable, "-m", "pip", "wheel", "-q", "--no-deps", "--no-build-isolation",
                    "--disable-pip-version-check", "-w", str(dist), "."], cwd=src, check=True)
    (wheel,) = dist.glob("twin-*.whl")
    return wheel


@pytest.fixture(scope="module")
def installed(tmp_path_factory) -> Path:
    """A fresh venv with the wheel built from this checkout; returns its bin/ folder."""
    work = tmp_path_factory.mktemp("wheel")
    wheel = build_wheel(work)
    venv = work / "venv"
    subprocess.run([sys.executable, "-m", "venv", "--without-pip", str(venv)], check=True)
    site = Path(sysconfig.get_paths(vars={"base": str(venv), "platbase": str(venv)})["purelib"])
    ours = Path(sysconfig.get_paths()["purelib"])
    # Third-party packages from here ("00-" sorts first: the .pth files copied below import
    # from that folder); the editable twin's hook is left out.
    (site / "00-twin-test-dependencies.pth").write_text(f"{ours}\n")
    for pth in ours.glob("*.pth"):
        if not pth.name.startswith(("__editable__", "distutils-precedence")):
            shutil.copy2(pth, site / pth.name)
    subprocess.run([sys.executable, "-m", "pip", "--python", str(venv / "bin" / "python"), "install", "-q",
                    "--no-deps", "--disable-pip-version-check", str(wheel)], check=True)
    return venv / "bin"


def clean_env() -> dict:
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "PYTHONHOME", "VIRTUAL_ENV")}
    env.setdefault("MUJOCO_GL", "egl")
    return env


def test_the_installed_package_is_the_wheels_and_knows_its_version(installed, tmp_path):
    probe = subprocess.run(
        [str(installed / "python"), "-c",
         "import sys, twin, twin.resources as r; print(twin.__file__); print(r.resource_root()); "
         "print(any(p.rstrip('/') == sys.argv[1] for p in sys.path))", str(ROOT)],
        cwd=tmp_path, env=clean_env(), capture_output=True, text=True, check=True)
    module, resources, repo_on_path = probe.stdout.split("\n")[:3]
    venv = installed.parent
    assert Path(module).is_relative_to(venv) and Path(resources).is_relative_to(venv)
    assert Path(resources, "models", "robots", "cobra_s600.xml").is_file()
    assert repo_on_path == "False"
    version = subprocess.run([str(installed / "twin"), "--version"], capture_output=True, text=True, check=True)
    assert version.stdout.strip() == "twin 0.1.0"


@pytest.mark.parametrize("program", ["programs/vplus/move_parts.pg", "programs/gpl/pick_place"])
def test_the_bundled_demo_runs_from_an_empty_directory(installed, tmp_path, program):
    run = subprocess.run(
        [str(installed / "twin"), "run", program, "--max-sim-time", "6", "--report", "report.json"],
        cwd=tmp_path, env=clean_env(), capture_output=True, text=True)
    assert "Traceback" not in run.stderr
    report = json.loads((tmp_path / "report.json").read_text())
    # Stopped by the time limit (and only by it), having put parts on the belt and in the bin.
    assert run.returncode == 1
    assert [e["message"] for e in report["errors"]] == ["*Simulation time limit reached* (6 s)"]
    assert Path(report["scene"]).is_relative_to(installed.parent)
    assert sum(report["regions"].get(r, 0) for r in ("bin", "conveyor")) >= 2
    assert sorted(p.name for p in tmp_path.iterdir()) == ["report.json"]
