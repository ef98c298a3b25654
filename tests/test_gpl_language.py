"""GPL language: parsing, types, conversions, control structures, procedures,
objects and exceptions (GPL User Manual, Brooks 609644 Rev. A, chapters 3-11;
line numbers Lnnn are in /work/shared/seeds/gpl-user-manual.txt)."""

from __future__ import annotations

import pytest

from gpl_helpers import SEMAPHORES, error_of, output_of, run_gpl
from twin.errors import ProgramError
from twin.language.gpl.runtime import GplSystem


def lines(text: str) -> list[str]:
    return text.splitlines()


def test_declarations_share_the_next_type_and_initialise():
    """Ch. 4 (L718-734): `Dim n As Integer, x As Double`, `Dim ii, jj As Integer`
    (both Integer), `Dim Count As Integer = 1`; Strings start empty."""
    out = output_of("""
Module M
    Public Sub Main()
        Dim n As Integer, x As Double
        Dim ii, jj As Integer
        Dim Count As Integer = 1
        Dim s As String
        ii = 2.6
        jj = 1.4
        x = 2.6
        Console.WriteLine(ii & " " & jj & " " & x & " " & Count & " [" & s & "]")
    End Sub
End Module
""")
    assert out == "3 1 2.6 1 []\n"


def test_ambiguous_public_name_is_a_compile_error():
    """Ch. 4 (L694-710): the same Public name in two modules must be qualified."""
    with pytest.raises(ProgramError) as err:
        output_of("""
Module Test1
    Public aa As Integer
End Module
Module Test2
    Public aa As Integer
End Module
Module Test3
    Public Sub Main()
        aa = 1
    End Sub
End Module
""")
    assert err.value.code == -2009 and err.value.line == 10


def test_me_and_shared_members():
    """Ch. 5: Me is the current object; a Shared field has one copy (Class.item);
    `Is` compares references (and VB.NET's `IsNot` is accepted)."""
    out = output_of("""
Public Class node
    Public Shared made As Integer
    Public value As Integer
    Public Sub New(v As Integer)
        value = v
        made += 1
    End Sub
    Public Function Self() As node
        Return Me
    End Function
End Class
Sub Main()
    Dim a As New node(3)
    Dim b As New node(4)
    Console.WriteLine(node.made & " " & (a.Self() Is a) & " " & (a Is b) & " " & b.Self.value & " " & (a IsNot b))
End Sub
""")
    assert out == "2 True False 4 True\n"


def test_objects_byval_and_byref():
    """Ch. 5 "Objects as Procedure Arguments" and ch. 10 "Procedure Arguments":
    ByVal lets the callee change the object but not the caller's variable; ByRef
    re-points the caller's variable; ByRef numbers are written back."""
    out = output_of("""
Class box
    Public tag As String
End Class
Sub Repoint(ByVal o As box, ByRef r As box)
    o.tag = "changed"
    o = New box
    o.tag = "lost"
    r = New box
    r.tag = "new"
End Sub
Sub Swap(ByRef a As Integer, ByRef b As Integer)
    Dim t As Integer
    t = a
    a = b
    b = t
End Sub
Sub Main()
    Dim o1 As New box, o2 As New box
    Dim x As Integer = 1, y As Integer = 2
    o1.tag = "one"
    o2.tag = "two"
    Repoint(o1, o2)
    Swap(x, y)
    Console.WriteLine(o1.tag & " " & o2.tag & " " & x & " " & y)
End Sub
""")
    assert out == "changed new 2 1\n"


def test_operators_and_precedence():
    """Ch. 6 Table 6-1 (L1129-1148): ^ above unary minus, / real, \\ truncates,
    Mod real remainder, And/Or bitwise on integers, logical on Booleans,
    shifts arithmetic, Not False is True (-1)."""
    out = output_of("""
Sub Main()
    Console.WriteLine(2 * -4 & " " & -2 ^ 2 & " " & 7 / 2 & " " & 2.3 \\ 2 & " " & 13.3 Mod 2)
    Console.WriteLine((6 And 3) & " " & (5 Or 2) & " " & (6 Xor 3) & " " & (True And False) & " " & (True Or False))
    Console.WriteLine((1 << 4) & " " & (-16 >> 2) & " " & CInt(Not False) & " " & (Not 0))
    Console.WriteLine(2.34 + "1.01")
    Console.WriteLine("ab" + "cd" & 1 + 2)
End Sub
""")
    assert lines(out) == ["-8 -4 3.5 1 1.3", "2 7 5 False True", "16 -4 -1 -1", "3.35", "abcd3"]


def test_hex_octal_and_string_literals():
    """Ch. 4 (L650-652) &H and &O constants; ch. 7 (L1204) "" inside a literal."""
    out = output_of('''
Sub Main()
    Console.WriteLine(&H1F & " " & &O17 & " " & "Tom said, ""Hello world""")
End Sub
''')
    assert out == '31 15 Tom said, "Hello world"\n'


def test_control_structures():
    """Ch. 9: If/ElseIf/Else, single-line If, For with negative Step, While,
    Do While/Until before and after, Exit For/Do/While, Select with lists,
    ranges and Is."""
    out = output_of("""
Sub Main()
    Dim n As Integer, s As String
    For n = 10 To 1 Step -3
        s &= n & " "
    Next n
    Console.WriteLine(s)
    n = 0
    While True
        n += 1
        If n = 4 Then Exit While
    End While
    Do While n < 10
        n += 2
        If n = 8 Then Exit Do
    Loop
    Console.WriteLine(n)
    Do
        n -= 3
    Loop Until n < 0
    Console.WriteLine(n)
    Do Until n >= 2
        n += 1
    Loop
    Do
        n += 1
    Loop While n < 5
    Console.WriteLine(n)
    For n = 0 To 7
        Select Case n
            Case 0
                s = "zero"
            Case 1, 2
                s = "one or two"
            Case 3 To 5
                s = "three to five"
            Case Is >= 7
                s = "seven up"
            Case Else
                s = "else"
        End Select
        If n = 0 Then
            Console.Write(s)
        ElseIf n < 7 Then
            Console.Write("," & s)
        Else
            Console.WriteLine("," & s)
        End If
    Next
End Sub
""")
    assert lines(out) == [
        "10 7 4 1 ", "8", "-1", "5",
        "zero,one or two,one or two,three to five,three to five,three to five,else,seven up",
    ]


def test_select_on_strings_and_exit_select():
    """Ch. 9 Select (L1426-1451): String match values; Exit Select."""
    out = output_of("""
Sub Main()
    Dim c As String = "blue"
    Select c
        Case "red"
            Console.WriteLine("r")
        Case "bl" & "ue", "navy"
            Console.WriteLine("b")
            Exit Select
            Console.WriteLine("not here")
    End Select
End Sub
""")
    assert out == "b\n"


def test_goto_forward_and_backward():
    """Ch. 9 "GoTo Statements" (L1338-1348): labels are names or numbers with a colon."""
    out = output_of("""
Sub Main()
    Dim i As Integer
top:
    i += 1
    If i < 3 Then GoTo top
    GoTo 100
    Console.WriteLine("skipped")
100: Console.WriteLine("i=" & i)
End Sub
""")
    assert out == "i=3\n"


def test_arrays_bounds_length_redim():
    """Ch. 4 "Data Type Arrays" (L766-817): Dim Count(9) has 10 elements, (3, 4)
    has 20, ReDim re-sizes, GetUpperBound/Length/Rank; an index past the upper
    bound stops the program with file and line."""
    source = """
Sub Main()
    Dim Count(9) As Integer
    Dim MyArray(3, 4) As Integer
    Dim TwoD(,) As Integer
    Dim sarray(3) As String
    Dim ii As Integer
    For ii = 0 To 9
        Count(ii) = ii * ii
    Next
    MyArray(3, 4) = 7
    ReDim TwoD(1, 100)
    Console.WriteLine(Count.Length & " " & Count(9) & " " & MyArray.Length & " " & MyArray.Rank & " " & MyArray(3, 4))
    Console.WriteLine(TwoD.GetUpperBound(1) & " " & sarray.Length & " " & sarray(0).Length)
    ReDim Count(19)
    Console.WriteLine(Count.Length & " " & Count(3))
    Count(20) = 1
End Sub
"""
    system, thread = run_gpl(source)
    assert lines(system.console.output) == ["10 81 20 2 7", "100 4 0", "20 0"]
    assert thread.error.code == -767 and thread.error.line == 17 and thread.error.column == 5


def test_string_members_and_functions():
    """Ch. 7 Tables 7-1 and 7-2: members are 0-based (IndexOf, Substring), the
    compatibility functions 1-based (Instr, Mid); comparisons are case-sensitive."""
    out = output_of("""
Sub Main()
    Dim s As String = "  Hello World  "
    Dim t As String
    Dim parts() As String
    t = s.Trim
    parts = t.Split(" ")
    Console.WriteLine(t.Length & "|" & t.ToUpper & "|" & t.ToLower & "|" & t.Substring(6) & "|" & t.Substring(0, 5))
    Console.WriteLine(t.IndexOf("o") & " " & t.IndexOf("o", 5) & " " & t.IndexOf("z") & " " & Instr(1, t, "World") & " " & Instr(1, t, "z"))
    Console.WriteLine(Mid(t, 7, 5) & "|" & Len(s) & "|" & UCase("a") & LCase("B") & "|" & Asc("A") & Chr(66))
    Console.WriteLine(parts.Length & " " & parts(1) & " " & ("A" = "a") & " " & String.Compare("A", "a", True) & " " & String.Compare("a", "b"))
    Console.WriteLine(s.TrimStart & "|" & s.TrimEnd & "|" & CStr(1.5) & "|" & Hex(255) & "|" & Format(3.14159, "0.00"))
End Sub
""")
    assert lines(out) == [
        "11|HELLO WORLD|hello world|World|Hello",
        "4 7 -1 7 0",
        "World|15|Ab|65B",
        "2 World False 0 -1",
        "Hello World  |  Hello World|1.5|FF|3.14",
    ]


def test_conversion_functions_and_ranges():
    """Ch. 4 Table 4-3 (CBool ... CStr, Hex) and Table 4-1 ranges: a Byte holds
    0-255, a Short -32768..32767; out of range is an overflow error."""
    out = output_of("""
Sub Main()
    Dim e As New Exception
    Dim b As Byte
    Dim sh As Short
    Console.WriteLine(CInt("42") & " " & CDbl("2.5") & " " & CBool(0) & " " & CBool(3) & " " & CByte(255) & " " & CShort(-32768) & " " & CInt(2.5) & " " & CInt(3.5))
    Console.WriteLine(Fix(-2.5) & " " & Int(-2.5) & " " & Math.Sqrt(16) & " " & Math.Sin(90) & " " & Math.Max(3, 4) & " " & Math.Abs(-2) & " " & Math.Atan2(1, 1))
    Try
        b = 256
    Catch e
        Console.WriteLine(e.ErrorCode & " " & e.Message)
    End Try
    Try
        sh = 40000
    Catch e
        Console.WriteLine(e.ErrorCode)
    End Try
End Sub
""")
    assert lines(out) == [
        "42 2.5 False True 255 -32768 2 4",
        "-2 -3 4 1 4 2 45",
        "-708 Value infinite or NAN: 256 as Byte",
        "-708",
    ]


def test_finally_runs_while_the_exception_goes_to_the_caller():
    """Ch. 11 (L1715): a Try with only Finally runs the Finally before the
    exception reaches the caller's Catch; Exit Try goes to the Finally; Throw
    re-raises a caught exception to an outer Try."""
    out = output_of("""
Sub Inner()
    Dim x As Integer
    Try
        x = 1 / 0
    Finally
        Console.WriteLine("finally")
    End Try
End Sub
Sub Main()
    Dim exc As Exception
    Dim outer As New Exception
    Try
        Inner()
    Catch exc
        Console.WriteLine("caught " & exc.ErrorCode & " " & exc.Message)
    End Try
    Try
        Console.WriteLine("before")
        Exit Try
        Console.WriteLine("not here")
    Catch exc
    Finally
        Console.WriteLine("finally 2")
    End Try
    Try
        Try
            Throw New Exception(-786)
        Catch exc
            Console.WriteLine("inner " & exc.ErrorCode)
            Throw exc
        End Try
    Catch outer
        Console.WriteLine("outer " & outer.ErrorCode & " " & outer.Message)
    End Try
End Sub
""")
    assert lines(out) == [
        "finally", "caught -709 Division by 0", "before", "finally 2", "inner -786",
        "outer -786 Project generated error",
    ]


def test_throw_of_error_code_zero_is_invalid():
    """GPL Dictionary (digest §7): a thrown Exception needs a negative ErrorCode."""
    error = error_of("""
Sub Main()
    Dim e As New Exception
    Throw e
End Sub
""")
    assert error.code == -807 and error.line == 4


def test_uncaught_error_reports_file_line_column_and_procedure():
    """Ch. 11 (L1713): an uncaught exception halts the thread and reports it."""
    error = error_of("""
Module Cell
    Public Sub Main()
        Step2()
    End Sub
    Sub Step2()
        Dim loc As Location
        Console.WriteLine(loc.X)
    End Sub
End Module
""")
    assert (error.code, error.file, error.line, error.column) == (-782, "test.gpl", 8, 9)
    assert error.program == "Cell.Step2" and "loc.X" in error.text


def test_delegate_signature_must_match():
    """Ch. 10 (L1562): a procedure that does not match the Delegate statement is
    a compile error."""
    with pytest.raises(ProgramError) as err:
        output_of("""
Delegate Function My_template(ByVal arg1 As Integer) As String
Public Function f2 (ByVal mode As String) As String
    Return mode
End Function
Sub Main()
    Dim d As My_template
    d = New My_template(AddressOf f2)
End Sub
""")
    assert err.value.code == -2004 and err.value.line == 8


def test_threads_share_module_variables_and_lock_with_test_and_set():
    """Ch. 18 (L3351-3367): threads started with New Thread (a procedure name, or
    AddressOf as in VB.NET) / Start / Join; an increment guarded by a
    Thread.TestAndSet lock is exact."""
    out = output_of("""
Module M
    Public my_lock As Integer
    Public total As Integer
    Public Sub Worker()
        Dim i As Integer
        For i = 1 To 50
            While Thread.TestAndSet(my_lock, 1) <> 0
                Thread.Sleep(0)
            End While
            total = total + 1
            my_lock = 0
            If i Mod 10 = 0 Then Thread.Sleep(5)
        Next
    End Sub
    Public Sub Main()
        Dim t1 As New Thread("Worker")
        Dim t2 As New Thread(AddressOf Worker)
        t1.Start
        t2.Start
        t1.Join(-1)
        t2.Join(-1)
        Console.WriteLine("total " & total)
    End Sub
End Module
""")
    assert out == "total 100\n"


def test_module_initialisers_and_init_run_before_the_start_procedure():
    """Ch. 4 (L742) and ch. 10 "Special Initialization" (L1658-1664): module
    variables are initialised in order, then Init, before the start procedure."""
    out = output_of("""
Module A
    Public base As Integer = 40
    Public home As New Location
    Public Sub Init
        home.XYZ(base, 2, 3)
        Console.WriteLine("A.Init")
    End Sub
End Module
Module B
    Public Sub Main()
        Console.WriteLine("Main " & home.X & " " & base)
    End Sub
End Module
""")
    assert lines(out) == ["A.Init", "Main 40 40"]


def test_me_outside_a_class_is_an_error():
    """Ch. 5 "Me Object" (L1082-1084): using Me outside a class procedure raises
    an exception."""
    error = error_of("""
Sub Main()
    Console.WriteLine(Me Is Nothing)
End Sub
""")
    assert error.code == -787


def test_syntax_error_has_file_line_column_and_text():
    """A user's mistake gives file, line, column and the offending text."""
    with pytest.raises(ProgramError) as err:
        output_of("""
Sub Main()
    Dim x As Integer
    x = (3 + 
End Sub
""")
    assert err.value.code == -2001 and err.value.file == "test.gpl" and err.value.line == 5


def test_unsupported_and_undeclared():
    """Ch. 4: every variable is declared ("Undefined symbol" otherwise, L825);
    `As Object` and the VB types of Table 4-2 are rejected."""
    for body, code in (("x = 1", -2002), ("Dim o As Object", -2010), ("Dim l As Long", -2010)):
        with pytest.raises(ProgramError) as err:
            output_of(f"Sub Main()\n    {body}\nEnd Sub\n")
        assert err.value.code == code and err.value.line == 2


def test_project_folder_with_gpo_globals(tmp_path):
    """Ch. 17 (L3222-3244): Project.gpr lists the files and the start procedure;
    a .gpo module's Init creates the global Location and Profile objects."""
    (tmp_path / "Project.gpr").write_text(
        "' project\nProjectBegin\nProjectName=\"Demo\"\nProjectStart=\"Main\"\n"
        "ProjectSource=\"Globals.gpo\"\nProjectSource=\"Main.gpl\"\nProjectEnd\n"
    )
    (tmp_path / "Globals.gpo").write_text(
        "Module Globals\n    Public safe As Location\n    Public fast As Profile\n"
        "    Public Sub Init\n        safe = New Location\n        safe.XYZ(300, 0, 200, 0, 180, 0)\n"
        "        fast = New Profile\n        fast.Speed = 50\n    End Sub\nEnd Module\n"
    )
    (tmp_path / "Main.gpl").write_text(
        "Module Main\n    Public Sub Main()\n        Console.WriteLine(safe.Z & \" \" & fast.Speed)\n"
        "    End Sub\nEnd Module\n"
    )
    from gpl_helpers import Clock, NoRobot
    from twin.controller.io import DigitalIO
    from twin.controller.scheduler import Scheduler
    from twin.language.vplus.runtime import Console

    scheduler = Scheduler()
    system = GplSystem(NoRobot(), DigitalIO(), Clock(), scheduler, Console(echo=None))
    assert system.load_project(tmp_path) == "Main"
    thread = system.start()
    while scheduler.alive:
        scheduler.run_cycle()
    assert thread.error is None and system.console.output == "200 50\n"


def test_exits_cross_select_and_finally():
    """Ch. 9 and 11: Exit Do from inside a Select, Continue/Exit For, Return
    inside a Try runs its Finally, a field as the For variable (L1378), a Dim
    of an unsized array initialised from Split, recursion."""
    out = output_of("""
Class Acc
    Public n As Double
End Class
Function Fact(ByVal n As Integer) As Double
    If n <= 1 Then Return 1
    Return n * Fact(n - 1)
End Function
Function Early() As Integer
    Dim i As Integer
    Try
        For i = 1 To 10
            If i = 3 Then Return i * 100
        Next
    Finally
        Console.WriteLine("cleanup")
    End Try
    Return -1
End Function
Sub Main()
    Dim a As New Acc
    Dim state, i As Integer
    Dim words() As String = "a,b,,c".Split(",")
    Do
        Select Case state
            Case 0, 1
                state += 1
            Case Else
                Exit Do
        End Select
    Loop
    For a.n = 0.5 To 2 Step 0.5
        Console.Write(a.n & " ")
    Next
    For i = 1 To 5
        If i = 2 Then Continue For
        If i = 4 Then Exit For
        Console.Write(i)
    Next
    Console.WriteLine(" i=" & i & " state=" & state & " words=" & words.Length)
    Console.WriteLine(Fact(10) & " " & Early())
End Sub
""")
    assert lines(out) == ["0.5 1 1.5 2 13 i=4 state=2 words=4", "cleanup", "3628800 300"]


def test_comments_regions_and_continuations():
    """Ch. 3 (L577-589): labels, ' comments, # lines ignored, ` _` continuation
    and (twin) implicit continuation after an operator or comma."""
    out = output_of("""
#Region "demo"
Sub Main() ' the start
    Dim s As String
    s = "a" & _
        "b" &
        "c"
    Console.WriteLine(s _
    )
#End Region
End Sub
""")
    assert out == "abc\n"


def test_thread_abort_and_readonly_property():
    """Ch. 18 Table 18-1: Abort stops another thread (ThreadState 0 after) and a
    thread may abort itself; VB's `ReadOnly Property` modifier is accepted."""
    out = output_of("""
Class C
    Private v As Integer = 7
    Public ReadOnly Property Value As Integer
        Get
            Return v
        End Get
    End Property
End Class
Module M
    Public count As Integer
    Public Sub Spin()
        While True
            count += 1
            Thread.Sleep(10)
        End While
    End Sub
    Public Sub SelfStop()
        Console.WriteLine("stopping myself")
        Thread.CurrentThread.Abort
        Console.WriteLine("never")
    End Sub
    Public Sub Main()
        Dim c As New C
        Dim t As New Thread("Spin")
        Dim t2 As New Thread("SelfStop")
        t.Start
        t2.Start
        Thread.Sleep(100)
        t.Abort
        Console.WriteLine(c.Value & " " & (count > 3) & " " & t.ThreadState & " " & t2.ThreadState)
    End Sub
End Module
""")
    assert lines(out) == ["stopping myself", "7 True 0 0"]


def test_twin_run_project_folder(tmp_path, capsys):
    """`twin run PROJECT_DIR` runs a GPL project on the cell; Console output goes
    to stdout and the report; an uncaught error is printed with file, line,
    column, GPL code and procedure, and the exit status is 1."""
    import json

    from twin.cli import main

    (tmp_path / "Project.gpr").write_text('ProjectBegin\nProjectStart="Main"\nProjectEnd\n')
    (tmp_path / "Main.gpl").write_text(
        "Module Cell\n    Public Sub Main()\n        Dim x As Integer\n        Console.WriteLine(\"hello\")\n"
        "        x = 1 / 0\n    End Sub\nEnd Module\n"
    )
    report = tmp_path / "out" / "report.json"
    report.parent.mkdir()  # a report into a missing folder is refused before the run
    code = main(["run", str(tmp_path), "--report", str(report), "--max-sim-time", "2"])
    captured = capsys.readouterr()
    assert code == 1 and captured.out == "hello\n"
    assert f"{tmp_path / 'Main.gpl'}:5:9: Division by 0 (-709) in Cell.Main" in captured.err
    data = json.loads(report.read_text())
    assert data["output"] == "hello\n" and data["errors"][0]["code"] == -709


def test_goto_inside_loops_and_out_of_them():
    """Ch. 9 (L1388, L1404): a GoTo may skip to a label in the loop body or leave
    the loop; Exit For still works in a body that holds labels; a label may be
    a keyword, as `exit:` in the manual's TftpWrite example (L2499-2567)."""
    out = output_of("""
Sub Main()
    Dim i, n As Integer
    For i = 1 To 6
        If i Mod 2 = 0 Then GoTo skip
        n += i
        If i = 5 Then Exit For
skip:
    Next
    Console.WriteLine(n & " " & i)
    Do
        n -= 1
        If n < 5 Then GoTo exit
    Loop
exit:
    Console.WriteLine("done " & n)
End Sub
""")
    assert lines(out) == ["9 5", "done 4"]


def test_windows_text_files(tmp_path):
    """Files from a Windows editor: byte-order mark and CR LF line ends."""
    from gpl_helpers import Clock, NoRobot
    from twin.controller.io import DigitalIO
    from twin.controller.scheduler import Scheduler
    from twin.language.vplus.runtime import Console

    path = tmp_path / "Main.gpl"
    path.write_bytes(b'\xef\xbb\xbfSub Main()\r\n    Console.WriteLine("ok") \' note\r\nEnd Sub\r\n')
    scheduler = Scheduler()
    system = GplSystem(NoRobot(), DigitalIO(), Clock(), scheduler, Console(echo=None))
    system.load_files([path])
    thread = system.start("Main")
    while scheduler.alive:
        scheduler.run_cycle()
    assert thread.error is None and system.console.output == "ok\n"


def test_exception_object_members():
    """Ch. 11 Table 11-1: ErrorCode, Qualifier, RobotError, RobotNum, Axis (r/w),
    Message, Clone (an independent copy), UpdateErrorCode."""
    out = output_of("""
Sub Main()
    Dim e As New Exception
    Dim c As Exception
    e.ErrorCode = -709
    e.Qualifier = 3
    c = e.Clone
    e.UpdateErrorCode(-708)
    Console.WriteLine(e.ErrorCode & " " & e.Message & " | " & c.ErrorCode & " " & c.Qualifier & " " & c.Message)
    e.RobotError = True
    e.RobotNum = 1
    e.Axis = &H4
    Console.WriteLine(e.RobotError & " " & e.RobotNum & " " & e.Axis & " " & e.Message)
End Sub
""")
    assert lines(out) == [
        "-708 Value infinite or NAN | -709 3 Division by 0",
        "True 1 4 Value infinite or NAN: Robot 1: Axis &H4",
    ]


def test_exception_message_knows_library_codes():
    """An ErrorCode set by the program shows the built-in classes' message too."""
    out = output_of("""
Sub Main()
    Dim e As New Exception
    e.ErrorCode = -323
    Console.WriteLine(e.Message)
End Sub
""")
    assert out == "Device full\n"


def test_method_of_nothing_is_reported_at_the_call():
    """Ch. 5 (L919): using a member of an object variable that is Nothing is an
    error, reported at the calling statement."""
    error = error_of("""
Class C
    Public n As Integer
    Public Sub Bump()
        n += 1
    End Sub
End Class
Sub Main()
    Dim c As C
    c.Bump
End Sub
""")
    assert (error.code, error.line, error.column) == (-782, 10, 5)


def test_byref_module_variable_is_a_real_reference_across_threads():
    """Ch. 10 "Procedure Arguments" and ch. 18 (L3351-3367): acquire_sem(ByRef
    lock) spins on the caller's module variable itself, so a thread waiting
    for the lock sees the holder release it even while it waits in the callee;
    a ByRef array element and field are references too."""
    out = output_of("""
Class Box
    Public n As Integer
End Class
Module Locks
    Public my_lock As Integer
    Public inside As Integer
    Public most As Integer
""" + SEMAPHORES + """    Public Sub Work()
        Dim i As Integer
        For i = 1 To 5
            acquire_sem(my_lock)
            inside += 1
            If inside > most Then most = inside
            Thread.Sleep(20)       ' hold the lock across a wait
            inside -= 1
            release_sem(my_lock)
        Next
    End Sub
    Sub Bump(ByRef x As Integer)
        x += 1
    End Sub
    Public Sub Main()
        Dim a As New Thread("Work")
        Dim b As New Thread("Work")
        Dim arr(2) As Integer
        Dim bx As New Box
        a.Start
        b.Start
        a.Join(-1)
        b.Join(-1)
        Bump(arr(1))
        Bump(bx.n)
        Bump(bx.n)
        Console.WriteLine(most & " " & my_lock & " " & arr(1) & " " & bx.n)
    End Sub
End Module
""")
    assert out == "1 0 1 2\n"


def test_project_of_several_files_with_qualified_names(tmp_path):
    """Ch. 17 "Modules" (L3230-3236): modules in several files; a Public
    procedure or class of another module is used as module_name.item_name or,
    when unambiguous, by its own name; without ProjectSource lines every .gpo,
    then every .gpl file is loaded."""
    (tmp_path / "Project.gpr").write_text('ProjectBegin\nProjectName="Multi"\nProjectStart="Cell.Run"\nProjectEnd\n')
    (tmp_path / "Shapes.gpl").write_text("""
Module Shapes
    Public Class Part
        Public size As Double
        Public Shared made As Integer
        Public Sub New(ByVal s As Double)
            size = s
            made += 1
        End Sub
    End Class
    Public Function Area(ByVal p As Part) As Double
        Return p.size * p.size
    End Function
    Private Sub Hidden()
    End Sub
End Module
""")
    (tmp_path / "Cell.gpl").write_text("""
Module Cell
    Public Sub Run()
        Dim a As Shapes.Part = New Shapes.Part(3)
        Dim b As New Part(4)
        Console.WriteLine(Shapes.Area(a) + Area(b) & " " & Shapes.Part.made)
    End Sub
End Module
""")
    from gpl_helpers import Clock, NoRobot
    from twin.controller.io import DigitalIO
    from twin.controller.scheduler import Scheduler
    from twin.language.vplus.runtime import Console

    scheduler = Scheduler()
    system = GplSystem(NoRobot(), DigitalIO(), Clock(), scheduler, Console(echo=None))
    system.load_project(tmp_path)
    thread = system.start()
    while scheduler.alive:
        scheduler.run_cycle()
    assert thread.error is None and system.console.output == "25 2\n"
    (tmp_path / "Cell.gpl").write_text("Module Cell\n    Public Sub Run()\n        Shapes.Hidden()\n    End Sub\nEnd Module\n")
    with pytest.raises(ProgramError) as err:
        GplSystem(NoRobot(), DigitalIO(), Clock(), Scheduler(), Console(echo=None)).load_project(tmp_path)
    assert err.value.code == -2008 and err.value.file.endswith("Cell.gpl") and err.value.line == 3


def test_catch_as_exception_and_nested_declaration_error():
    """VB.NET's `Catch e As Exception` and `For k As Integer` declare e and k
    (twin accepts them); a Dim nested in a block is allowed (issue 10: Precise's own
    code does it), but the same name in two blocks with different types is -2003."""
    out = output_of("""
Sub Main()
    Dim x As Integer
    Try
        x = 1 \\ 0
    Catch e As Exception
        Console.WriteLine(e.ErrorCode)
    End Try
    For k As Integer = 1 To 3
        x += k
    Next
    Console.WriteLine(x)
End Sub
""")
    assert out == "-709\n6\n"
    with pytest.raises(ProgramError) as err:
        output_of("""
Sub Main()
    Dim i As Integer
    For i = 1 To 2
        If i = 2 Then
            Dim late As Integer
        Else
            Dim late As String
        End If
    Next
End Sub
""")
    assert err.value.code == -2003 and err.value.line == 8


def test_short_circuit_with_byref_calls():
    """Table 6-1: AndAlso/OrElse stop once the left side decides, also when the
    right side is a call with a ByRef argument (which needs statements first)."""
    out = output_of("""
Module M
    Public calls As Integer
    Function Check(ByRef x As Integer) As Boolean
        calls += 1
        x += 1
        Return x > 2
    End Function
    Public Sub Main()
        Dim v, i As Integer
        For i = 1 To 4
            If i > 2 AndAlso Check(v) Then Console.WriteLine("yes " & i)
        Next
        While v < 5 OrElse Not Check(v)
            v += 1
        End While
        Console.WriteLine(calls & " " & v)
    End Sub
End Module
""")
    assert out == "3 6\n"


def test_built_in_member_argument_count_is_checked_when_compiling():
    """A call of a built-in member with the wrong number of arguments is a
    compile error at its line (not a Python error at run time)."""
    with pytest.raises(ProgramError) as err:
        output_of("""
Sub Main()
    Dim x As Integer = 3
    Console.WriteLine("Value: {0}", x)
End Sub
""")
    assert err.value.code == -2005 and err.value.line == 4 and "Console.WriteLine" in err.value.message


def test_single_shows_seven_digits_and_object_types_are_checked():
    """Table 4-1: a Single is a 32-bit float (shown with its 7 digits by CStr,
    as VB does); Nothing in a String is ""; assigning an object of another
    class is a compile error (ch. 5 "Limitations": explicit classes)."""
    out = output_of("""
Sub Main()
    Dim a As Single = 0.1
    Dim d As Double = 0.1
    Dim s As String = Nothing
    Console.WriteLine(CStr(a) & " " & d & " [" & s & "] " & (a = d))
End Sub
""")
    assert out == "0.1 0.1 [] False\n"
    with pytest.raises(ProgramError) as err:
        output_of("Sub Main()\n    Dim l As Location\n    Dim p As New Profile\n    l = p\nEnd Sub\n")
    assert err.value.code == -2004 and err.value.line == 4


def test_wrong_arguments_to_a_member_found_at_run_time():
    """A member the compiler could not resolve (the result of a built-in method)
    called with the wrong number of arguments stops with a GPL error, located."""
    error = error_of("""
Sub Main()
    Dim loc As New Location
    Console.WriteLine(loc.Inverse.Mul())
End Sub
""")
    assert (error.code, error.line) == (-2005, 4) and "Location.Mul" in error.message
