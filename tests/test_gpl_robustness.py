"""Bad GPL programs and hostile projects (issue 14): every user error is a located GPL
error, never a Python traceback.  Wrong argument types to every library member are
GPL exceptions the program's own Try/Catch catches; sizes are bounded by the
controller's memory (-200); nesting is bounded (-2014); Project.gpr sources stay in
the project folder and are regular files (-2013)."""

from __future__ import annotations

import inspect
import os
from pathlib import Path

import pytest

from twin.errors import ProgramError
from twin.language.gpl.expressions import _library_kind, library_arity, library_has_instances
from twin.language.gpl.library import CLASSES, member
from twin.runner import run_program

from conftest import SCARA_SCENE as SCENE
from gpl_helpers import output_of, run_project

# One object of each built-in class that has objects (the sweep calls their members).
OBJECTS = {
    "location": "New Location", "refframe": "New RefFrame", "profile": "New Profile",
    "thread": 'New Thread("Worker")', "ipendpoint": 'New IPEndPoint("127.0.0.1", 5999)',
    "xmldoc": "New XmlDoc", "exception": "New Exception", "streamwriter": 'New StreamWriter("/flash/a.txt")',
}
WRONG = ['"abc"', "Nothing", "New Location"]  # a String that is not a number, Nothing, an object


def member_calls() -> list[str]:
    """A statement for every member of every built-in class that takes arguments (and
    every assignable property) with each wrong kind of value."""
    calls = []
    for key, cls in sorted(CLASSES.items()):
        has_objects = library_has_instances(cls)
        if has_objects and key not in OBJECTS:
            continue  # Socket, TcpClient...: made by other members, swept through those
        owner = f"o_{key}" if has_objects else cls.gpl_name
        for attr in sorted(set(cls.gpl_members.values())):
            raw = inspect.getattr_static(cls, attr)
            if attr.startswith("set_") or not attr[0].isupper() or \
                    not isinstance(raw, (property, staticmethod)) and not callable(raw):
                continue
            kind = _library_kind(cls, attr)
            if kind == "property":
                if has_objects and raw.fset is not None:
                    calls += [f"{owner}.{attr} = {w}" for w in WRONG]
                continue
            if kind != "shared" and not has_objects:
                continue
            low, high = library_arity(cls, attr)
            setter = member(cls, "set_" + attr)
            n = max(low, 1)
            if high < n:
                if setter:
                    calls += [f"{owner}.{attr} = {w}" for w in WRONG]
                continue
            for w in WRONG:
                args = ", ".join([w] * n)
                calls.append(f"{owner}.{attr}({args})")
                if setter:
                    calls.append(f"{owner}.{attr}({args}) = {w}")
    return calls


def test_wrong_argument_kinds_to_every_library_member_are_catchable_gpl_errors(tmp_path):
    """Every member of every built-in class, given a String that is not a number, Nothing
    or an object of another class for each argument, either accepts it or raises a GPL
    error that the program's own Catch sees (-717 Invalid number format, -782 Object is
    Nothing, -202 Invalid argument or the member's own code): the run ends normally."""
    calls = member_calls()
    assert len(calls) > 500
    body = "".join(f"        Try\n            {c}\n        Catch ex\n            Console.WriteLine(\"{i} \" & ex.ErrorCode)\n"
                   f"        End Try\n" for i, c in enumerate(calls))
    objects = "".join(f"        Dim o_{k} As {CLASSES[k].gpl_name} = {v}\n" for k, v in OBJECTS.items())
    folder = tmp_path / "sweep"
    folder.mkdir()
    (folder / "Project.gpr").write_text('ProjectBegin\nProjectStart="Main"\nProjectSource="Main.gpl"\nProjectEnd\n')
    (folder / "Main.gpl").write_text(
        "Module Sweep\n    Public Sub Worker()\n    End Sub\n    Public Sub Main()\n        Dim ex As Exception\n"
        + objects + "        Controller.PowerEnabled = True\n        Robot.Attached = 1\n        Robot.Home\n"
        + body + "        Console.WriteLine(\"done\")\n    End Sub\nEnd Module\n")
    report = run_program(folder, scene=SCENE, max_sim_time=60.0).report
    assert report.errors == []
    lines = report.output.splitlines()
    assert lines[-1] == "done"
    codes = {int(line.split()[1]) for line in lines if line[:1].isdigit()}
    assert {-717, -782, -202} <= codes
    assert all(code < 0 for code in codes)


@pytest.mark.parametrize("statement, code", [
    ('Thread.Sleep("abc")', -717), ('Signal.DIO("a") = True', -717), ('p.Speed = "fast"', -717),
    ("p.Speed = Nothing", -2004), ("Move.Loc(p, p)", -202), ('Controller.PDbNum("x")', -717),
])
def test_the_issues_examples_are_caught_by_the_programs_own_catch(statement, code):
    out = output_of(f"""
Module M
    Public Sub Main()
        Dim p As New Profile
        Try
            {statement}
        Catch ex As Exception
            Console.WriteLine(CStr(ex.ErrorCode))
        End Try
    End Sub
End Module
""")
    assert out == f"{code}\n"


# ------------------------------------------------------------ memory
@pytest.mark.parametrize("statements", [
    "Dim a(1000000000) As Integer",
    "Dim a(100000, 100000) As Double",
    "Dim a(1) As String\n        ReDim a(2000000000)",
    'Dim s As String = "ab"\n        While True\n            s = s & s\n        End While',
    'Dim s As String = "ab"\n        While True\n            s += s\n        End While',
])
def test_runaway_sizes_are_the_controllers_out_of_memory_error(statements):
    """Arrays above 4,194,304 elements and Strings above 16,777,216 characters are -200
    *No memory available* (docs/gpl.md: the twin's bounds for the controller's memory), never a
    Python MemoryError; the program's Catch sees it."""
    out = output_of(f"""
Module M
    Public Sub Main()
        Try
        {statements}
        Catch ex As Exception
            Console.WriteLine(CStr(ex.ErrorCode))
        End Try
    End Sub
End Module
""")
    assert out == "-200\n"


# ------------------------------------------------------------ nesting and long lines
def _nested(opener: str, closer: str, depth: int, extra: str = "") -> str:
    return ("Module M\n    Public Sub Main()\n" + extra + "".join(opener.format(k) + "\n" for k in range(depth))
            + "        Console.WriteLine(1)\n" + "".join(closer + "\n" for _ in range(depth))
            + "    End Sub\nEnd Module\n")


@pytest.mark.parametrize("opener, closer", [
    ("If True Then", "End If"), ("While False", "End While"), ("Do While False", "Loop"),
    ("For i{0} = 1 To 1", "Next"), ("Try", "Catch\nEnd Try"), ("Select Case 1\nCase 1", "End Select"),
])
@pytest.mark.parametrize("depth", [40, 300, 1500])
def test_deep_nesting_is_a_located_error_or_works(opener, closer, depth):
    """Blocks nested deeper than the compiler can go are -2014 at a line of the program,
    never a RecursionError (the parser itself does not recurse)."""
    declarations = "".join(f"Dim i{k} As Integer\n" for k in range(depth)) if "For" in opener else ""
    try:
        assert output_of(_nested(opener, closer, depth, declarations)) == "1\n"
    except ProgramError as err:
        assert err.code == -2014 and err.file == "test.gpl" and err.line and err.text is not None


@pytest.mark.parametrize("terms", [50, 2000, 50000])
def test_very_long_lines_are_a_located_error_or_work(terms):
    chain = " + ".join(["1"] * terms)
    parens = "(" * terms + "1" + ")" * terms
    text = "x" * (terms * 5)
    source = (f"Module M\n    Public Sub Main()\n        Dim x As Double\n        x = {chain}\n        x = {parens}\n"
              f"        Console.WriteLine(\"{text}\".Length)\n    End Sub\nEnd Module\n")
    try:
        assert output_of(source) == f"{terms * 5}\n"
    except ProgramError as err:
        assert err.code == -2014 and err.line == 4


# ------------------------------------------------------------ project files
def _project(tmp_path: Path, source_line: str) -> Path:
    folder = tmp_path / "proj"
    folder.mkdir(exist_ok=True)
    (folder / "Main.gpl").write_text("Module M\n    Public Sub Main()\n    End Sub\nEnd Module\n")
    (folder / "Project.gpr").write_text(f'ProjectBegin\nProjectStart="Main"\nProjectSource="{source_line}"\nProjectEnd\n')
    return folder


@pytest.mark.parametrize("source", ["/etc/passwd", "../secret.gpl", "..\\secret.gpl", "sub/../../secret.gpl",
                                    "C:\\secret.gpl", "link.gpl", "fifo.gpl", "dev.gpl", "folder.gpl", ""])
def test_project_sources_outside_the_folder_or_not_regular_files_are_refused(tmp_path, source):
    """ProjectSource must name a regular file of the project folder: an absolute path,
    `..`, a link out of the folder, a FIFO (which would hang), a device or a folder is
    -2013 at its Project.gpr line; the message never shows the other file's content."""
    secret = tmp_path / "secret.gpl"
    secret.write_text("TOP SECRET LINE\n")
    folder = _project(tmp_path, source)
    (folder / "link.gpl").symlink_to(secret)
    os.mkfifo(folder / "fifo.gpl")
    (folder / "dev.gpl").symlink_to("/dev/zero")
    (folder / "folder.gpl").mkdir()
    with pytest.raises(ProgramError) as caught:
        run_project(folder)
    err = caught.value
    assert err.code == -2013 and err.line == 3 and err.file.endswith("Project.gpr")
    assert "TOP SECRET" not in str(err) and "root:" not in str(err)


def test_a_fifo_project_file_is_refused_not_read(tmp_path):
    folder = tmp_path / "proj"
    folder.mkdir()
    os.mkfifo(folder / "Project.gpr")
    with pytest.raises(ProgramError) as caught:
        run_project(folder)
    assert caught.value.code == -2013


def test_a_subfolder_source_inside_the_project_is_allowed(tmp_path):
    folder = _project(tmp_path, "lib/Main.gpl")
    (folder / "lib").mkdir()
    (folder / "Main.gpl").rename(folder / "lib" / "Main.gpl")
    system, thread = run_project(folder)
    assert thread.error is None
