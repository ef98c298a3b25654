"""GPL as field programs write it (issue 10): each rule cites the User Manual
(/work/shared/seeds/gpl-user-manual.txt, lines Lnnn) or the public GPL Dictionary /
Parameter Database reference it comes from (docs/gpl.md records the decisions)."""

from __future__ import annotations

from pathlib import Path

import pytest

from twin.errors import ProgramError
from twin.runner import run_program

from conftest import SCARA_SCENE as SCENE
from gpl_helpers import main_project, output_of


def on_cell(tmp_path: Path, body: str, max_sim_time: float = 20.0):
    return run_program(main_project(tmp_path, body), scene=SCENE, max_sim_time=max_sim_time).report


# ------------------------------------------------------------ parameter database
def test_pdb_reads_and_writes_robot_configuration(tmp_path):
    """GPL Dictionary, Controller.PDb / PDbNum (dataid, unit, unit2, array_index, key);
    PDB reference: 2000 Number of axes, 2002 Robot Name, 601 test speed, 1892 (manual
    L3034) eight NVRAM integers."""
    report = on_cell(tmp_path, """
        Console.WriteLine(CStr(Controller.PDbNum(2000)))
        Console.WriteLine(Controller.PDb(2002, 1))
        Controller.PDb(2002) = "Picker"
        Console.WriteLine(Controller.PDb(2002))
        Controller.PDbNum(601) = 25
        Console.WriteLine(Controller.PDb(601))
        Controller.PDbNum(1892, 1, 1, 3) = 7
        Console.WriteLine(Controller.PDb(1892))
        Console.WriteLine(CStr(Controller.PDbNum(1892, 1, 1, 3)))
        Console.WriteLine(Controller.PDb(100))
""")
    assert report.errors == []
    assert report.output.splitlines() == ["4", "Robot 1", "Picker", "25", "0,0,7,0,0,0,0,0", "7",
                                          "Brooks Automation"]


def test_pdb_errors_are_catchable_gpl_errors(tmp_path):
    """An unknown DataID, a read-only one, a robot that does not exist, a String DataID
    through PDbNum: each is a GPL error the program's Try/Catch sees."""
    report = on_cell(tmp_path, """
        Dim ex As Exception
        Try
            Console.WriteLine(Controller.PDb(9999))
        Catch ex
            Console.WriteLine(CStr(ex.ErrorCode))
        End Try
        Try
            Controller.PDbNum(2000) = 6
        Catch ex
            Console.WriteLine(CStr(ex.ErrorCode))
        End Try
        Try
            Console.WriteLine(Controller.PDb(2002, 2))
        Catch ex
            Console.WriteLine(CStr(ex.ErrorCode))
        End Try
        Try
            Console.WriteLine(CStr(Controller.PDbNum(2002)))
        Catch ex
            Console.WriteLine(CStr(ex.ErrorCode))
        End Try
        Try
            Console.WriteLine(CStr(Controller.PDbNum("x")))
        Catch ex
            Console.WriteLine(CStr(ex.ErrorCode))
        End Try
""")
    assert report.errors == []
    # Brooks error list: -1501 Unknown Data ID code, -209 Read only, -1514 Invalid parameter
    # array index (a robot number too large)
    assert report.output.splitlines() == ["-1501", "-209", "-1514", "-202", "-717"]


def test_pdb_robot_speed_homing_payload_and_gpl_variables(tmp_path):
    """DataIDs and labels of a PreciseFlex's saved configuration (AD-SDL/pf400_module_ros
    controller.pac, robot01.pac, calib01.pac, gpl_vars.pac, GPL 4.2J2): 2700 / 2702 the
    100 % joint speeds and accelerations (the robot model's, deg/s and mm/s), 16077 / 16078
    the joint soft limits, 2802 / 2803 / 2810 homing, 16071 the default %payload that
    Robot.Payload starts from, 601 the test speed that Controller.SystemSpeed also sets,
    1800-1849 GPL program Strings, 1890 a 25-value GPL variable array."""
    report = on_cell(tmp_path, """
        Console.WriteLine(Controller.PDb(2700))
        Console.WriteLine(Controller.PDb(2702))
        Console.WriteLine(Controller.PDb(16077) & " / " & Controller.PDb(16078))
        Console.WriteLine(Controller.PDb(2802) & " " & Controller.PDb(2803) & " " & Controller.PDb(2810))
        Controller.PDbNum(2803, 1, 1, 3) = -3
        Console.WriteLine(Controller.PDb(2803))
        Console.WriteLine(CStr(Robot.Payload))
        Controller.PDbNum(16071) = 25
        Console.WriteLine(CStr(Robot.Payload))
        Robot.Payload = 60
        Console.WriteLine(CStr(Robot.Payload) & " " & Controller.PDb(16071))
        Controller.SystemSpeed = 40
        Console.WriteLine(Controller.PDb(601))
        Controller.PDbNum(601) = 20
        Console.WriteLine(CStr(Controller.SystemSpeed))
        Controller.PDb(1800) = "tray A"
        Console.WriteLine(Controller.PDb(1800) & "|" & Controller.PDb(1849) & "|")
        Controller.PDbNum(1890, 1, 1, 25) = 3.5
        Console.WriteLine(CStr(Controller.PDbNum(1890, 1, 1, 25)) & " " & CStr(Controller.PDbNum(1891, 1, 1, 1)))
""")
    assert report.errors == []
    lines = report.output.splitlines()
    speeds = [float(v) for v in lines[0].split(",")]
    accels = [float(v) for v in lines[1].split(",")]
    assert len(speeds) == len(accels) == 4 and all(v > 0 for v in speeds + accels)
    upper, lower = ([float(v) for v in side.split(",")] for side in lines[2].split(" / "))
    assert len(upper) == len(lower) == 4 and all(lo < hi for lo, hi in zip(lower, upper))
    assert lines[3:] == ["2 -9,-9,-9,-9 1,2,3,4,0,0,0,0,0,0,0,0", "-9,-9,-3,-9", "0", "25", "60 25",
                         "40", "20", "tray A||", "3.5 0"]


def test_pdb_index_and_value_errors(tmp_path):
    """Brooks error list: -1509 Invalid data index (an array index beyond the array),
    -707 Value out-of-range (a test speed or payload outside 0-100 percent)."""
    report = on_cell(tmp_path, """
        Dim ex As Exception
        Try
            Console.WriteLine(Controller.PDb(1890, 1, 1, 26))
        Catch ex
            Console.WriteLine(CStr(ex.ErrorCode))
        End Try
        Try
            Controller.PDbNum(601) = 150
        Catch ex
            Console.WriteLine(CStr(ex.ErrorCode))
        End Try
        Try
            Robot.Payload = -5
        Catch ex
            Console.WriteLine(CStr(ex.ErrorCode))
        End Try
        Try
            Controller.PDbNum(16077, 1, 1, 1) = 10
        Catch ex
            Console.WriteLine(CStr(ex.ErrorCode))
        End Try
        Try
            Controller.PDbNum(14002, 1, 0, 0) = 1
        Catch ex
            Console.WriteLine(CStr(ex.ErrorCode))
        End Try
        Console.WriteLine(CStr(Controller.SystemSpeed))
""")
    assert report.errors == []
    # 14002 (release brake, a servo expert command of the PDB's 14000-14999 group): -204
    assert report.output.splitlines() == ["-1509", "-707", "-707", "-209", "-204", "50"]


def test_restart_tool_and_base_come_from_the_database(tmp_path):
    """PDB 16051 "Tool set at restart" / 16052 "Base set at restart" are what
    Robot.RestartTool / RestartBase return."""
    report = on_cell(tmp_path, """
        Controller.PDb(16051) = "0,0,50,0,0,0"
        Console.WriteLine(CStr(Robot.RestartTool.Z))
        Console.WriteLine(Controller.PDb(16051, 1, 1, 3))
""")
    assert report.errors == []
    assert report.output.splitlines() == ["50", "50"]


def test_boot_state_and_power_enabled_with_a_timeout(tmp_path):
    """Manual L1954-1959: at boot high power is off and the robot is not homed;
    `Controller.PowerEnabled(timeout) = True` (GPL Dictionary form used by the TCP
    Command Server) turns power on; Robot.Where reports the arm configuration in Config
    (Table 4-4: GPL_Righty &H01, GPL_Lefty &H02)."""
    report = on_cell(tmp_path, """
        Console.WriteLine(CStr(Controller.PowerEnabled) & " " & CStr(Robot.Homed))
        Controller.PowerEnabled(30) = True
        Robot.Attached = 1
        Robot.Home
        Console.WriteLine(CStr(Controller.PowerEnabled) & " " & CStr(Robot.Homed))
        Dim here As Location = Robot.Where
        Console.WriteLine(CStr(here.Config And (GPL_Righty Or GPL_Lefty)))
""")
    assert report.errors == []
    lines = report.output.splitlines()
    assert lines[:2] == ["False False", "True True"]
    assert lines[2] in ("1", "2")


# ------------------------------------------------------------ declarations and arrays
def test_redim_and_redim_preserve():
    """ReDim gives new bounds (manual L766-817); ReDim Preserve (GPL Dictionary, ReDim
    statement) keeps the elements inside both the old and the new bounds."""
    out = output_of("""
Module M
    Public Sub Main()
        Dim a(2) As Integer
        Dim g(1, 1) As String
        a(0) = 5
        a(2) = 7
        ReDim Preserve a(4)
        Console.WriteLine(a(0) & " " & a(2) & " " & a(4) & " " & a.GetUpperBound(0))
        ReDim Preserve a(1)
        Console.WriteLine(a(0) & " " & a.Length)
        ReDim a(3)
        Console.WriteLine(a(0) & " " & a.Length)
        g(1, 1) = "x"
        ReDim Preserve g(2, 3)
        Console.WriteLine(g(1, 1) & g(2, 3) & "|")
    End Sub
End Module
""")
    assert out == "5 7 0 4\n5 2\n0 4\nx|\n"


def test_dim_inside_blocks_as_precise_code_writes_it():
    """A Dim inside If, For, Select, While and Try bodies (Precise's sample code does
    this; VB.NET block scope): each works, and its initialiser runs each time."""
    out = output_of("""
Module M
    Public Sub Main()
        Dim i As Integer
        For i = 1 To 3
            Dim sq As Integer = i * i
            If sq > 1 Then
                Dim msg As String = "sq=" & sq
                Console.WriteLine(msg)
            End If
        Next
        Select Case i
            Case 4
                Dim four As New Location
                four.X = 4
                Console.WriteLine(CStr(four.X))
        End Select
        Try
            Dim z As Double = 1.5
            Console.WriteLine(CStr(z))
        Catch
        End Try
        If True Then
            Dim msg As String
            Console.WriteLine("again " & msg)
        End If
    End Sub
End Module
""")
    assert out == "sq=4\nsq=9\n4\n1.5\nagain sq=9\n"


def test_class_const_inside_its_class_its_shared_bounds_and_outside():
    """A class `Public Const` (manual L756-762: constants) is a name inside its class,
    including in its own Shared array bounds, and Class.Const outside."""
    out = output_of("""
Class Buf
    Public Const SIZE As Integer = 4
    Public Shared cells(SIZE) As Integer
    Public Function Cap() As Integer
        Return SIZE * 2
    End Function
End Class
Module M
    Public Sub Main()
        Dim b As New Buf
        Console.WriteLine(Buf.SIZE & " " & b.Cap() & " " & Buf.cells.GetUpperBound(0))
    End Sub
End Module
""")
    assert out == "4 8 4\n"


def test_a_class_public_const_is_unqualified_outside_where_it_is_unique():
    """Brooks error list -772 *Ambiguous Public reference*: "References to top-level public
    variables do not need to be qualified by their containing module or class provided that
    they are unique"; the TCP Command Server 3.0 tests `sta.flags And STA_FL_PAL` in its
    modules with STA_FL_PAL a Public Const of class Station.  The same name Public in two
    classes must be qualified (-2009)."""
    out = output_of("""
Public Class Station
    Public Const STA_FL_PAL As Integer = &H0001
    Public Shared Count As Integer = 2
    Public flags As Integer
End Class
Module M
    Public Sub Main()
        Dim s As New Station
        s.flags = 17
        Console.WriteLine(CStr(s.flags And STA_FL_PAL) & " " & CStr(Count))
    End Sub
End Module
""")
    assert out == "1 2\n"
    with pytest.raises(ProgramError) as caught:
        output_of("""
Class A
    Public Const FLAG As Integer = 1
End Class
Class B
    Public Const FLAG As Integer = 2
End Class
Module M
    Public Sub Main()
        Console.WriteLine(CStr(FLAG))
    End Sub
End Module
""")
    assert caught.value.code == -2009 and caught.value.line == 10


def test_module_const_from_another_modules_member_whatever_the_file_order(tmp_path):
    """ch. 10 "Special Initialization": module variables are initialised module by module
    in load order; a Const that uses a Const of a module loaded later still gets its value
    (constants are set first, in the order they need each other)."""
    folder = tmp_path / "p"
    folder.mkdir()
    (folder / "Project.gpr").write_text('ProjectBegin\nProjectName="p"\nProjectStart="Main"\n'
                                       'ProjectSource="A.gpl"\nProjectSource="B.gpl"\nProjectEnd\n')
    (folder / "A.gpl").write_text("Module A\n    Public Const Two As Integer = B.One * 2\n"
                                  "    Public Const Label As String = \"n=\" & B.One\n"
                                  "    Public Sub Main()\n        Console.WriteLine(Label & \" \" & CStr(Two))\n"
                                  "    End Sub\nEnd Module\n")
    (folder / "B.gpl").write_text("Module B\n    Public Const One As Integer = 1\nEnd Module\n")
    from gpl_helpers import run_project
    system, thread = run_project(folder)
    assert thread.error is None
    assert system.console.output == "n=1 2\n"


def test_constants_that_need_each_other_are_a_located_error():
    with pytest.raises(ProgramError) as caught:
        output_of("""
Module A
    Public Const X As Integer = B.Y
    Public Sub Main()
    End Sub
End Module
Module B
    Public Const Y As Integer = A.X + 1
End Module
""")
    assert caught.value.code == -2006 and caught.value.line == 3 and "B.Y" in caught.value.text


def test_goto_out_of_a_try_block_runs_its_finally():
    """GoTo out of a Try's statements to an enclosing label, as field code does (VB.NET runs
    the Finally on the way out); the manual's own illegal cases stay -2011 (L1717-1736:
    out of the Catch, `GoTo bad_jump ' ILLEGAL!!!`; into a block; out of a Finally)."""
    out = output_of("""
Module M
    Public Sub Main()
        Dim n As Integer
        Try
            n = 1
            If n = 1 Then
                GoTo done
            End If
        Catch
        Finally
            Console.WriteLine("finally")
        End Try
        n = 2
done:
        Console.WriteLine(CStr(n))
    End Sub
End Module
""")
    assert out == "finally\n1\n"
    for inside in ("Catch\n            GoTo over", "Finally\n            GoTo over"):
        with pytest.raises(ProgramError) as caught:
            output_of(f"""
Module M
    Public Sub Main()
        Try
        {inside}
        End Try
over:
    End Sub
End Module
""")
        assert caught.value.code == -2011


def test_line_continuation_without_a_blank_before_the_underscore():
    """` _` continues a line (manual L1130-ish, ch. 4); Brooks' own code writes `,_`."""
    out = output_of("""
Module M
    Public Sub Main()
        Console.WriteLine(Add(1,_
            2) & "|" & my_name())
    End Sub
    Function Add(ByVal a As Integer,_
                 ByVal b As Integer) As Integer
        Return a + b
    End Function
    Function my_name() As String
        Return "x_"
    End Function
End Module
""")
    assert out == "3|x_\n"


def test_write_only_built_in_properties(tmp_path):
    """A Shared built-in property with only a setter (the GPL Dictionary has write-only
    members) compiles and runs when assigned, and reading it is -2002."""
    from twin.language.gpl.library import CLASSES, gpl_class, shared

    @gpl_class("WriteOnlyProbe")
    class Probe:
        seen: list = []

        @shared
        def set_Level(rt, value) -> None:
            Probe.seen.append(value)

    try:
        assert output_of("""
Module M
    Public Sub Main()
        WriteOnlyProbe.Level = 7
        Console.WriteLine("ok")
    End Sub
End Module
""") == "ok\n"
        assert Probe.seen == [7]
        with pytest.raises(ProgramError) as caught:
            output_of("Module M\n    Public Sub Main()\n        Console.WriteLine(WriteOnlyProbe.Level)\n"
                      "    End Sub\nEnd Module\n")
        assert caught.value.code == -2002
    finally:
        del CLASSES["writeonlyprobe"]
    report = on_cell(tmp_path, """
        Robot.RapidDecel = True
        Console.WriteLine("ok")
""")
    assert report.errors == [] and report.output == "ok\n"


# ------------------------------------------------------------ numeric semantics
@pytest.mark.parametrize("statement", [
    "a = big + 1", "a = big * 2", "a = -big - 2", "a += big", "a -= -big", "a *= 3",
    "cells(1) = big + big", "cells(1) -= big + 2", "k.value = big + 1", "k.value -= big + 2", "a = Twice(big)",
    "a = big \\ 0.5", "a = CDbl(big) * 4",
])
def test_integer_overflow_is_an_error_for_every_store(statement):
    """Integer is 32-bit (Table 4-1); a value out of its range stored in an Integer (a
    variable, an array element, a field, a Function's result) is -708 *Value infinite or NAN*,
    as Short and Byte are; the program's Try/Catch sees it."""
    out = output_of(f"""
Class Counter
    Public value As Integer
End Class
Module M
    Function Twice(ByVal x As Integer) As Integer
        Return x * 2
    End Function
    Public Sub Main()
        Dim big As Integer = 2147483647
        Dim a As Integer = 1000000000
        Dim cells(2) As Integer
        Dim k As New Counter
        Try
            {statement}
            Console.WriteLine("no error " & a)
        Catch ex As Exception
            Console.WriteLine(CStr(ex.ErrorCode))
        End Try
    End Sub
End Module
""")
    assert out == "-708\n"


def test_integer_arithmetic_in_range_is_unchanged():
    out = output_of("""
Module M
    Public Sub Main()
        Dim a As Integer = 2147483646
        Dim b As Short = 3
        a += 1
        b *= 2
        Console.WriteLine(a & " " & b & " " & (a - 1) & " " & CStr(-2147483647 - 1))
    End Sub
End Module
""")
    assert out == "2147483647 6 2147483646 -2147483648\n"


@pytest.mark.parametrize("expression, code", [("d * d", -710), ("d + d", -710), ("-d - d", -710),
                                              ("d / 1E-300", -710), ("d ^ 2", -710), ("CDbl(\"1E400\")", -708)])
def test_double_overflow_is_an_error_not_infinity(expression, code):
    """Double overflow is an error, never INF, stored, shown or converted (L1156): an
    operation's result beyond the Double range is -710 *Arithmetic overflow*, a conversion
    of a String beyond it -708 *Value infinite or NAN* (Brooks error code list)."""
    for use in (f"x = {expression}", f"Console.WriteLine({expression})", f"Console.WriteLine(CStr({expression}))"):
        out = output_of(f"""
Module M
    Public Sub Main()
        Dim d As Double = 1E308
        Dim x As Double
        Try
            {use}
            Console.WriteLine("no error " & x)
        Catch ex As Exception
            Console.WriteLine(CStr(ex.ErrorCode))
        End Try
    End Sub
End Module
""")
        assert out == f"{code}\n", use


def test_not_on_a_number_is_logical():
    """Table 6-1: Not converts False (0) to True (-1) and any True (<> 0) value to False (0);
    And / Or / Xor stay bitwise on numbers."""
    out = output_of("""
Module M
    Public Sub Main()
        Dim n As Integer = 5
        Dim z As Integer = 0
        Dim d As Double = 0.5
        Console.WriteLine((Not n) & " " & (Not z) & " " & (Not d) & " " & (Not False) & " " & (6 And 3))
        If Not n Then
            Console.WriteLine("wrong")
        Else
            Console.WriteLine("Not 5 is False")
        End If
    End Sub
End Module
""")
    assert out == "0 -1 0 True 2\nNot 5 is False\n"


def test_compound_assignment_evaluates_its_target_once():
    """`a(f()) += 1` calls f once (VB.NET semantics of compound assignment)."""
    out = output_of("""
Class Box
    Public v(20) As Integer
End Class
Module M
    Dim calls As Integer
    Dim shared_box As New Box
    Function F() As Integer
        calls += 1
        Return calls
    End Function
    Function GetBox() As Box
        calls += 10
        Return shared_box
    End Function
    Public Sub Main()
        Dim a(5) As Integer
        a(F()) += 7
        Console.WriteLine(calls & " " & a(1))
        GetBox().v(F()) += 2
        Console.WriteLine(calls & " " & shared_box.v(12))
    End Sub
End Module
""")
    assert out == "1 7\n12 2\n"


def test_character_constants_are_codes():
    """Table 4-4: GPL_CR is the ASCII carriage return character (13), GPL_LF line feed (10);
    the manual writes `Chr(GPL_CR) & Chr(GPL_LF)` (L2398)."""
    out = output_of("""
Module M
    Public Sub Main()
        Dim message As String = "Test message" & Chr(GPL_CR) & Chr(GPL_LF)
        Console.WriteLine(CStr(GPL_CR + GPL_LF) & " " & message.Length & " " & Asc(message.Substring(12, 1)))
    End Sub
End Module
""")
    assert out == "23 14 13\n"


# ------------------------------------------------------------ procedures
def test_byref_is_a_true_reference():
    """ch. 10 (L1505-1514) ByRef passes the variable itself: the callee's write is the
    caller's at once, so it stays when the callee then throws, and two ByRef parameters
    bound to one variable are that one variable."""
    out = output_of("""
Module M
    Sub SetThenFail(ByRef v As Integer)
        v = 42
        Throw New Exception(-786)
    End Sub
    Sub Both(ByRef a As Integer, ByRef b As Integer)
        a = 5
        Console.WriteLine("b sees " & b)
        b += 1
    End Sub
    Public Sub Main()
        Dim x As Integer = 1
        Try
            SetThenFail(x)
        Catch
        End Try
        Console.WriteLine("after throw " & x)
        Dim y As Integer = 0
        Both(y, y)
        Console.WriteLine("y " & y)
    End Sub
End Module
""")
    assert out == "after throw 42\nb sees 5\ny 6\n"


def test_delegates_in_fields_and_module_variables_are_called_directly():
    """ch. 10: a Delegate is an object like any other; one stored in a class field or a
    module variable is called as obj.handler(x) or Module.fallback(x)."""
    out = output_of("""
Delegate Function Op(ByVal x As Integer) As Integer
Delegate Sub Note(ByVal s As String)
Class Handler
    Public handler As Op
    Public notify As Note
End Class
Module Ops
    Public fallback As Op
    Public Function Twice(ByVal x As Integer) As Integer
        Return 2 * x
    End Function
    Public Function Neg(ByVal x As Integer) As Integer
        Return -x
    End Function
    Public Sub Say(ByVal s As String)
        Console.WriteLine("say " & s)
    End Sub
End Module
Module M
    Public Sub Main()
        Dim h As New Handler
        h.handler = New Op(AddressOf Ops.Twice)
        h.notify = New Note(AddressOf Ops.Say)
        Ops.fallback = New Op(AddressOf Ops.Neg)
        Console.WriteLine(h.handler(21) & " " & Ops.fallback(3))
        h.notify("hi")
    End Sub
End Module
""")
    assert out == "42 -3\nsay hi\n"


# ------------------------------------------------------------ library signatures
def test_library_signatures_field_code_relies_on(tmp_path):
    """GPL Dictionary: Location.Angles(a1, ..., an) makes an Angles location with one value
    per robot axis; Profile.Speed2 = 0 is allowed; Exception.UpdateErrorCode with no
    argument; Robot.TrajState(robot, n); Location.Pos = a Cartesian value on an Angles
    location makes it Cartesian."""
    report = on_cell(tmp_path, """
        Dim a As New Location
        a.Angles(10, 20, 30, 40)
        Console.WriteLine(a.Type & " " & a.Angle(2) & " " & a.Angle(4))
        Dim p As New Profile
        p.Speed2 = 0
        Console.WriteLine(CStr(p.Speed2))
        Dim ex As New Exception(-1033)
        ex.UpdateErrorCode()
        ex.UpdateErrorCode
        Console.WriteLine(CStr(ex.ErrorCode))
        Console.WriteLine(CStr(Robot.TrajState(1, 0)))
        Dim c As New Location
        c.XYZ(300, 10, 200, 0, 180, 0)
        a.Pos = c
        Console.WriteLine(a.Type & " " & a.X & " " & a.Y)
""")
    assert report.errors == []
    assert report.output.splitlines() == ["1 20 40", "0", "-1033", "0", "0 300 10"]


def test_pallet_order_uses_the_dictionarys_encoding():
    """GPL Dictionary, RefFrame.PalletOrder: 0 row-column-layer (a new pallet's), 1 row-layer-
    column, 2 column-row-layer, 3 column-layer-row, 4 layer-row-column, 5 layer-column-row."""
    out = output_of("""
Module M
    Public Sub Main()
        Dim frame As New RefFrame
        Dim spot As New Location
        Dim order As Integer
        frame.Type = 1
        frame.Loc.XYZ(0, 0, 0, 0, 0, 0)
        frame.PalletMaxIndex(1) = 2
        frame.PalletMaxIndex(2) = 2
        frame.PalletMaxIndex(3) = 2
        frame.PalletPitch(1) = 1
        frame.PalletPitch(2) = 10
        frame.PalletPitch(3) = 100
        spot.RefFrame = frame
        Console.WriteLine(CStr(frame.PalletOrder))
        For order = 0 To 5
            frame.PalletOrder = order
            frame.PalletRowColLay(1, 1, 1)
            frame.PalletNextPos
            Console.WriteLine(order & ": " & (spot.Pos.X + spot.Pos.Y + spot.Pos.Z))
        Next
    End Sub
End Module
""")
    assert out.splitlines() == ["0", "0: 1", "1: 1", "2: 10", "3: 10", "4: 100", "5: 100"]


def test_an_undefined_procedure_in_addressof_or_a_delegate_or_a_thread():
    """AddressOf a procedure that does not exist stops the load (Undefined symbol); a name
    given as a String is found when the New runs: a Delegate's is -729 *Undefined symbol*,
    a Thread's -744 *Invalid start procedure* ("The start procedure specified ... by a
    Thread.Start method could not be found"), both from the Brooks error code list and
    both catchable, as a command server's dispatcher needs."""
    for target in ("Missing", "M.Missing"):
        with pytest.raises(ProgramError) as caught:
            output_of(f"""
Delegate Sub Cmd()
Module M
    Public Sub Main()
        Dim d As New Cmd(AddressOf {target})
    End Sub
End Module
""")
        assert caught.value.code == -2002 and caught.value.line == 5
    out = output_of("""
Delegate Sub Cmd()
Module M
    Public Sub Main()
        Try
            Dim d As New Cmd("NoSuchCommand")
        Catch ex As Exception
            Console.WriteLine(CStr(ex.ErrorCode))
        End Try
        Try
            Dim t As New Thread("NoSuchProcedure")
            t.Start()
        Catch ex As Exception
            Console.WriteLine(CStr(ex.ErrorCode))
        End Try
    End Sub
End Module
""")
    assert out == "-729\n-744\n"


# ------------------------------------------------------------ members of the manual's tables
def test_source_angles_and_power_state_mode(tmp_path):
    """Manual L2182 Robot.SourceAngles: the axes at the start of the previous motion
    (Robot.DestAngles its end); L2131 Controller.PowerState, which the GPL Dictionary
    writes Controller.PowerState(mode)."""
    report = on_cell(tmp_path, """
        Dim target As New Location
        Dim start As Location
        Dim p As New Profile
        Console.WriteLine(CStr(Controller.PowerState(0)))
        Controller.PowerEnabled = True
        Robot.Attached = 1
        Robot.Home
        Console.WriteLine(CStr(Controller.PowerState(1)))
        start = Robot.WhereAngles
        target.Type = 1
        target.Angles(start.Angle(1) + 20, start.Angle(2) - 15, start.Angle(3), start.Angle(4) + 30)
        Move.Loc(target, p)
        Move.WaitForEOM
        Console.WriteLine(Format(Robot.SourceAngles.Angle(1) - start.Angle(1), "0.000"))
        Console.WriteLine(Format(Robot.SourceAngles(1).Angle(4) - start.Angle(4), "0.000"))
        Console.WriteLine(Format(Robot.DestAngles.Angle(1) - start.Angle(1), "0.000"))
        Move.Loc(start, p)
        Move.WaitForEOM
        Console.WriteLine(Format(Robot.SourceAngles.Angle(2) - start.Angle(2), "0.000"))
""")
    assert report.errors == []
    # PowerState: 7 off, 21 on with the robot attached (DataID 234, robot.power_state)
    assert report.output.splitlines() == ["7", "21", "0.000", "0.000", "20.000", "-15.000"]


def test_pdb_as_the_tcp_command_server_reads_it(tmp_path):
    """A unit and sub unit of 0 are the first (the controller's .pac files write
    "DI: 2000, 0, 0, 0"), and PDbNum with array_index 0 reads or sets the first value:
    the TCP Command Server 3.0 reads Controller.PdbNum(2000, robot, 0, 0) (number of
    axes), PdbNum(2007, robot, 0, 0) (the robot model number, 400 for a PreciseFlex 400
    in robot01.pac) and PdbNum(113) (PDB: controller type, 10 for the next generation
    controller)."""
    report = on_cell(tmp_path, """
        Console.WriteLine(CStr(Controller.PdbNum(2000, 1, 0, 0)) & " " & CStr(Controller.PdbNum(2007, 1, 0, 0)))
        Console.WriteLine(CStr(Controller.PdbNum(113)) & " " & Controller.PDb(2002, 0, 0))
        Controller.PdbNum(2803, 1, 0, 0) = -3
        Console.WriteLine(Controller.PDb(2803, 0, 0, 0))
""")
    assert report.errors == []
    assert report.output.splitlines() == ["4 0", "10 Robot 1", "-3,-9,-9,-9"]


def test_pdb_robot_model_number_of_the_pf400(tmp_path):
    """DataID 2007 "Robot model number or version" is 400 on the PreciseFlex 400 bench
    (robot01.pac of a PF400), as the TCP Command Server's RobType expects."""
    scene = Path(__file__).resolve().parents[1] / "scenes" / "pf400_plates.toml"
    report = run_program(main_project(tmp_path, """
        Console.WriteLine(CStr(Controller.PdbNum(2007, 1, 0, 0)) & " " & Controller.PDb(2000))
"""), scene=scene, max_sim_time=5.0).report
    assert report.errors == []
    assert report.output.splitlines() == ["400 5"]  # the servo gripper is axis 5, as on a PF400


def test_system_state_power_and_homing_dataids_and_traj_state(tmp_path):
    """What the TCP Command Server 3.0 reads and writes: DataID 234 the system state (7
    "Power off - waiting for power request TRUE", 20 "Power on - ready to have GPL attach
    robot", 21 "GPL project attached to robot", the server's own labels), 241 "Power enable"
    (Brooks error list, -1600) turns power on, 213 = 1 homes every robot (its HomeAll), 111
    the number of robots; Robot.TrajState 0 "Halted" with power off, 1 "Idle", 3 "Position
    mode - constant" while a motion runs (its DestC / DestJ test `state <= 1`)."""
    report = on_cell(tmp_path, """
        Dim target As Location
        Dim p As New Profile
        Console.WriteLine(Controller.PDb(234) & " " & CStr(Robot.TrajState(1)) & " " & CStr(Controller.PdbNum(111)))
        Controller.PDbNum(241, 0, 0, 0) = 1
        Console.WriteLine(Controller.PDb(234) & " " & CStr(Controller.PowerEnabled) & " " & CStr(Robot.TrajState(1)))
        Controller.PDbNum(213) = 1
        Console.WriteLine(CStr(Robot.Homed) & " " & Controller.PDb(213))
        Robot.Attached = 1
        Console.WriteLine(Controller.PDb(234))
        target = Robot.WhereAngles
        target.Angle(1) = target.Angle(1) + 30
        Move.Loc(target, p)
        Thread.Sleep(100)
        Console.WriteLine(CStr(Robot.TrajState(1)))
        Move.WaitForEOM
        Console.WriteLine(CStr(Robot.TrajState(1)))
        Controller.PDbNum(241) = 0
        Console.WriteLine(Controller.PDb(234) & " " & CStr(Controller.PowerEnabled))
""")
    assert report.errors == []
    assert report.output.splitlines() == ["7 0 1", "20 True 1", "True 0", "21", "3", "1", "7 False"]


def test_vision_default_result_and_rapid_decel_as_a_statement(tmp_path):
    """The TCP Command Server 3.0 asks `glbVision.ResultCount` and `glbVision.Result()`
    with no tool ("If not specified, return the default result"): the process's last tool
    (docs/gpl.md); its halt command is the statement `Robot.RapidDecel(robot)` (manual
    L2176 gives the property form, `Robot.RapidDecel = True`, too)."""
    scene = Path(__file__).resolve().parents[1] / "scenes" / "scara_vision.toml"
    report = run_program(main_project(tmp_path, """
        Dim vis As New Vision
        Dim r As VisResult
        Dim far As Location
        Dim p As New Profile
        Thread.Sleep(500)
        vis.Process("Main")
        Console.WriteLine(CStr(vis.ResultCount) & " " & CStr(vis.ResultCount("inspect")))
        r = vis.Result()
        Console.WriteLine(Format(r.Loc.X - vis.Result("inspect", 1).Loc.X, "0.000") & " " & CStr(r.InspectPassed))
        Controller.PowerEnabled = True
        Robot.Attached = 1
        Robot.Home
        far = Robot.WhereAngles
        far.Angle(1) = far.Angle(1) + 60
        Move.Loc(far, p)
        Thread.Sleep(100)
        Robot.RapidDecel(1)
        Move.WaitForEOM
        Console.WriteLine(CStr(Math.Abs(Robot.WhereAngles.Angle(1) - far.Angle(1)) > 1))
"""), scene=scene, max_sim_time=20.0).report
    assert report.errors == []
    count, inspected = report.output.splitlines()[0].split()
    assert count == inspected and int(count) >= 1
    assert report.output.splitlines()[1].startswith("0.000 ")
    assert report.output.splitlines()[2] == "True"  # stopped short of the destination


def test_exception_messages_of_codes_field_code_throws():
    """Exception.Message of a code a program sets and throws, as the TCP Command Server
    3.0 does (-1017 with RobotError, -717, -704, -1001): the messages of the Brooks error
    code list."""
    out = output_of("""
Module M
    Public Sub Main()
        Dim codes(3) As Integer
        Dim i As Integer
        Dim ex As Exception
        codes(0) = -1017
        codes(1) = -717
        codes(2) = -704
        codes(3) = -1001
        For i = 0 To 3
            Try
                ex = New Exception
                ex.ErrorCode = codes(i)
                If i = 0 Then
                    ex.RobotError = True
                    ex.RobotNum = 1
                End If
                Throw ex
            Catch ex
                Console.WriteLine(CStr(ex.ErrorCode) & " " & ex.Message)
            End Try
        Next i
    End Sub
End Module
""")
    assert out.splitlines() == ["-1017 Not in position control mode: Robot 1", "-717 Invalid number format",
                                "-704 Missing quote mark", "-1001 Undefined robot"]


def test_a_new_locations_zclearance_is_not_set(tmp_path):
    """Brooks error list -794 *ZClearance property not set*: "When a Location is first
    created, its ZClearance property is set to a very large number" and Move.Approach to
    it is this error (the TCP Command Server 3.0 tests `ZClearance > 1E30` before a pick);
    GDE-generated files write 1E+32 for it."""
    report = on_cell(tmp_path, """
        Dim nest As New Location
        Dim p As New Profile
        Dim ex As Exception
        Controller.PowerEnabled = True
        Robot.Attached = 1
        Robot.Home
        nest = Robot.Where
        Console.WriteLine(CStr(nest.ZClearance > 1E30) & " " & CStr((New Location).ZClearance))
        Try
            Move.Approach(nest, p)
        Catch ex
            Console.WriteLine(CStr(ex.ErrorCode) & " " & ex.Message)
        End Try
        nest.ZClearance = 20
        Move.Approach(nest, p)
        Move.WaitForEOM
        Console.WriteLine(Format(Robot.Where.Z - nest.Z, "0.0"))
""")
    assert report.errors == []
    lines = report.output.splitlines()
    assert lines[:2] == ["True 1E+32", "-794 ZClearance property not set"]
    assert abs(abs(float(lines[2])) - 20.0) < 0.2


def test_a_class_shared_init_runs_at_start_up():
    """A class's `Private Shared Sub Init()` runs at start-up, before the modules' Init
    subs and the start procedure: the TCP Command Server 3.0's GpoFile class fills its
    Shared type-name tables so ("Init routine called automatically at startup"); manual
    ch. 10 "Special Initialization" describes the module case."""
    out = output_of("""
Public Class Names
    Public Const LAST As Integer = 2
    Private Shared Label(LAST) As String
    Private Shared Sub Init()
        Label(1) = "Integer"
        Label(2) = "Location"
        Console.WriteLine("class init")
    End Sub
    Public Shared Function Of(ByVal i As Integer) As String
        Return Label(i)
    End Function
End Class
Module M
    Public Sub Init()
        Console.WriteLine("module init " & Names.Of(2))
    End Sub
    Public Sub Main()
        Console.WriteLine(Names.Of(1))
    End Sub
End Module
""")
    assert out.splitlines() == ["class init", "module init Location", "Integer"]
