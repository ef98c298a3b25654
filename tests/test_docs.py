"""The commands in the user pages of docs/ work as written.

Every line that starts with `$ ` inside a ```console block of these pages is run, in order,
in a scratch directory holding a copy of examples/ (the scenes and programs the commands
name are the bundled ones, found from any directory), and must exit 0.  The ```python
blocks of docs/notebooks.md run in order as one script, as a notebook user would type them.
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from conftest import ROOT

PAGES = ["ci.md", "offline.md"]


def commands(page: Path) -> list[str]:
    blocks = re.findall(r"```console\n(.*?)```", page.read_text(), re.S)
    return [line[2:] for block in blocks for line in block.splitlines() if line.startswith("$ ")]


@pytest.mark.parametrize("name", PAGES)
def test_the_commands_of_a_docs_page_run(name, tmp_path):
    page = ROOT / "docs" / name
    found = commands(page)
    assert found, f"{page} has no console commands"
    shutil.copytree(ROOT / "examples", tmp_path / "examples", ignore=shutil.ignore_patterns("__pycache__"))
    env = {**os.environ, "PATH": f"{Path(sys.executable).parent}{os.pathsep}{os.environ['PATH']}",
           "MUJOCO_GL": os.environ.get("MUJOCO_GL", "egl")}
    for command in found:
        run = subprocess.run(command, shell=True, cwd=tmp_path, env=env, capture_output=True, text=True)
        assert run.returncode == 0, f"{name}: `{command}` exited {run.returncode}:\n{run.stdout}\n{run.stderr}"


def test_the_python_of_the_notebook_page_runs(tmp_path):
    page = ROOT / "docs" / "notebooks.md"
    script = "\n".join(re.findall(r"```python\n(.*?)```", page.read_text(), re.S))
    (tmp_path / "page.py").write_text(script)
    env = {**os.environ, "MUJOCO_GL": os.environ.get("MUJOCO_GL", "egl")}
    run = subprocess.run([sys.executable, "page.py"], cwd=tmp_path, env=env, capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    lines = run.stdout.splitlines()
    assert lines[0] == "time" and abs(float(lines[2]) - 50.8) < 1e-4   # height2, a V+ real (single precision)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["page.py"]
