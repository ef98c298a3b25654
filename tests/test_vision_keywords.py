"""The vision keywords of V+ and the Vision/VisResult members of GPL, one by one, on the
vision cell: results, parameters, states and the errors a program gets."""

from __future__ import annotations

import pytest

from conftest import ROOT
from twin.errors import ProgramError
from twin.runner import run_program

SCENE = ROOT / "scenes" / "scara_vision.toml"


def _vplus(tmp_path, body: str):
    program = tmp_path / "t.pg"
    program.write_text(".PROGRAM t()\n    $ip = \"192.168.1.120\"\n    DELAY 0.5\n    BREAK\n" + body + ".END\n")
    return run_program(program, scene=SCENE).report


def test_vplus_run_wait_state_results(tmp_path):
    report = _vplus(tmp_path, """\
    TYPE "before ", VSTATE($ip, 1)
    VRUN $ip, 1
    TYPE "running ", VSTATE($ip, 1)
    VWAITI (1) $ip, 0
    TYPE "done ", VSTATE($ip, 1)
    TYPE "count ", VRESULT($ip, 1, 2, 1, 1310)
    TYPE "acquired ", VRESULT($ip, 1, 1, 1, 1310)
    SET p = VLOCATION($ip, 1, 2, 1, 1311)
    TYPE /F0.1, "x ", DX(p), " ", VRESULT($ip, 1, 2, 1, 1311), " area ", VRESULT($ip, 1, 2, 1, 2000)
""")
    assert report.errors == []
    lines = report.output.splitlines()
    assert lines[:5] == ["before 0", "running 1", "done 3", "count 5", "acquired 0"]
    x, x2 = lines[5].split()[1:3]
    assert x == x2 and 200 < float(x) < 400


def test_vparameter_sets_what_the_tool_uses(tmp_path):
    report = _vplus(tmp_path, """\
    TYPE "threshold ", VPARAMETER($ip, 1, 2, 5000, 1, 1)
    VPARAMETER (1, 2, 5001) $ip = 5000
    VRUN $ip, 1
    VWAITI (1) $ip, 0
    TYPE "count ", VRESULT($ip, 1, 2, 1, 1310)
""")
    assert report.errors == []
    assert report.output.splitlines() == ["threshold 100", "count 0"]  # min_area above the parts'


@pytest.mark.parametrize("body, code", [
    ('    TYPE VRESULT($ip, 1, 2, 1, 1310)\n', -3205),  # no run yet
    ('    VRUN $ip, 7\n', -3201),  # no such sequence
    ('    VRUN $ip, 1\n    VWAITI (1) $ip, 0\n    TYPE VRESULT($ip, 1, 9, 1, 1310)\n', -3202),
    ('    VRUN $ip, 1\n    VWAITI (1) $ip, 0\n    SET p = VLOCATION($ip, 1, 2, 9, 1311)\n', -3204),
    ('    VRUN $ip, 1\n    TYPE VRESULT($ip, 1, 2, 1, 1310)\n', -3209),  # still running
    ('    VRUN $ip, 1\n    VWAITI (1) $ip, 0\n    TYPE VRESULT($ip, 1, 2, 1, 4242)\n', -407),
    ('    PARAMETER VTIMEOUT = 0.01\n    VRUN $ip, 1\n    VWAITI (1) $ip, 0\n', -3208),
])
def test_vplus_mistakes_are_located_errors(tmp_path, body, code):
    report = _vplus(tmp_path, body)
    assert len(report.errors) == 1
    assert report.errors[0]["code"] == code
    assert report.errors[0]["line"] == 4 + body.count("\n")  # the last line of the body


def test_an_address_that_is_not_a_string_is_a_load_time_error(tmp_path):
    with pytest.raises(ProgramError) as caught:
        _vplus(tmp_path, "    VRUN 42, 1\n")
    assert caught.value.code == -412 and caught.value.line == 5


def _gpl(tmp_path, body: str):
    folder = tmp_path / "p"
    folder.mkdir()
    (folder / "Project.gpr").write_text('ProjectBegin\nProjectName="p"\nProjectStart="Main"\n'
                                        'ProjectSource="Main.gpl"\nProjectEnd\n')
    (folder / "Main.gpl").write_text("Module M\n    Public Sub Main()\n        Dim vis As New Vision\n"
                                     "        Dim r As VisResult\n        Thread.Sleep(500)\n" + body
                                     + "    End Sub\nEnd Module\n")
    return run_program(folder, scene=SCENE).report


def test_gpl_vision_and_visresult_members(tmp_path):
    report = _gpl(tmp_path, """\
        Console.WriteLine("status " & CStr(vis.Status))
        vis.IPAddress = "192.168.0.50"
        vis.Process("Main")
        Console.WriteLine("status " & CStr(vis.Status) & " error " & CStr(vis.ErrorCode))
        Console.WriteLine("count " & CStr(vis.ResultCount("part1")))
        r = vis.Result("blobs", 1)
        Console.WriteLine("info " & CStr(r.InfoCount) & " " & Format(r.Info(1) - r.Loc.X, "0.000") & " type " & CStr(r.Type))
        Console.WriteLine("id " & CStr(r.ProcessID) & " error " & CStr(r.ErrorCode))
        Console.WriteLine("threshold " & CStr(vis.ToolProperty("blobs", "threshold")))
        vis.ToolProperty("blobs", "min_area") = 5000
        vis.Process("Main")
        Console.WriteLine("count " & CStr(vis.ResultCount("blobs")) & " id " & CStr(vis.Result("blobs", 1).ErrorCode))
        Console.WriteLine("system " & vis.ToolProperty("", "processes"))
        vis.Process("Nothing")
        Console.WriteLine("status " & CStr(vis.Status) & " error " & CStr(vis.ErrorCode))
        vis.Disconnect
        Console.WriteLine("ip " & vis.IPAddress)
""")
    assert report.errors == []
    assert report.output.splitlines() == [
        "status 0", "status 3 error 0", "count 5", "info 7 0.000 type 0", "id 1 error 0", "threshold 100",
        "count 0 id -3204", "system Main,Wrist", "status 2 error -3201", "ip 192.168.0.50"]


def test_gpl_result_count_of_an_unknown_tool_raises(tmp_path):
    report = _gpl(tmp_path, '        vis.Process("Main")\n        Console.WriteLine(CStr(vis.ResultCount("part9")))\n')
    assert report.errors[0]["code"] == -3202
    assert report.errors[0]["line"] == 7
