"""GPL language: parsing, types, conversions, control structures, procedures,
objects and exceptions (GPL User Manual, Brooks 609644 Rev. A, chapters 3-11;
line numbers Lnnn are in /work/shared/seeds/gpl-user-manual.txt)."""

from __future__ import annotations

import pytest

from gpl_helpers import error_of, output_of
from twin.errors import ProgramError
from twin.language.gpl.runtime import GplSystem


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
