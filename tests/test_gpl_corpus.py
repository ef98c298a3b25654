"""Broken GPL programs and projects, as a careless or hostile user writes them (issue 14):
each one stops with the GPL error code, located at file, line and column with the source
line, and never with a Python exception (only ProgramError is caught here, so anything
else escaping fails the test).  Then the parser and compiler are fuzzed with hypothesis
(bounded, derandomized): whatever the text, a located error or a program that runs."""

from __future__ import annotations

import os
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from twin.errors import ProgramError

from gpl_helpers import run_gpl, run_project

HEADER = "Module M\n    Public Sub Main()\n"  # the body starts at line 3
FOOTER = "    End Sub\nEnd Module\n"


def outcome(text: str, max_cycles: int = 3000) -> ProgramError | None:
    """The error a program stops with, at load or when it runs; None if it ends normally."""
    try:
        _system, thread = run_gpl(text, max_cycles=max_cycles)
    except ProgramError as err:
        return err
    return thread.error


def main(*lines: str) -> str:
    return HEADER + "".join(f"        {line}\n" for line in lines) + FOOTER


# (name, source, code, line): `line` is where the error is reported.
CASES: list[tuple[str, str, int, int]] = []


def case(name: str, source: str, code: int, line: int) -> None:
    CASES.append((name, source, code, line))


# ---- wrong argument kinds to library members (run time: the thread stops, located)
for statement, code in [
    ('Thread.Sleep("abc")', -717), ("Thread.Sleep(Nothing)", -782), ("Thread.Sleep(New Location)", -202),
    ('Signal.DIO("a") = True', -717), ("Signal.DIO(Nothing) = True", -782), ('Signal.DIO(99999) = True', -1517),
    ('Controller.PDb("x")', -717), ("Controller.PDb(9999)", -1501), ("Controller.PDbNum(2002) = 3", -202),
    ('Controller.PDbNum(2002)', -202), ('Controller.PDb(2002, 7)', -1514), ('Controller.SystemSpeed = "x"', -717),
    ('Controller.SystemSpeed = 500', -202), ('Controller.SleepTick("x")', -717), ("Robot.Attached = 2", -1000),
    ('Robot.Attached = "one"', -717), ("Robot.Home", -1046), ("Move.Loc(Nothing, Nothing)", -782),
    ('Move.Loc("a", "b")', -202), ("Move.WaitForEOM(1, 2, 3)", -2005), ('Math.Sqrt("x")', -717),
    ("Math.Sqrt(-1)", -202), ('Math.Abs(Nothing)', -2004), ('Console.WriteLine(New Location)', -2004),
    ('Dim f As New StreamReader("/nowhere/x.txt")', -3111), ('Dim f As New StreamReader("/flash/none.txt")', -3110),
    ('Dim t As New Thread(Nothing)', -782), ('Dim e As New IPEndPoint("x", "y")', -717),
    ("Dim p As New Profile(1, 2)", -202), ('Dim l As New Location\n        l.XYZ("a")', -717),
    ('Dim l As New Location\n        l.Angle(1) = 3', -763), ('Dim l As New Location\n        l.Type = 7', -202),
    ('Dim l As New Location\n        l.X = "west"', -717), ('Dim p As New Profile\n        p.Speed = "fast"', -717),
    ('Dim p As New Profile\n        p.Speed = 0', -202), ('Dim p As New Profile\n        p.Accel = 200', -202),
    ('Dim p As New Profile\n        p.AccelRamp = -1', -202), ('Dim p As New Profile\n        p.InRange = "x"', -717),
    ('Dim r As New RefFrame\n        r.PalletIndex(1) = 2', -202), ('Dim r As New RefFrame\n        r.PalletOrder = 9', -202),
    ('Dim x As XmlDoc\n        x.SaveFile("/flash/a.xml")', -782), ('Dim e As New Exception\n        e.ErrorCode = "x"', -717),
    ("Throw New Exception(0)", -807), ('Thread.WaitEvent("x", 0)', -717),
]:
    body = statement.split("\n        ")
    case(f"library: {statement}", main(*body), code, 2 + len(body))

# ---- numbers
for statement, code in [
    ("a = 2147483647 + 1", -708), ("a = -2147483647 - 2", -708), ("a = 65536 * 65536", -708),
    ("a = 2147483647\n        a += 1", -708), ("a = 2147483647\n        a *= 2", -708),
    ("a = 1E10", -708), ('a = CInt("1E12")', -708), ("s = 40000", -708), ("s = -40000", -708),
    ("b = 256", -708), ("b = -1", -708), ("cells(1) = 3000000000", -708), ("cells(1) = 2147483647\n        cells(1) += 1", -708),
    ("a = CInt(1E300 * 1E300)", -708), ("d = 1E308 * 10", -710), ("d = -1E308 * 10", -710),
    ("d = 1E308 + 1E308", -710), ("d = 10 ^ 400", -710), ('d = CDbl("1E400")', -708), ("g = 1E39", -708),
    ("Console.WriteLine(1E308 * 1E308)", -710), ("Console.WriteLine(CStr(-1E308 * 1E308))", -710),
    ("a = 1 \\ 0", -709), ("d = 1 / 0", -709), ("a = 5 Mod 0", -709), ("d = 0 / 0", -709),
    ('a = CInt("twelve")', -717), ('d = CDbl("")', -717), ('d = "x" + 1', -717), ('a = "1,5"', -717),
    ("cells(5) = 1", -767), ("cells(-1) = 1", -767), ("a = cells(3)", -767), ("a = cells(1, 1)", -2006),
    ("d = (-8) ^ 0.5", -708),
]:
    body = statement.split("\n        ")
    decl = ["Dim a As Integer", "Dim s As Short", "Dim b As Byte", "Dim d As Double", "Dim g As Single",
            "Dim cells(2) As Integer"]
    case(f"number: {statement}", main(*decl, *body), code, 2 + len(decl) + len(body))

# ---- memory
for statement, line in [("Dim a(1000000000) As Integer", 3), ("Dim a(5000000) As Byte", 3),
                        ("Dim a(3000, 3000) As Double", 3), ("Dim a(100, 100, 100, 100) As Short", 3),
                        ("Dim a(1) As Integer\n        ReDim a(2000000000)", 4),
                        ('Dim a(1) As String\n        ReDim Preserve a(99999999)', 4),
                        ('Dim s As String = "abcd"\n        While True\n            s = s & s\n        End While', 5),
                        ('Dim s As String = "abcd"\n        While True\n            s = s + s\n        End While', 5)]:
    case(f"memory: {statement}", main(*statement.split("\n        ")), -200, line)

# ---- nesting and long lines
for depth in (70, 500, 2000):
    for opener, closer in [("If True Then", "End If"), ("While False", "End While"), ("Select Case 1", None)]:
        if closer is None:
            lines = [x for _ in range(depth) for x in ("Select Case 1", "Case 1")] + ["a = 1"] + ["End Select"] * depth
        else:
            lines = [opener] * depth + ["a = 1"] + [closer] * depth
        first_too_deep = 3 + 1 + (64 - 1) * (2 if closer is None else 1)
        case(f"nesting: {opener} x {depth}", main("Dim a As Integer", *lines), -2014, first_too_deep)
for n in (20000, 200000):
    case(f"long line: {n}", main("Dim a As Integer", "a = " + " + ".join(["1"] * (n // 4))), -2014, 4)
case("long line: expression too deep", main("Dim a As Double", "a = " + " + ".join(["1"] * 3000)), -2014, 4)

# ---- compile-time errors
for lines, code, line in [
    (["x = 1"], -2002, 3), (["Dim a As Integer", "a = b"], -2002, 4), (["Dim a As Widget"], -2002, 3),
    (["Dim a As Integer", "Dim a As Integer"], -2003, 4), (["Dim a"], -2004, 3), (['Dim a As Integer = New Location'], -2004, 3),
    (["Dim l As Location = 5"], -2004, 3), (["Dim a As Long"], -2010, 3), (["Dim a As Object"], -2010, 3),
    (["Console.WriteLine()", "Math.Sqrt(1, 2)"], -2005, 4), (["Dim c As New Controller"], -2006, 3),
    (["Exit For"], -2006, 3), (["Exit Try"], -2006, 3), (["Return 5"], -2006, 3), (["GoTo nowhere"], -2002, 3),
    (["Next"], -2001, 3), (["End If"], -2001, 3), (["If 1 Then"], -2001, 4), (["For i = 1 To"], -2001, 3),
    (['Console.WriteLine("abc)'], -2001, 3), (["a = 5 $ 3"], -2001, 3), (["Dim 1a As Integer"], -2001, 3),
    (["Dim a() As Double = {1, 2}"], -2001, 3), (["Loop"], -2001, 3), (["Catch"], -2001, 3),
    (["Dim a As Integer", "ReDim a(3)"], -2004, 4), (["Dim a(2, 2) As Integer", "ReDim a(3)"], -2006, 4),
    (["Dim k As Integer", "k.Value = 1"], -2002, 4), (["Me.x = 1"], -787, 3),
    (["Dim t As New Thread(AddressOf Missing)"], -2002, 3), (["Robot.NoSuchThing = 1"], -2002, 3),
    (["Dim x As Integer = Robot.NoSuchValue"], -2002, 3), (["Console.WriteLine(GPL_NOPE)"], -2002, 3),
    (["Try", "Finally", "GoTo out", "End Try", "out:"], -2011, 5),
    (["Try", "Catch", "GoTo out", "End Try", "out:"], -2011, 5),
    (["GoTo inside", "If True Then", "inside:", "End If"], -2011, 3),
]:
    case(f"compile: {' / '.join(lines)}", main(*lines), code, line)
for source, code, line in [
    ("Module M\n    Public Const C As Integer = 1\n    Public Sub Main()\n        C = 2\n    End Sub\nEnd Module\n", -2007, 4),
    ("Module M\n    Private Sub Hidden()\n    End Sub\nEnd Module\nModule N\n    Public Sub Main()\n        M.Hidden()\n"
     "    End Sub\nEnd Module\n", -2008, 7),
    ("Module A\n    Public x As Integer\nEnd Module\nModule B\n    Public x As Integer\nEnd Module\nModule M\n"
     "    Public Sub Main()\n        x = 1\n    End Sub\nEnd Module\n", -2009, 9),
    ("Module M\n    Public Const X As Integer = Y\n    Public Const Y As Integer = X\n    Public Sub Main()\n"
     "    End Sub\nEnd Module\n", -2006, 2),
    ("Module M\n    Sub Main()\n    End Sub\nEnd Module\n", -2012, None),
    ("Class C\n    Public v As Integer\nEnd Class\nModule M\n    Public Sub Main()\n        Dim c As New C\n"
     "        c.w = 1\n    End Sub\nEnd Module\n", -2002, 7),
    ("Module M\n    Public Sub Main()\n        Dim n As Integer\n        n = F(1, 2)\n    End Sub\n"
     "    Function F(ByVal a As Integer) As Integer\n        Return a\n    End Function\nEnd Module\n", -2005, 4),
    ("Delegate Sub D(ByVal x As Integer)\nModule M\n    Sub Two(ByVal a As Integer, ByVal b As Integer)\n    End Sub\n"
     "    Public Sub Main()\n        Dim d As New D(AddressOf Two)\n    End Sub\nEnd Module\n", -2004, 6),
]:
    case(f"module: {source.splitlines()[1].strip()}", source, code, line)

# ---- run-time errors
for lines, code, line in [
    (["Dim l As Location", "l.X = 1"], -782, 4), (["Dim l As Location", "Console.WriteLine(l.X)"], -782, 4),
    (["Dim e As Exception", "Throw e"], -782, 4), (["Throw New Exception(-1234)"], -1234, 3),
    (["Dim s As String = \"abc\"", "Console.WriteLine(s.Substring(5))"], -202, 4),
    (["Dim a(2) As Integer", "Console.WriteLine(a.GetUpperBound(3))"], -767, 4),
    (['Dim x As New XmlDoc', 'x = XmlDoc.LoadString("<a>")', 'Console.WriteLine(x.DocumentElement.Name)'], -782, 5),
]:
    case(f"run: {' / '.join(lines)}", main(*lines), code, line)


def test_the_corpus_has_the_issues_size():
    assert len(CASES) >= 150


@pytest.mark.parametrize("name, source, code, line", CASES, ids=[c[0][:60] for c in CASES])
def test_each_broken_program_stops_with_its_located_gpl_error(name, source, code, line):
    err = outcome(source)
    assert err is not None, "the program should stop with an error"
    assert err.code == code, str(err)
    if line is not None:
        assert err.file == "test.gpl" and err.line == line and err.column, str(err)
        written = source.splitlines()[line - 1].strip()
        shown = (err.text or "").strip()
        assert shown == written or shown.endswith("...") and written.startswith(shown[:-3]), str(err)
    assert err.message and "Traceback" not in err.message


# ---- projects
def _project(tmp_path: Path, gpr: str, files: dict[str, str] | None = None) -> Path:
    folder = tmp_path / "proj"
    folder.mkdir()
    (folder / "Project.gpr").write_text(gpr)
    for name, text in (files or {"Main.gpl": "Module M\n    Public Sub Main()\n    End Sub\nEnd Module\n"}).items():
        (folder / name).write_text(text)
    return folder


PROJECTS = [
    ("absolute path", 'ProjectBegin\nProjectSource="/etc/passwd"\nProjectEnd\n', 2),
    ("dot dot", 'ProjectBegin\nProjectSource="../x.gpl"\nProjectEnd\n', 2),
    ("dot dot inside", 'ProjectBegin\nProjectSource="a/../../x.gpl"\nProjectEnd\n', 2),
    ("backslash dot dot", 'ProjectBegin\nProjectSource="..\\\\x.gpl"\nProjectEnd\n', 2),
    ("drive", 'ProjectBegin\nProjectSource="C:\\\\x.gpl"\nProjectEnd\n', 2),
    ("missing", 'ProjectBegin\nProjectSource="Nope.gpl"\nProjectEnd\n', 2),
    ("empty name", 'ProjectBegin\nProjectSource=""\nProjectEnd\n', 2),
    ("not key value", 'ProjectBegin\nthis is not a project\nProjectEnd\n', 2),
    ("device", 'ProjectBegin\nProjectSource="zero.gpl"\nProjectEnd\n', 2),
    ("fifo", 'ProjectBegin\nProjectSource="pipe.gpl"\nProjectEnd\n', 2),
    ("folder", 'ProjectBegin\nProjectSource="sub"\nProjectEnd\n', 2),
    ("link out", 'ProjectBegin\nProjectSource="out.gpl"\nProjectEnd\n', 2),
]


@pytest.mark.parametrize("name, gpr, line", PROJECTS, ids=[p[0] for p in PROJECTS])
def test_each_broken_project_file_is_a_located_2013(tmp_path, name, gpr, line):
    folder = _project(tmp_path, gpr)
    (folder / "zero.gpl").symlink_to("/dev/zero")
    os.mkfifo(folder / "pipe.gpl")
    (folder / "sub").mkdir()
    (tmp_path / "x.gpl").write_text("SECRET CONTENT\n")
    (folder / "out.gpl").symlink_to(tmp_path / "x.gpl")
    with pytest.raises(ProgramError) as caught:
        run_project(folder)
    err = caught.value
    assert err.code == -2013 and err.line == line and err.file.endswith("Project.gpr"), str(err)
    assert "SECRET" not in str(err)


# ---- fuzzing
_WORDS = ["Module M", "End Module", "Public Sub Main()", "End Sub", "Dim", "a", "As", "Integer", "Double", "String",
          "Location", "New", "=", "+", "-", "*", "/", "\\", "^", "&", "(", ")", ",", ".", "If", "Then", "Else", "End If",
          "For", "To", "Step", "Next", "While", "End While", "Do", "Loop", "Try", "Catch", "Finally", "End Try",
          "Select Case", "Case", "End Select", "GoTo", "lbl:", "Return", "Exit", "Sub", "Function", "Class", "End Class",
          "ByRef", "ByVal", "Const", "Shared", "ReDim", "Preserve", "Not", "And", "Or", "Xor", "Mod", "Nothing", "Me",
          "Console.WriteLine", "Thread.Sleep", "Controller.PDb", "Signal.DIO", "Move.Loc", '"s"', "1", "2.5", "1E400",
          "&HFF", "_", "\n", "\n", "\n", " ", "'", "#If", "AddressOf", "Delegate", "Throw", "True", "False"]

_PROGRAM = st.lists(st.sampled_from(_WORDS), min_size=1, max_size=60).map(" ".join)


def _only_located_errors(text: str) -> None:
    err = outcome(text, max_cycles=50)
    if err is not None:
        assert err.code is not None and err.message, repr(text)
        assert err.file is None or err.file == "test.gpl"


@settings(max_examples=250, derandomize=True, deadline=None, suppress_health_check=list(HealthCheck))
@given(_PROGRAM)
def test_fuzzed_token_soup_gives_only_located_gpl_errors(text):
    _only_located_errors(text)


_VALID = main("Dim a As Integer", "Dim s As String = \"x\"", "For a = 1 To 3", "s = s & a", "Next",
              "If a > 2 Then", "Console.WriteLine(s)", "End If", "Try", "a = a \\ 0", "Catch e As Exception",
              "Console.WriteLine(e.ErrorCode)", "End Try")


@settings(max_examples=250, derandomize=True, deadline=None, suppress_health_check=list(HealthCheck))
@given(st.integers(0, len(_VALID) - 1), st.integers(0, 40), st.text(alphabet='()=+-*"&._\n ,aE1', max_size=8))
def test_fuzzed_edits_of_a_valid_program_give_only_located_gpl_errors(position, cut, insert):
    _only_located_errors(_VALID[:position] + insert + _VALID[position + cut:])
