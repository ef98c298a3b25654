"""GPL as field programs write it (issue 10): each rule cites the User Manual
(/work/shared/seeds/gpl-user-manual.txt, lines Lnnn) or the public GPL Dictionary /
Parameter Database reference it comes from (docs/gpl.md records the decisions)."""

from __future__ import annotations

from pathlib import Path

import pytest

from twin.runner import run_program

from conftest import SCARA_SCENE as SCENE
from gpl_helpers import error_of, output_of


def _project(tmp_path: Path, body: str, declarations: str = "") -> Path:
    folder = tmp_path / "proj"
    folder.mkdir()
    (folder / "Project.gpr").write_text(
        'ProjectBegin\nProjectName="proj"\nProjectStart="Main"\nProjectSource="Main.gpl"\nProjectEnd\n')
    (folder / "Main.gpl").write_text(
        "Module Test\n" + declarations + "    Public Sub Main()\n" + body + "    End Sub\nEnd Module\n")
    return folder


def on_cell(tmp_path: Path, body: str, max_sim_time: float = 20.0):
    return run_program(_project(tmp_path, body), scene=SCENE, max_sim_time=max_sim_time).report


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
    assert report.output.splitlines() == ["-501", "-502", "-1000", "-706", "-708"]


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
