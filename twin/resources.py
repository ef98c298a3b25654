"""The files `twin run` needs besides the code: robot and gripper models, the demo scenes
and programs (the grammars live beside their parsers).

In the repository they are the top-level folders `models/`, `scenes/` and `programs/`
(other work adds files there, so they stay where they are).  The wheel carries copies of
them in the package as `twin/data/<folder>/...` (setup.py's build step copies them), and
they are found there through `importlib.resources`.  An editable install or a plain
checkout has no `twin/data`; the folders are then read where they are, beside the package.

A path a user gives (`twin run programs/vplus/move_parts.pg --scene scenes/scara_pick.toml`)
is taken as it is when it exists; a relative path that does not exist is then looked up
among these resources, so the README's commands work from any directory once installed.
"""

from __future__ import annotations

from importlib.resources import files
from pathlib import Path

__all__ = ["FOLDERS", "resource_root", "bundled", "find_user_file"]

FOLDERS = ("models", "scenes", "programs")


def resource_root() -> Path:
    """The folder that holds models/, scenes/ and programs/."""
    packaged = files("twin") / "data"
    if packaged.is_dir():
        # A wheel installed on a file system (the only way twin is installed: MuJoCo reads
        # model files by name, so a zipped package could not work anyway).
        return Path(str(packaged))
    return Path(__file__).resolve().parent.parent   # a checkout / editable install


def bundled(relative: str | Path) -> Path:
    """A bundled resource by its repository-relative path, e.g. 'scenes/scara_pick.toml'."""
    return resource_root() / Path(relative)


def find_user_file(path: str | Path) -> Path:
    """`path` as given when it exists (or is absolute); else the bundled resource with that
    relative path when there is one; else `path` unchanged (the caller reports it missing)."""
    path = Path(path)
    if path.exists() or path.is_absolute():
        return path
    candidate = bundled(path)
    return candidate if candidate.exists() else path
