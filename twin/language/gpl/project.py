"""Project.gpr: which files make a GPL project and where it starts.

The User Manual (ch. 17) says only that Project.gpr lists the project's files
and names the start procedure.  The format follows project files written by
the PreciseFlex development environment (digest §12): `Key="value"` lines
between `ProjectBegin` and `ProjectEnd`, keys case-insensitive, `'` comments:

    ProjectBegin
    ProjectName="Pallet_demo"
    ProjectStart="Main"
    ProjectSource="Main.gpl"
    ProjectSource="Globals.gpo"
    ProjectEnd

Files load in the listed order (module initialisers and Init subs run in that
order).  Without ProjectSource lines every .gpo file, then every .gpl file of
the folder is loaded, in name order.  Other keys are ignored.
"""

from __future__ import annotations

import os
import re
import stat
from dataclasses import dataclass
from pathlib import Path, PureWindowsPath

from ...errors import ProgramError
from .errors import PROJECT_FILE_ERROR, message

_LINE = re.compile(r'^\s*([A-Za-z_][A-Za-z0-9_]*)\s*=\s*"?([^"]*)"?\s*$')


@dataclass
class ProjectFile:
    name: str
    start: str | None
    sources: list[Path]


def read_project(folder: Path) -> ProjectFile:
    gpr = next((p for p in folder.iterdir() if p.name.lower() == "project.gpr"), None) if folder.is_dir() else None
    if gpr is None:
        raise ProgramError(f"{message(PROJECT_FILE_ERROR)}: no Project.gpr in {folder}", PROJECT_FILE_ERROR,
                           file=str(folder))
    if not regular_file(gpr):
        raise ProgramError(f"{message(PROJECT_FILE_ERROR)}: {gpr.name} is not a regular file", PROJECT_FILE_ERROR,
                           file=str(gpr))
    name, start, sources = folder.name, None, []
    text = gpr.read_text(encoding="latin-1").removeprefix("\xef\xbb\xbf")  # byte-order mark
    for number, raw in enumerate(text.splitlines(), start=1):
        line = raw.strip()
        if not line or line.startswith("'") or line.lower() in ("projectbegin", "projectend"):
            continue
        match = _LINE.match(line)
        if match is None:
            raise ProgramError(f"{message(PROJECT_FILE_ERROR)}: expected Key=\"value\"", PROJECT_FILE_ERROR,
                               file=str(gpr), line=number, column=1, text=raw)
        key, value = match.group(1).lower(), match.group(2).strip()
        if key == "projectname":
            name = value
        elif key == "projectstart":
            start = value
        elif key == "projectsource":
            sources.append(_source(folder, value, gpr, number, raw))
    if not sources:
        files = sorted(p for p in folder.iterdir() if p.suffix.lower() in (".gpo", ".gpl") and _inside(folder, p))
        sources = [p for p in files if p.suffix.lower() == ".gpo"] + [p for p in files if p.suffix.lower() == ".gpl"]
    return ProjectFile(name, start, sources)


def _source(folder: Path, value: str, gpr: Path, number: int, raw: str) -> Path:
    """A ProjectSource file: inside the project folder (no absolute path, no `..`, no
    link out of it) and a regular file (a FIFO or a device would hang or be endless).
    The error quotes the Project.gpr line, never the file's content."""
    def refuse(why: str) -> ProgramError:
        return ProgramError(f"{message(PROJECT_FILE_ERROR)}: ProjectSource {value}: {why}", PROJECT_FILE_ERROR,
                            file=str(gpr), line=number, column=1, text=raw)

    relative = PureWindowsPath(value) if "\\" in value else Path(value)
    if relative.is_absolute() or relative.anchor or ".." in relative.parts or not value:
        raise refuse("must be a file of the project folder (no absolute path, no ..)")
    path = _find(folder, Path(*relative.parts))
    if path is None:
        raise refuse(f"no such file in {folder}")
    if not _inside(folder, path):
        raise refuse("is a link out of the project folder")
    if not regular_file(path):
        raise refuse("not a regular file")
    return path


def regular_file(path: Path) -> bool:
    """Whether path is a regular file (not a FIFO, device, socket or folder)."""
    try:
        return stat.S_ISREG(os.stat(path).st_mode)
    except OSError:
        return False


def _inside(folder: Path, path: Path) -> bool:
    try:
        return path.resolve().is_relative_to(folder.resolve())
    except (OSError, RuntimeError):  # a symlink loop
        return False


def _find(folder: Path, name: Path) -> Path | None:
    """A listed file; names match case-insensitively (the files may come from Windows)."""
    exact = folder / name
    if exact.exists():
        return exact
    parent = folder / name.parent
    if not parent.is_dir():
        return None
    return next((p for p in parent.iterdir() if p.name.lower() == name.name.lower()), None)
