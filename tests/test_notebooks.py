"""The notebooks in notebooks/ run clean (nbclient, a fresh kernel) and draw their plots.

They run from an empty temporary directory, on the bundled scene and programs, and must
leave nothing in the repository (the notebook files are read, not written back)."""

from __future__ import annotations

import subprocess

import nbformat
import pytest
from nbclient import NotebookClient

from conftest import ROOT

NOTEBOOKS = sorted((ROOT / "notebooks").glob("*.ipynb"))


def _repository_state() -> str:
    return subprocess.run(["git", "status", "--porcelain", "--untracked-files=all"], cwd=ROOT,
                          capture_output=True, text=True).stdout


@pytest.mark.parametrize("path", NOTEBOOKS, ids=[p.stem for p in NOTEBOOKS])
def test_the_notebook_runs_clean_and_draws_its_plots(path, tmp_path, monkeypatch):
    monkeypatch.setenv("MPLBACKEND", "module://matplotlib_inline.backend_inline")
    before = _repository_state()
    notebook = nbformat.read(path, as_version=4)
    NotebookClient(notebook, timeout=300, kernel_name="python3", resources={"metadata": {"path": str(tmp_path)}}).execute()
    outputs = [o for cell in notebook.cells if cell.cell_type == "code" for o in cell.outputs]
    assert not [o for o in outputs if o.output_type == "error"]
    images = [o for o in outputs if "image/png" in o.get("data", {})]
    assert len(images) == (3 if path.stem == "getting_started" else 1)   # every plot drawn
    for cell in notebook.cells:
        if cell.cell_type == "code" and ".viewer(" in cell.source:   # the inline Rerun viewer, shown
            assert any("application/vnd.jupyter.widget-view+json" in o.get("data", {}) for o in cell.outputs)
    assert _repository_state() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == []
