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

import re
from dataclasses import dataclass
from pathlib import Path

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
            path = _find(folder, value)
            if path is None:
                raise ProgramError(f"{message(PROJECT_FILE_ERROR)}: no file {value} in {folder}",
                                   PROJECT_FILE_ERROR, file=str(gpr), line=number, column=1, text=raw)
            sources.append(path)
    if not sources:
        files = sorted(p for p in folder.iterdir() if p.suffix.lower() in (".gpo", ".gpl"))
        sources = [p for p in files if p.suffix.lower() == ".gpo"] + [p for p in files if p.suffix.lower() == ".gpl"]
    return ProjectFile(name, start, sources)


def _find(folder: Path, name: str) -> Path | None:
    """A listed file; names match case-insensitively (the files may come from Windows)."""
    exact = folder / name
    if exact.exists():
        return exact
    return next((p for p in folder.iterdir() if p.name.lower() == name.lower()), None)
