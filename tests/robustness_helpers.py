"""Shared by the tests/test_robustness_*.py corpus: run the command line in-process and
capture what it prints, write V+ files and GPL projects into a temporary folder."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from twin.cli import main as twin_main


@dataclass
class CliResult:
    status: int
    out: str
    err: str


def run_cli(capsys, *argv: str) -> CliResult:
    """`twin ARGV...` in this process: exit status, standard output and error."""
    capsys.readouterr()  # drop what earlier steps printed
    status = twin_main([str(a) for a in argv])
    captured = capsys.readouterr()
    return CliResult(status, captured.out, captured.err)


def vplus_file(folder: Path, source: str, name: str = "prog.pg") -> Path:
    path = folder / name
    path.write_text(source.strip() + "\n", encoding="latin-1")
    return path


def gpl_project(folder: Path, module: str, name: str = "proj") -> Path:
    """A GPL project folder holding one module (Main.gpl) that starts at Main."""
    project = folder / name
    project.mkdir()
    (project / "Project.gpr").write_text(
        f'ProjectBegin\nProjectName="{name}"\nProjectStart="Main"\nProjectSource="Main.gpl"\nProjectEnd\n')
    (project / "Main.gpl").write_text(module.strip() + "\n")
    return project


def gpl_main(body: str, extra: str = "") -> str:
    """A module whose Main runs `body` (indented by the caller), with `extra` procedures."""
    return f"Module M\n    Public Sub Main()\n{body}\n    End Sub\n{extra}\nEnd Module\n"
