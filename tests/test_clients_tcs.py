"""programs/gpl/tcs, the TCP Command Server project, over a raw socket: the reply format
(`0 <data>`, `<code> <message>`), the general, location and profile commands, motions,
the GPL error codes, and the connection's life (exit, the next client)."""

from __future__ import annotations

import socket

import pytest

from clients_helpers import serving

PORT = 10100


class Tcs:
    def __init__(self, port: int):
        self.sock = socket.create_connection(("127.0.0.1", port), timeout=60)
        self.lines = self.sock.makefile("rb")

    def __call__(self, command: str) -> str:
        self.sock.sendall(command.encode() + b"\n")
        line = self.lines.readline()
        assert line.endswith(b"\r\n"), line
        return line[:-2].decode()

    def close(self) -> None:
        self.sock.sendall(b"exit\n")
        assert self.lines.readline() == b""  # exit: closed without a reply
        self.sock.close()


def numbers(reply: str) -> list[float]:
    code, *data = reply.split()
    assert code == "0", reply
    return [float(v) for v in data]


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
        assert tcs("pd 2000 1") == "0 4"  # number of axes of robot 1
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
        tcs.close()

        # The next client is served.
        again = Tcs(served.port(PORT))
        assert again("attach") == "0 -1"
        again.close()
    assert served.returncode == 0, served.stderr
