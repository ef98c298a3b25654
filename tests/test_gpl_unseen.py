"""GPL projects written the way a PreciseFlex programmer writes them (Project.gpr, several
.gpl modules, a .gpo of taught data), not taken from the manual: tests/data/gpl/<project>/.
Each expected output is worked out from the manual's rules (cited per test), not pasted
from a run.  The second half feeds the interpreter malformed projects: every one must stop
with the file, line, column, source text and GPL code of its mistake, never a traceback."""

from __future__ import annotations

import socket
from pathlib import Path

import pytest

from gpl_helpers import error_of, output_of, run_project
from twin.errors import ProgramError
from twin.runner import run_program

ROOT = Path(__file__).resolve().parent.parent
DATA = Path(__file__).resolve().parent / "data" / "gpl"
SCENE = ROOT / "scenes" / "scara_pick.toml"


def _output(name: str, **kw) -> list[str]:
    system, thread = run_project(DATA / name, **kw)
    errors = [t.error for t in system.threads if t.error is not None]
    if errors:
        raise errors[0]
    return system.console.output.splitlines()


def _cell_run(name: str, max_sim_time: float):
    return run_program(DATA / name, scene=SCENE, max_sim_time=max_sim_time).report


# ------------------------------------------------------------------ with the cell
def test_pick_three_parts_with_profiles_and_approach():
    """Ch. 12 Move.Approach / Move.Loc with Profiles from the .gpo's Init (ch. 10 "Special
    Initialization"), the hand in its own module: three parts leave the nest and reach the
    bin, none dropped; `&` shows an Integer plainly and a Boolean as False (ch. 7)."""
    report = _cell_run("pick_three", 20.0)
    assert report.errors == []
    assert report.output.splitlines() == [
        "part 1 placed, hand closed: False", "part 2 placed, hand closed: False",
        "part 3 placed, hand closed: False", "Placed 3 parts"]
    assert [e["kind"] for e in report.events if e["kind"] in ("grasp", "release")] == ["grasp", "release"] * 3
    assert report.regions["bin"] == 3 and report.regions["nest"] == 1
    assert not [p for p in report.parts if p["dropped"]]


def test_pallet_refframe_visits_every_slot_and_its_approach():
    """A pallet RefFrame (ch. 12, L2048-2072) of 3 x 2 slots, 25 mm and 35 mm apart: the
    location on it visits the slots in index order (rows along +X, the frame's yaw 0 /
    pitch 180 / roll 180 turns the second index to -Y); Move.Approach stops ZClearance
    20 mm above the slot (tool pointing down); PalletNextPos wraps to 1,1 after the last.
    A variable named like its module (`tray` in Module Tray) is the variable."""
    report = _cell_run("pallet", 40.0)
    assert report.errors == []
    expected = []
    for n, (x, y) in enumerate([(320, -60), (345, -60), (370, -60), (320, -95), (345, -95), (370, -95)], 1):
        expected += [f"{n} above {x}.0 {y}.0 260.0", f"{n} at {x}.0 {y}.0 240.0"]
    assert report.output.splitlines() == expected + ["back at 1,1"]


def test_motion_errors_reach_catch_with_their_gpl_codes():
    """Ch. 11: a motion to an unreachable Location raises in Move.Loc; Catch gets the
    code in Exception.ErrorCode and the text in Message(), Finally runs either way, a bare
    Throw re-raises to the caller's Try.  A thread that has not attached the robot gets
    -1009 (ch. 12 L1954-1959).  The last, uncaught error stops the thread and is
    reported at its statement (Main.gpl line 51)."""
    report = _cell_run("motion_error", 20.0)
    assert report.output.splitlines() == [
        "not attached: -1009", "attempt 1 done", "home1 True",
        "caught -1033: Invalid Cartesian value: Location out of range", "attempt 2 done", "faraway False",
        "inner -1033", "outer -1033", "still at X 300"]
    assert len(report.errors) == 1
    error = report.errors[0]
    assert (error["code"], error["line"], error["column"]) == (-1033, 51, 9)
    assert error["file"].endswith("Main.gpl")


# ------------------------------------------------------------------ language only
def test_class_with_properties_and_constructors_across_modules():
    """Ch. 5 user classes: a class in Parts.gpl used from Main.gpl by its short and
    qualified name; two New constructors chosen by argument count, a ReadOnly property, a
    Set that throws (the Catch sees -786 and the field unchanged), a Shared counter;
    Format(x, "0.00") rounds a half away from zero (3.125 -> 3.13)."""
    assert _output("parts_class") == [
        "bolt (10.25 g) ok", "nut (14.00 g) REJECT", "unnamed (3.13 g) ok",
        "heaviest: nut", "created: 3", "error -786, weight still 10.25"]


def test_select_case_with_ranges_is_and_strings():
    """Ch. 9 Select...Case: values, `a To b` ranges, `Is <op>`, lists, Case Else, Exit
    Select; the first matching Case wins (75 is in a list before `Is >= 50`); String
    ranges compare binary (ch. 7); Consts from a .gpo used in Case expressions."""
    assert _output("case_sort") == [
        "-2 -> error", "0 -> empty", "0.25 -> between", "0.5 -> light", "7 -> light",
        "10.5 -> between", "11 -> medium", "49.9 -> between", "50 -> heavy", "75 -> medium",
        "80 -> heavy", "1120-1"]


def test_do_loop_variants_and_exits():
    """Ch. 9: `Do While` tests first, `Loop Until` last (the body runs once); Continue Do,
    Exit Do, Exit For, Exit While; a negative Step ends when the variable passes the final
    value (it is then -2); a Double loop variable with Step 0.25."""
    assert _output("loops") == [
        "while-first 5", "until-last 6", "sum not /3 37", "halved 0.78125", "power 243",
        "down 10,7,4,1, after -2", "squares 12345 stop 6", "quarter steps 5 end 1.25",
        "triangle 5 35"]


def test_threads_share_module_flags_and_a_testandset_lock():
    """Ch. 18: three threads started by name (plain, qualified, and with a name left out
    of New Thread's optional arguments); a Public flag in the .gpo stops the producer,
    which sleeps 100 ms between parts, so it has made 3 when Main sees the flag set at 3;
    two adders that sleep between read and write keep their sum right behind a
    Thread.TestAndSet lock (Table 18-2's race cannot happen)."""
    assert _output("workers") == [
        "made 1", "made 2", "made 3", "stop requested at 3", "producer leaves after 3",
        "tally 50 by adder1 and adder2"]


def test_string_functions_of_tables_7_1_and_7_2():
    """Table 7-2 functions are 1-based (Instr, Mid), Table 7-1 members 0-based (IndexOf,
    Substring); Split, Trim with characters, Asc/Chr/Hex, String.Compare with ignore-case;
    `&` binds tighter than `=` and `<>` (Table 6-1); "" inside a literal is one quote."""
    assert _output("strings") == [
        "id A17 x 12.5 y -3", "missing []", "sum 9.5", "fields 4 last OK",
        "Id=a17,X=12.5,Y=-3,Ok", "at 7 / 8 / -1", "[padded][hi][left]", "65 B FF 0 3",
        "True 0", "1,234.50 1 007", "True"]


def test_file_log_written_and_read_back(tmp_path):
    """Ch. 15 "Steps for Writing/Reading a File": a StreamWriter (append with True, NewLine
    set to LF) on /flash, read back with Peek/ReadLine; File.Length counts the bytes; a
    missing file raises -3110 into the Catch."""
    assert _output("file_log", sandbox=tmp_path) == [
        "NEST took 1.250", "BELT took 0.500", "BIN took 2.063",
        "4 lines, 3 entries, total 3.813", "log size 50", "missing: -3110"]
    assert (tmp_path / "flash" / "cycle.log").read_text() == \
        "# cycle log\n1;nest;1.250\n2;belt;0.500\n3;bin;2.063\n"


def test_exit_sub_function_and_byref_byval_mixes():
    """Ch. 10 "Procedure Arguments": ByRef swaps a local pair and two array elements, and
    reaches an object's field, an element of its array field and a module variable; ByVal
    leaves the caller's variable alone; an expression passed ByRef is not written back;
    Exit Function keeps the value set so far, Exit Sub leaves a loop and the procedure."""
    assert _output("exits_byref") == [
        "swapped -4 1.5", "first above 5 at 0 after 1 compares; data(0) 16", "none: -1 after 5",
        "clamp 42 -> 200", "negative -> -3, calls 2", "level 2 history 1 calls 3",
        "expression passed ByRef leaves v 42", "loop 1"]


def test_consts_and_public_globals_of_a_gpo():
    """Ch. 4 "Scope of Names": Public Consts, variables and an array of the .gpo are seen
    unqualified from two modules (and qualified, Settings.CELL_NAME); the same Public name
    in two modules (`count`) needs its module name; Single * Integer arithmetic is Double."""
    assert _output("globals") == [
        "Cell-7/feed part 1", "Cell-7/weld part 2", "Cell-7/pack part 3", "Cell-7/feed part 4",
        "done 4/4 in 7.5 s", "station count 4, supervisor count 100"]


def test_console_formats_each_data_type():
    """Table 15-5 Console.Write/WriteLine show values as CStr does: a Double with 15
    significant digits, a Single with 7 (1234.5678 stored in a Single shows 1234.568),
    integers plainly (7 / 2 = 3.5 stored in an Integer rounds to even, 4), Booleans as
    True/False, 1E+20 and 1.5E-07 exponents; arithmetic on a Single is Double (ch. 6)."""
    assert _output("console_format") == [
        "0.666666666666667", "0.6666667", "1234.568", "4", "-32768", "255", "False", "True",
        "1E+20", "1.5E-07", "tray 3", "a=0.1 b=0.1", "3 1 -1 2 4 -1", "2.5 0.125 100 -0.5",
        "2.00000005960464", "2"]


def test_single_shows_seven_digits_in_cstr_and_console_alike():
    """Known issue: Console.WriteLine of a Single printed 15 digits where CStr printed 7.
    A Single copied to a Double is a Double (15 digits)."""
    out = output_of("""
Sub Main()
    Dim s As Single = 1 / 3
    Dim d As Double = s
    Console.WriteLine(s)
    Console.WriteLine(CStr(s))
    Console.WriteLine("" & s)
    Console.WriteLine(d)
End Sub
""")
    assert out.splitlines() == ["0.3333333", "0.3333333", "0.3333333", "0.333333343267441"]


def test_byref_argument_of_a_chained_builtin_call():
    """Known issue: `tc.Client.Receive(buf, n)` (ch. 13, Socket.Receive(ByRef buffer,
    max)) on a member whose class only the run time knows fills the caller's String."""
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    out = output_of(f"""
Module Net
    Public Sub Main()
        Dim client As New Thread("Net.Client")
        Dim tl As New TcpListener(New IPEndPoint("", {port}))
        Dim ts As Socket
        Dim got As String
        client.Start()
        tl.Start()
        While Not tl.Pending()
            Thread.Sleep(20)
        End While
        ts = tl.AcceptSocket()
        ts.Receive(got, 100)
        ts.Send("ack " & got)
        client.Join(-1)
        ts.Close()
    End Sub

    Public Sub Client()
        Dim tc As TcpClient
        Dim reply As String
        Dim n As Integer
        Thread.Sleep(100)
        tc = New TcpClient(New IPEndPoint("127.0.0.1", {port}))
        tc.Client.Send("part 7")
        n = tc.Client.Receive(reply, 100)
        Console.WriteLine(reply & " (" & n & ")")
        tc.Close()
    End Sub
End Module
""")
    assert out == "ack part 7 (10)\n"


def test_new_of_a_class_without_objects_is_a_clear_error():
    """Known issue: Controller (like Move, Robot, Signal, Console) has only Shared members
    (ch. 12); `New Controller` names the class and the statement."""
    with pytest.raises(ProgramError) as info:
        output_of("Sub Main()\n    Dim c As New Controller\nEnd Sub\n")
    err = info.value
    assert (err.code, err.line, err.column) == (-2006, 2, 9)
    assert "Controller has no objects" in err.message


# ------------------------------------------------------------------ malformed projects
GPR = 'ProjectBegin\nProjectName="bad"\nProjectStart="Main"\nProjectEnd\n'


def _main(body: str, extra: str = "") -> dict[str, str]:
    """A one-module project whose Main holds `body` (Main.gpl line 3 is body's first line)."""
    return {"Main.gpl": "Module Cell\n    Public Sub Main()\n" + body + "    End Sub\n" + extra + "End Module\n"}


# (case id, files, code, file, line, column): the first error of the project.
MALFORMED = [
    ("array initialiser", _main("        Dim a() As Double = {1, 2}\n"), -2001, "Main.gpl", 3, 29),
    ("Dim in two blocks with two types", _main("        If True Then\n            Dim k As Integer\n"
                                                "        Else\n            Dim k As String\n        End If\n"),
     -2003, "Main.gpl", 6, 17),
    ("missing End If", _main("        If 1 > 0 Then\n            Console.WriteLine(1)\n"), -2001, "Main.gpl", 5, 9),
    ("Next without For", _main("        Next\n"), -2001, "Main.gpl", 3, 9),
    ("unterminated string", _main('        Console.WriteLine("abc)\n'), -2001, "Main.gpl", 3, 27),
    ("stray character", _main("        Dim x As Integer\n        x = 5 $ 3\n"), -2001, "Main.gpl", 4, 15),
    ("class without End Class", {"Main.gpl": "Module Cell\n    Class Part\n        Public w As Integer\n"
                                              "    Public Sub Main()\n    End Sub\nEnd Module\n"},
     -2001, "Main.gpl", 6, 5),
    ("Function at end of file", {"Main.gpl": "Module Cell\n    Public Sub Main()\n    End Sub\n"
                                              "    Function F() As Integer\n        Return 1\n"},
     -2001, "Main.gpl", 5, 17),
    ("undefined variable", _main("        total = 3\n"), -2002, "Main.gpl", 3, 9),
    ("undefined member of a built-in", _main("        Dim loc As New Location\n        loc.Foo = 1\n"),
     -2002, "Main.gpl", 4, 9),
    ("Private variable of another module",
     {**_main("        Console.WriteLine(Data.secret)\n"),
      "Data.gpl": "Module Data\n    Private secret As Integer\nEnd Module\n"}, -2008, "Main.gpl", 3, 27),
    ("assignment to a Const", _main("        LIMIT = 4\n", "    Const LIMIT As Integer = 3\n"),
     -2007, "Main.gpl", 3, 9),
    ("wrong argument count", _main("        Go(1, 2)\n", "    Sub Go(ByVal a As Integer)\n    End Sub\n"),
     -2005, "Main.gpl", 3, 9),
    ("Sub used as a value", _main("        Dim x As Integer = Go()\n", "    Sub Go()\n    End Sub\n"),
     -2004, "Main.gpl", 3, 28),
    ("Dim without a type", _main("        Dim x\n"), -2004, "Main.gpl", 3, 13),
    ("unsupported type Long", _main("        Dim x As Long\n"), -2010, "Main.gpl", 3, 13),
    ("duplicate local", _main("        Dim x As Integer\n        Dim x As Double\n"), -2003, "Main.gpl", 4, 13),
    ("ambiguous Public name",
     {**_main("        count = 1\n"), "A.gpl": "Module A\n    Public count As Integer\nEnd Module\n",
      "B.gpl": "Module B\n    Public count As Integer\nEnd Module\n"}, -2009, "Main.gpl", 3, 9),
    ("object assigned to a number", _main("        Dim n As Integer\n        n = New Location\n"),
     -2004, "Main.gpl", 4, 9),
    ("Shared use of an instance member", _main("        Console.WriteLine(Location.X)\n"),
     -2006, "Main.gpl", 3, 27),
    ("built-in constructor arguments", _main("        Dim p As New Profile(1, 2)\n"), -202, "Main.gpl", 3, 9),
    ("argument left out of a user Sub",
     _main("        Go(1, , 3)\n", "    Sub Go(ByVal a As Integer, ByVal b As Integer, ByVal c As Integer)\n"
           "    End Sub\n"), -2006, "Main.gpl", 3, 11),
    ("Return with a value in a Sub", _main("        Return 5\n"), -2006, "Main.gpl", 3, 9),
    ("GoTo into a Try", _main("        GoTo inside\n        Try\ninside:\n            Console.WriteLine(1)\n"
                              "        Catch\n        End Try\n"), -2011, "Main.gpl", 3, 9),
    ("New of a Shared-only class", _main("        Dim m As New Move\n"), -2006, "Main.gpl", 3, 13),
    # run time
    ("divide by zero", _main("        Dim a As Integer = 0\n        Console.WriteLine(10 / a)\n"),
     -709, "Main.gpl", 4, 9),
    ("index out of range", _main("        Dim a(2) As Integer\n        a(3) = 1\n"), -767, "Main.gpl", 4, 9),
    ("member of Nothing", _main("        Dim loc As Location\n        loc.X = 1\n"), -782, "Main.gpl", 4, 9),
    ("String that is not a number", _main('        Dim n As Integer = CInt("12a")\n'), -717, "Main.gpl", 3, 9),
    ("Byte overflow", _main("        Dim b As Byte\n        b = 300\n"), -708, "Main.gpl", 4, 9),
    ("endless recursion", _main("        Down(1)\n", "    Sub Down(ByVal n As Integer)\n        Down(n + 1)\n"
                                "    End Sub\n"), -755, "Main.gpl", 5, 5),
    ("Throw of an empty Exception", _main("        Dim e As New Exception\n        Throw e\n"),
     -807, "Main.gpl", 4, 9),
    ("Thread of an unknown procedure", _main('        Dim t As New Thread("Nowhere")\n        t.Start()\n'),
     -744, "Main.gpl", 4, 9),
    ("Me in a module procedure", _main("        Console.WriteLine(Me Is Nothing)\n"), -787, "Main.gpl", 3, 9),
    # project files
    ("missing source file", {"Project.gpr": GPR.replace("ProjectEnd", 'ProjectSource="Gone.gpl"\nProjectEnd'),
                             **_main("")}, -2013, "Project.gpr", 4, 1),
    ("malformed project line", {"Project.gpr": GPR.replace("ProjectEnd", "Source Main.gpl\nProjectEnd"),
                                **_main("")}, -2013, "Project.gpr", 4, 1),
]


def _first_error(folder: Path) -> ProgramError:
    try:
        system, thread = run_project(folder, max_cycles=2000)
    except ProgramError as err:
        return err
    errors = [t.error for t in system.threads if t.error is not None]
    assert errors, "expected the project to stop on an error"
    return errors[0]


def _write(folder: Path, files: dict[str, str]) -> Path:
    folder.mkdir()
    (folder / "Project.gpr").write_text(GPR)
    for name, text in files.items():
        (folder / name).write_text(text)
    return folder


@pytest.mark.parametrize("files, code, file, line, column",
                         [pytest.param(*case[1:], id=case[0]) for case in MALFORMED])
def test_malformed_project_gives_file_line_column_text_and_code(tmp_path, files, code, file, line, column):
    """Every mistake is a ProgramError that names the file, line, column, the source line
    and GPL's code and message (docs/gpl.md lists the codes), never a Python traceback."""
    folder = _write(tmp_path / "bad", files)
    err = _first_error(folder)
    assert (err.code, Path(err.file).name, err.line, err.column) == (code, file, line, column), str(err)
    source = (folder / file).read_text().splitlines()
    assert err.text is not None and err.text.strip() == source[line - 1].strip()
    assert str(code) in str(err)


def test_project_folder_without_project_gpr(tmp_path):
    """Ch. 17: a project is a folder with Project.gpr; without it, -2013 names the folder."""
    (tmp_path / "Main.gpl").write_text("Sub Main()\nEnd Sub\n")
    with pytest.raises(ProgramError) as info:
        run_project(tmp_path)
    assert info.value.code == -2013 and info.value.file == str(tmp_path)


def test_start_procedure_must_be_public_and_without_parameters(tmp_path):
    """Ch. 17 L3238-3244: the start procedure is Public and takes no arguments (-2012)."""
    folder = _write(tmp_path / "p", {"Main.gpl": "Module M\n    Public Sub Main(ByVal n As Integer)\n"
                                                  "    End Sub\nEnd Module\n"})
    with pytest.raises(ProgramError) as info:
        run_project(folder)
    assert info.value.code == -2012 and "Main" in info.value.message


def _mutants(text: str):
    """The text with one line dropped, or cut in half, or a token doubled: the slips of a
    programmer's editor."""
    lines = text.splitlines()
    for i, line in enumerate(lines):
        if not line.strip():
            continue
        yield "\n".join(lines[:i] + lines[i + 1:])
        yield "\n".join(lines[:i] + [line[: len(line) // 2]] + lines[i + 1:])
        words = line.split(" ")
        yield "\n".join(lines[:i] + [" ".join(words + words[-1:])] + lines[i + 1:])


@pytest.mark.parametrize("project", ["parts_class", "case_sort", "loops", "strings", "exits_byref", "globals",
                                     "console_format", "workers", "file_log"])
def test_no_python_exception_escapes_from_damaged_projects(tmp_path, project):
    """Each of the valid projects, damaged one line at a time, either still runs or stops
    with a ProgramError carrying a GPL code and a location; nothing else escapes."""
    source = DATA / project
    for path in sorted(source.iterdir()):
        if path.suffix.lower() not in (".gpl", ".gpo"):
            continue
        for n, text in enumerate(_mutants(path.read_text())):
            folder = tmp_path / f"{path.stem}_{n}"
            folder.mkdir()
            for other in source.iterdir():
                (folder / other.name).write_text(other.read_text())
            (folder / path.name).write_text(text)
            try:
                system, _ = run_project(folder, max_cycles=200, sandbox=tmp_path / "files")
            except ProgramError as err:
                assert err.code is not None and err.file and err.line, f"{path.name} mutant {n}: {err}"
                continue
            for thread in system.threads:
                if thread.error is not None:
                    assert thread.error.code is not None and thread.error.line, f"{path.name} mutant {n}"


def test_continue_do_goes_to_the_loop_test():
    """Ch. 9 Do...Loop Until: Continue Do goes on at the Loop's test (VB.NET), so the loop
    ends at n = 3 though every pass before 5 continues; a spinning Continue still gives
    the CPU back (the other thread runs)."""
    out = output_of("""
Module M
    Public ticks As Integer
    Public Sub Main()
        Dim n As Integer
        Dim hits As Integer
        Dim t As New Thread("Ticker")
        Do
            n += 1
            If n < 5 Then Continue Do
            hits += 1
        Loop Until n >= 3
        Console.WriteLine(n & " " & hits)
        t.Start()
        Do While ticks = 0
            If ticks = 0 Then Continue Do
        Loop
        Console.WriteLine("ticker ran")
    End Sub
    Public Sub Ticker()
        ticks = 1
    End Sub
End Module
""")
    assert out == "3 0\nticker ran\n"


@pytest.mark.parametrize("body, detail", [
    ("    If 1 > 0 Then\n        Console.WriteLine(1)\n", "unexpected 'Sub', expected If"),
    ("    While True\n", "unexpected 'Sub', expected While"),
    ("    Do\n        Console.WriteLine(1)\n", "unexpected 'End', expected Loop"),
    ("    Next\n", "unexpected 'Next'"),
])
def test_an_unclosed_block_names_the_end_it_expected(body, detail):
    """A block without its End (ch. 9) is reported where the parser noticed it, with the
    keyword it expected."""
    with pytest.raises(ProgramError) as info:
        output_of("Sub Main()\n" + body + "End Sub\n")
    assert info.value.code == -2001 and detail in info.value.message
