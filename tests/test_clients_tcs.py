"""programs/gpl/tcs, the TCP Command Server project, over a raw socket: the reply format
(`0 <data>`, `<code> <message>`), the general, location and profile commands, motions,
the GPL error codes, and the connection's life (exit, the next client)."""

from __future__ import annotations

import socket

import pytest

from clients_helpers import Tcs, numbers, serving

PORT = 10100


def test_the_command_set_over_a_raw_socket():
    with serving(["programs/gpl/tcs", "--scene", "scenes/pf400_plates.toml", "--fast"], [PORT]) as served:
        tcs = Tcs(served.port(PORT))
        # Before power and attach: the controller's errors, as codes and messages.
        code, message = tcs("move 1 1").split(" ", 1)
        assert int(code) < 0 and "Power" in message  # the GPL library's power error
        assert tcs("hp") == "0 0"
        assert tcs("hp 1 10") == "0" and tcs("hp") == "0 1"
        assert tcs("move 1 1").startswith("-1021 ")  # not homed yet (Brooks error list: Robot not homed)
        assert tcs("attach") == "0 0" and tcs("home").startswith("-1009 ")  # homing needs the robot attached
        assert tcs("attach 1") == "0" and tcs("attach") == "0 -1"
        assert tcs("home") == "0"
        assert tcs("mode") == "0 0" and tcs("mode 1") == "0" and tcs("mode") == "0 1"
        assert tcs("nop") == "0"
        assert tcs("selectRobot") == "0 1"
        assert tcs("mspeed 50") == "0" and tcs("mspeed") == "0 50"
        assert tcs("payload 25") == "0" and tcs("payload") == "0 25"
        assert tcs("pd 100") == "0 Brooks Automation"
        assert tcs("pd 2000 1") == "0 5"  # number of axes of robot 1: the arm's 4, the gripper
        assert tcs("pd 2003 1") == "0 15"  # axis mask: axes 1 to 4
        assert tcs("pd 16050 1") == "0 0,302,289" + ",0" * 13  # the link lengths, as a PF400 lists them
        assert tcs("pd 16077 1") == "0 401.5,93,348,960,134"  # soft limits (the field unit's)
        assert tcs("pd 16078 1") == "0 1.5,-93,12,-960,69"
        assert tcs("sig 7 1") == "0" and tcs("sig 7") == "0 7 -1"
        assert tcs("tool") == "0 -60 0 50 0 0 0"  # the gripper's pads (the TCS sets it)
        assert tcs("base") == "0 0 0 0 0"

        # Positions: the scene's home, plate-centre tool point, RIGHTY.
        assert numbers(tcs("wherec")) == pytest.approx([350, 0, 140, 0, 90, 180, 1], abs=0.01)
        j1, j2, j3, j4, j5 = numbers(tcs("wherej"))
        assert j1 == pytest.approx(210.0, abs=0.01) and j3 > 0 and j5 == 110.0

        # Stations and profiles.
        assert tcs("locXyz 3 400 -50 120 30 90 180") == "0"
        assert numbers(tcs("locXyz 3")) == pytest.approx([0, 3, 400, -50, 120, 30, 90, 180])
        assert tcs("locConfig 3 1") == "0" and tcs("locConfig 3") == "0 3 1"
        assert tcs("locZClearance 3 40 1") == "0" and tcs("locZClearance 3") == "0 3 40 -1"
        assert tcs("locAngles 3").startswith("-763 ")  # a Cartesian station
        assert tcs("Profile 2 60 50 70 80 0 0 5 1") == "0"
        assert tcs("Profile 2") == "0 2 60 50 70 80 0 0 5 -1"
        assert tcs("Speed 2 40") == "0" and tcs("Speed 2") == "0 2 40"
        assert tcs("Straight 2 0") == "0" and tcs("Straight 2") == "0 2 0"

        # Motions: each replies once it has ended.
        assert tcs("move 3 2") == "0"
        assert numbers(tcs("wherec")) == pytest.approx([400, -50, 120, 30, 90, 180, 1], abs=0.05)
        assert tcs("moveAppro 3 2") == "0"  # ZWorld: 40 mm straight up
        assert numbers(tcs("wherec"))[2] == pytest.approx(160.0, abs=0.05)
        assert numbers(tcs("destC"))[:3] == pytest.approx([400, -50, 160], abs=0.01)
        assert tcs("moveOneAxis 1 250 2") == "0"
        assert numbers(tcs("wherej"))[0] == pytest.approx(250.0, abs=0.05)
        assert tcs("moveJ 2 200 -30 90 -20") == "0"
        assert numbers(tcs("destJ"))[:4] == pytest.approx([200, -30, 90, -20], abs=0.01)
        assert tcs("hereJ 4") == "0"
        assert numbers(tcs("locAngles 4"))[:6] == pytest.approx([1, 4, 200, -30, 90, -20], abs=0.05)
        assert tcs("hereC 5") == "0" and tcs("waitForEom") == "0"
        assert tcs("moveC 2 1000 0 100 0 90 180").startswith("-")  # out of reach: the GPL motion error

        # The gripper.
        assert tcs("gripper 2") == "0" and tcs("IsFullyClosed") == "0 -1"
        assert numbers(tcs("wherej"))[4] == 70.0
        assert tcs("GripOpenPos 105") == "0" and tcs("gripper 1") == "0" and tcs("IsFullyClosed") == "0 0"
        assert tcs("GraspData 85.5 40 12") == "0" and tcs("GraspData") == "0 85.5 40 12"
        assert tcs("StationType 6 0 0 30 15 5") == "0" and tcs("StationType 6") == "0 6 0 0 30 15 5"

        # Mistakes: the GPL codes.
        assert tcs("frobnicate") == "-714 *Unknown command*"
        assert tcs("move 3") == "-205 *Missing argument*"
        assert tcs("move x 1") == "-717 *Invalid number format*"
        assert tcs("locXyz 0") == "-707 *Value out-of-range*"
        assert tcs("moveOneAxis 9 1 1") == "-1002 *Invalid axis number*"
        # No rail on this bench (scenes/pf400_rail.toml has one: test_clients_rail.py).
        assert tcs("Rail 1 250") == "0" and tcs("Rail 1") == "0 250"  # kept with the station all the same
        assert tcs("MoveRail 1 1") == "-1002 *Invalid axis number*"
        assert tcs("MoveRail 0") == "0"  # nothing pending to cancel
        assert tcs("moveOneAxis 6 100 1") == "-1002 *Invalid axis number*"
        assert tcs("moveJ 1 200 -30 90 -20 110 50") == "-1002 *Invalid axis number*"
        assert tcs("moveExtraAxis 100") == "-1002 *Invalid axis number*"
        assert tcs("MoveRail 1 3") == "-202 *Invalid argument*"
        tcs.close()

        # The next client is served.
        again = Tcs(served.port(PORT))
        assert again("attach") == "0 -1"
        again.close()
    assert served.returncode == 0, served.stderr


def test_clients_that_leave_mid_command_or_before_the_reply_leave_the_server_serving():
    with serving(["programs/gpl/tcs", "--scene", "scenes/pf400_plates.toml", "--fast"], [PORT]) as served:
        port = served.port(PORT)
        setup = Tcs(port)
        assert setup("hp 1 10") == "0" and setup("attach 1") == "0" and setup("home") == "0"
        setup.close()
        # Half a command, then gone: the half line is dropped with the connection.
        half = socket.create_connection(("127.0.0.1", port), timeout=60)
        half.sendall(b"moveJ 1 200 -3")
        half.close()
        # A whole motion command, then gone before its reply: the motion still runs to
        # its end, the reply to nobody is lost, and the server takes the next client.
        hasty = socket.create_connection(("127.0.0.1", port), timeout=60)
        hasty.sendall(b"moveJ 1 200 -30 90 -20\n")
        hasty.close()
        after = Tcs(port)
        assert after("nop") == "0"
        assert after("waitForEom") == "0"
        assert numbers(after("wherej"))[:4] == pytest.approx([200, -30, 90, -20], abs=0.05)
        assert after("attach") == "0 -1"
        after.close()
    assert served.returncode == 0, served.stderr
