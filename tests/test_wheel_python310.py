"""The oldest Python twin declares, 3.10: the wheel installs into a fresh 3.10 virtual
environment with its dependencies pinned by constraints.txt (the python_version < "3.11"
lines: mujoco 3.17, numpy 2.2, rerun-sdk 0.39...), and `twin run` of the bundled demo works
from an empty directory, recording included.

It needs a Python 3.10 interpreter: $TWIN_PYTHON310, else `python3.10` on the PATH, else
pyenv's (~/.pyenv/versions/3.10.*); skipped when there is none.  Slow: the dependencies are
installed from the package index (pip's cache makes a second run quick).
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
from pathlib import Path

import pytest

from conftest import ROOT
from test_packaging import build_wheel, clean_env

pytestmark = pytest.mark.slow


def _python310() -> str | None:
    candidates = [os.environ.get("TWIN_PYTHON310"), shutil.which("python3.10"),
                  *sorted(str(p) for p in Path.home().glob(".pyenv/versions/3.10.*/bin/python3.10"))]
    for candidate in filter(None, candidates):
        probe = subprocess.run([candidate, "-c", "import sys; print(sys.version_info[:2] == (3, 10))"],
                               capture_output=True, text=True)
        if probe.returncode == 0 and probe.stdout.strip() == "True":   # a pyenv shim may say no
            return candidate
    return None


PYTHON310 = _python310()


@pytest.fixture(scope="module")
def venv310(tmp_path_factory) -> Path:
    if PYTHON310 is None:
        pytest.skip("no Python 3.10 interpreter here (set TWIN_PYTHON310)")
    work = tmp_path_factory.mktemp("py310")
    wheel = build_wheel(work)
    venv = work / "venv"
    subprocess.run([PYTHON310, "-m", "venv", str(venv)], check=True)
    pip = [str(venv / "bin" / "python"), "-m", "pip", "--disable-pip-version-check", "-q"]
    subprocess.run([*pip, "install", "-c", str(ROOT / "constraints.txt"), str(wheel)], check=True, timeout=1200)
    return venv / "bin"


def test_the_wheel_on_python_310_imports_with_the_older_dependencies(venv310, tmp_path):
    probe = subprocess.run(
        [str(venv310 / "python"), "-c",
         "import sys, mujoco, numpy, rerun, twin, twin.notebook, twin.recorder, twin.check, twin.sweep; "
         "print('.'.join(map(str, sys.version_info[:2])), mujoco.__version__, twin.__file__, sep='\\n')"],
        cwd=tmp_path, env=clean_env(), capture_output=True, text=True)
    assert probe.returncode == 0, probe.stderr
    version, mujoco_version, module = probe.stdout.splitlines()[-3:]
    assert version == "3.10" and mujoco_version.startswith("3.")
    assert Path(module).is_relative_to(venv310.parent)


def test_the_demo_runs_and_records_on_python_310(venv310, tmp_path):
    run = subprocess.run(
        [str(venv310 / "twin"), "run", "programs/vplus/move_parts.pg", "--max-sim-time", "6",
         "--report", "report.json", "--rrd", "run.rrd"],
        cwd=tmp_path, env=clean_env(), capture_output=True, text=True, timeout=600)
    assert "Traceback" not in run.stderr, run.stderr
    report = json.loads((tmp_path / "report.json").read_text())
    assert run.returncode == 1   # stopped by the time limit, and only by it
    assert [e["message"] for e in report["errors"]] == ["*Simulation time limit reached* (6 s)"]
    assert sum(report["regions"].get(r, 0) for r in ("bin", "conveyor")) >= 2
    assert (tmp_path / "run.rrd").stat().st_size > 100_000
