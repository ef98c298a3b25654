"""The GPL User Manual's own example procedures (language chapters 4-11), run as
printed, with the repairs the PDF extraction needs noted in each docstring
(digest §14 lists them).  Section names and line numbers Lnnn refer to
/work/shared/seeds/gpl-user-manual.txt (Brooks 609644 Rev. A)."""

from __future__ import annotations

import pytest

from gpl_helpers import SEMAPHORES, output_of
from twin.errors import ProgramError


def lines(text: str) -> list[str]:
    return text.splitlines()


def test_assignment_rounds_to_integer():
    """Ch. 8 (L1293-1302): 2.25 * 3.5 = 7.875 stored in an Integer is 8."""
    out = output_of("""
Module Test
    Public Sub Main()
        Dim a, b As Single, c As Integer
        a = 2.25
        b = 3.5
        c = a * b
        Console.WriteLine(c)
    End Sub
End Module
""")
    assert out == "8\n"


def test_function_return_and_assign_to_name():
    """Ch. 10 "Returning from a Procedure" (L1495-1504): Return expr, or assign
    to the function's name then Exit Function."""
    out = output_of("""
Module M
    Public Sub Main()
        Console.WriteLine(Test(5))
        Console.WriteLine(Test(10))
    End Sub
    Function Test (ByVal x As Double) As Double
        If x < 10 Then
            Return x+1     ' Exits with a value of x+1
        Else
            Test = x+2     ' Sets the return value to x+2
            Exit Function  ' Exits with the current return value
        End If
    End Function
End Module
""")
    assert lines(out) == ["6", "12"]


def test_static_keeps_its_value_dim_does_not():
    """Ch. 4 (L668-679): Dim locals are re-initialised on every call, Static ones
    keep their value."""
    out = output_of("""
Module M
    Sub Counter()
        Dim ii As Short
        Static jj As Short
        Static kk As Integer = 10
        ii += 1
        jj += 1
        kk += 1
        Console.WriteLine(ii & " " & jj & " " & kk)
    End Sub
    Public Sub Main()
        Counter()
        Counter
        Call Counter()
    End Sub
End Module
""")
    assert lines(out) == ["1 1 11", "1 2 12", "1 3 13"]


def test_public_names_qualified_and_unqualified():
    """Ch. 4 "Scope of Names" (L696-710, L833-851): `Test1.aa` picks one of two
    Public aa; an unambiguous Public name needs no module name."""
    out = output_of("""
Module Test1
    Public aa As Integer
    Public bb As Integer
End Module
Module Test2
    Public aa As Integer
End Module
Module Test3
    Public Sub Main()
        Test1.aa = 5
        Test2.aa = 7
        bb = 9
        Console.WriteLine(Test1.aa & " " & Test2.aa & " " & Test1.bb)
    End Sub
End Module
""")
    assert out == "5 7 9\n"


def test_private_class_member_is_rejected():
    """Ch. 5 "Class Procedures" (L1052-1080): `aa.size_in = 5` is invalid since
    size_in is Private; the Property clips to 0..10 and Main writes 10."""
    source = """
Public Class cc
    Private size_in As Integer
    Public Property Size As Integer
        Get
            Return size_in
        End Get
        Set (value As Integer)
            If value > 10 Then
                value = 10
            ElseIf value < 0 Then
                value = 0
            End If
            size_in = value
        End Set
    End Property
End Class
Module M
    Public Sub Main()
        Dim aa As New cc
        Dim ii As Integer
        aa.Size = 20
        ii = aa.Size
        Console.WriteLine(ii)
        PRIVATE_LINE
    End Sub
End Module
"""
    assert output_of(source.replace("PRIVATE_LINE", "")) == "10\n"
    with pytest.raises(ProgramError) as err:
        output_of(source.replace("PRIVATE_LINE", "aa.size_in = 5"))
    assert err.value.code == -2008 and "size_in" in err.value.message


def test_class_fields_and_instance_methods():
    """Ch. 5 "Class Procedures" (L1008-1044): two objects of class cc, each with
    its own count; Increment works on the object it is called for: 6 and 21."""
    out = output_of("""
Public Class cc
    Public count As Integer
    Public Sub Increment
        count = count+1
    End Sub
End Class
Sub Main()
    Dim aa As New cc
    Dim bb As New cc
    aa.count = 5
    aa.Increment
    bb.count = 20
    bb.Increment
    Console.WriteLine(aa.count)
    Console.WriteLine(bb.count)
End Sub
""")
    assert lines(out) == ["6", "21"]


def test_overloaded_constructors():
    """Ch. 5 "Constructors" (L1094-1111): New cc calls the first New (count 25),
    New cc(15) the second."""
    out = output_of("""
Public Class cc
    Public count As Integer
    Public Sub New
        count = 25
    End Sub
    Public Sub New (value As Integer)
        count = value
    End Sub
End Class
Sub Main()
    Dim aa As New cc
    Dim bb As New cc(15)
    Console.WriteLine(bb.count)
    Console.WriteLine(aa.count)
End Sub
""")
    assert lines(out) == ["15", "25"]


def test_object_reference_copy_versus_clone():
    """Ch. 5 "Copying Object Variables and Values" and "Clone Method"
    (L937-960): assignment copies the pointer, Clone an independent value."""
    out = output_of("""
Sub Main()
    Dim My_Loc1 As New Location
    Dim My_Loc2 As Location
    Dim Same As Location
    Dim tmp As Double
    My_Loc1.X = 10
    My_Loc2 = My_Loc1.Clone
    Same = My_Loc1
    tmp = My_Loc2.X
    My_Loc1.X = 20
    Console.WriteLine(tmp & " " & My_Loc2.X & " " & Same.X)
End Sub
""")
    assert out == "10 10 20\n"


def test_compound_assignment_operators():
    """Ch. 8 Table 8-1 (L1313-1324): ^= *= /= \\= += -= <<= >>= &=."""
    out = output_of("""
Sub Main()
    Dim x As Double = 2
    Dim i As Integer = 7
    Dim s As String = "a"
    x ^= 3
    x *= 3
    x /= 4
    i \\= 2
    i += 10
    i -= 1
    i <<= 2
    i >>= 1
    s &= " more"
    Console.WriteLine(x & " " & i & " " & s)
End Sub
""")
    assert out == "6 24 a more\n"


def test_exception_in_called_procedure_is_caught_by_caller():
    """Ch. 11 (L1694-1713): the divide by 0 in test ends test and the Try in
    MAIN: the only output is "Exception!"."""
    out = output_of("""
Public Sub MAIN
    Dim exc1 As New Exception
    Try
        test()
        Console.WriteLine("Test completed") ' Never gets here
    Catch exc1
        Console.WriteLine("Exception!")      ' Is executed
    End Try
End Sub
Public Sub test()
    Dim ii As Integer
    ii = 1 / 0                              ' Generates exception
    Console.WriteLine("Inside Test")        ' Never gets here
End Sub
""", start="MAIN")
    assert out == "Exception!\n"


def test_retry_goto_from_catch_into_try():
    """Ch. 11 (L1719-1736): a GoTo in the Catch may jump back into its Try
    (retry, lowering a profile's speed by 10% each time); GoTo out of the Catch
    to a label after End Try is illegal."""
    source = """
Sub Main()
    Dim exc1 As New Exception
    Dim attempts As Integer
    Dim speed As Double = 100
    Try
retry:
        attempts += 1
        If speed > 75 Then Throw New Exception(-153)
        Console.WriteLine("moved at " & Format(speed, "0.0") & " after " & attempts)
    Catch exc1
        If (exc1.ErrorCode = -153) Then
            speed *= .9
            GoTo retry ' LEGAL BRANCH
        End If
        BAD
    End Try
bad_jump:
End Sub
"""
    assert output_of(source.replace("BAD", "")) == "moved at 72.9 after 4\n"
    with pytest.raises(ProgramError) as err:
        output_of(source.replace("BAD", "GoTo bad_jump ' ILLEGAL!!!"))
    assert err.value.code == -2011 and err.value.line == 16


def test_delegates_from_addressof_and_string():
    """Ch. 10 "Delegates" (L1530-1568): an array of delegates, made with
    AddressOf and with a String, called as del_obj(index)(3)."""
    out = output_of("""
Delegate Function My_template(ByVal arg1 As Integer) As String
Public Function f0 (ByVal mode As Integer) As String
    Return "f0:" & CStr(mode)
End Function
Public Function f1 (ByVal mode As Integer) As String
    Return "f1:" & CStr(mode)
End Function
Sub Main()
    Dim del_obj(1) As My_template
    Dim str As String
    Dim index As Integer
    del_obj(0) = New My_template(AddressOf f0)
    del_obj(1) = New My_template("f1")
    For index = 0 To 1
        str = del_obj(index)(3)   ' Call f0 or f1 with mode = 3
        Console.WriteLine(str)
    Next
End Sub
""")
    assert lines(out) == ["f0:3", "f1:3"]


def test_delegate_binds_the_object_at_creation():
    """Ch. 10 (L1600-1632): AddressOf my_obj.My_fn saves the object; assigning
    my_obj later does not change the delegate's target."""
    out = output_of("""
Delegate Function My_template(ByVal arg1 As Integer) As String
Class My_class
    Public tag As String
    Public Function My_fn(ByVal mode As Integer) As String
        Return tag & "(" & mode & ")"
    End Function
End Class
Public Sub Test
    Dim my_obj As New My_class
    Dim del_obj As My_template
    my_obj.tag = "first"
    del_obj = New My_template(AddressOf my_obj.My_fn)
    my_obj = New My_class
    my_obj.tag = "second"
    Console.Writeline(del_obj(3))
End Sub
""", start="Test")
    assert out == "first(3)\n"


def test_new_in_dim_forms_are_equivalent():
    """Ch. 4 (L750-754): `Dim Loc1 As New Location` and `Dim Loc1 As Location =
    New Location` both allocate a Location (repair: the two lines redeclare
    Loc1, so each goes in its own procedure); without New it is Nothing."""
    out = output_of("""
Sub First()
    Dim Loc1 As New Location ' Creates a location class instance
    Console.WriteLine(Loc1 Is Nothing)
End Sub
Sub Second()
    Dim Loc1 As Location = New Location ' Equivalent to above
    Dim Loc2 As Location
    Console.WriteLine((Loc1 Is Nothing) & " " & (Loc2 Is Nothing))
End Sub
Sub Main()
    First()
    Second()
End Sub
""")
    assert lines(out) == ["False", "False True"]


def test_const_cannot_be_assigned():
    """Ch. 4 (L756-762): `MaxCount = MaxCount+1` on a Const is invalid."""
    source = """
Sub Main()
    Const MaxCount As Integer = 10
    INVALID
    Console.WriteLine(MaxCount)
End Sub
"""
    assert output_of(source.replace("INVALID", "")) == "10\n"
    with pytest.raises(ProgramError) as err:
        output_of(source.replace("INVALID", "MaxCount = MaxCount+1 ' Invalid"))
    assert err.value.code == -2007 and err.value.line == 4


def test_scope_of_names_module_class_shared():
    """Ch. 4 "Scope of Names" (L833-851): MyMod.My_class.MaxSize is reachable,
    the Private Shared Size2 is not, and the Public ModVar needs no module name
    (repairs: "plete" junk line dropped, `My class` -> `My_class`, the wrapped
    comment rejoined)."""
    source = """
Module MyMod
   Public ModVar As Integer
   Public Class My_class
      Public Shared MaxSize As Integer
      Private Shared Size2 As Integer
   End Class
End Module
Module GPL
   Public Sub Main
      MyMod.My_class.MaxSize = 100 ' Okay
      INVALID
      ModVar = 20                  ' Okay, special case
      Console.WriteLine(MyMod.My_class.MaxSize & " " & MyMod.ModVar)
   End Sub
End Module
"""
    assert output_of(source.replace("INVALID", "")) == "100 20\n"
    with pytest.raises(ProgramError) as err:
        output_of(source.replace("INVALID", "MyMod.My_class.Size2 = 100 'Invalid, private variable"))
    assert err.value.code == -2008 and err.value.line == 12


def test_dot_operator_properties_methods_and_chains():
    """Ch. 5 "The Dot Operator" (L897-909): a property read and written, a Math
    method, a method called without parentheses, and `location_object.Inverse.X`
    (for a pure translation, -X)."""
    out = output_of("""
Sub Main()
    Dim location_object As New Location
    Dim Pos_x, Value As Double
    location_object.X = 3           ' Set x-axis displacement property
    Pos_x = location_object.X+2     ' Get x-axis displacement + 2
    Value = Math.Sqrt(3)            ' Sqrt is method of Math Class
    Console.WriteLine(Pos_x & " " & Format(Value, "0.000"))
    Pos_x = location_object.Inverse.X
    Console.WriteLine(Pos_x)
End Sub
""")
    assert lines(out) == ["5 1.732", "-3"]


def test_calling_procedures():
    """Ch. 10 "Calling a Procedure" (L1473-1481): `Call P (1, 2, 3)`, `P (1, 2, 3)`,
    a Function in an expression and a Function as a statement (its value
    dropped); a Sub without arguments needs no parentheses."""
    out = output_of("""
Sub MyProcedure(ByVal a As Integer, ByVal b As Integer, ByVal c As Integer)
    Console.WriteLine(a + b + c)
End Sub
Function MyFunction(ByVal y As Double) As Double
    Console.WriteLine("MyFunction " & y)
    Return y * 10
End Function
Sub NoArgs
    Console.WriteLine("no args")
End Sub
Sub Main()
    Dim x, y As Double
    y = 2
    Call MyProcedure (1, 2, 3) ' () always required for non-null args
    MyProcedure (1, 2, 3)      ' Call is optional
    x = 2 * MyFunction (y)
    MyFunction(y)              ' Do not care about the value
    NoArgs
    Console.WriteLine(x)
End Sub
""")
    assert lines(out) == ["6", "6", "MyFunction 2", "MyFunction 2", "no args", "40"]


def test_throw_statement_syntax():
    """Ch. 11 "Throw Statement" (L1740-1748): `Throw exception_object` forces an
    exception, here caught by the caller."""
    out = output_of("""
Sub Fails()
    Dim exception_object As New Exception
    exception_object.ErrorCode = -786
    Throw exception_object
End Sub
Sub Main()
    Dim e As Exception
    Try
        Fails()
    Catch e
        Console.WriteLine(e.ErrorCode)
    End Try
End Sub
""")
    assert out == "-786\n"


def test_append_string_under_a_lock():
    """Ch. 18 "Creating Thread-Safe Interlocks" (L3369-3391): AppendString and
    ReadString lock a String while two threads append to it (repairs: the lost
    acquire_sem/release_sem bodies written with Thread.TestAndSet, the stray
    `End Function` dropped)."""
    out = output_of("""
Module Strings
    Public my_lock As Integer
    Public text As String
""" + SEMAPHORES + """    Public Sub AppendString(ByRef sg As String, ByVal app As String)
        acquire_sem(my_lock)   ' Prohibit access by other threads
        sg &= app              ' Modify string while locked
        release_sem(my_lock)   ' Allow access by other threads
    End Sub
    Public Function ReadString(ByRef sg As String) As String
        Dim ret_string As String
        acquire_sem(my_lock)   ' Prohibit access by other threads
        ret_string = sg        ' Copy string while locked
        release_sem(my_lock)   ' Allow access by other threads
        Return ret_string
    End Function
    Public Sub Writer()
        Dim i As Integer
        For i = 1 To 20
            AppendString(text, "b")
            Thread.Sleep(1)
        Next
    End Sub
    Public Sub Main()
        Dim t As New Thread("Writer")
        Dim i As Integer
        t.Start
        For i = 1 To 20
            AppendString(text, "a")
            Thread.Sleep(1)
        Next
        t.Join(-1)
        Console.WriteLine(Len(ReadString(text)))
    End Sub
End Module
""")
    assert out == "40\n"
