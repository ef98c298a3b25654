"""The TCS against the command sequence of PyLabRobot's newer PreciseFlex driver (GitHub main,
`pylabrobot/brooks/precise_flex/`, not in the 0.2.2 release the other client tests install):
its setup reads the controller's identity, axes, limits and motion references with `pd`, and
gives up on its configuration, or refuses the arm, when a reply does not parse as it expects.
Replayed over a raw socket and parsed by the rules that driver applies (docs/clients.md,
"PyLabRobot main"): a reply is `<code> <data>`; a per-axis DataID is a comma list, axis 1
first, and the axes it lists are the ones the robot has (a 6th means a rail); a scalar DataID
is its first comma field; text is stripped; `version` is the server, then its modules."""

from __future__ import annotations

import json

import pytest

from clients_helpers import Tcs, numbers, serving

PORT = 10100


def data(reply: str) -> str:
    code, _, rest = reply.partition(" ")
    assert int(code) == 0, reply
    return rest


def per_axis(reply: str) -> dict[int, float]:
    values = [float(v) for v in data(reply).split(",")]
    return {axis: values[axis - 1] for axis in range(1, min(len(values), 6) + 1)}


def scalar(reply: str) -> float:
    return float(data(reply).split(",")[0])


def limits(tcs: Tcs, low: int, high: int) -> dict[int, tuple[float, float]]:
    lows, highs = per_axis(tcs(f"pd {low}")), per_axis(tcs(f"pd {high}"))
    return {axis: (lows[axis], highs[axis]) for axis in lows.keys() & highs.keys()}


def test_the_newer_pylabrobot_setup_reads_a_configuration_that_parses(tmp_path):
    report = tmp_path / "report.json"
    arguments = ["programs/gpl/tcs", "--scene", "scenes/pf400_plates.toml", "--fast", "--report", str(report)]
    with serving(arguments, [PORT]) as served:
        tcs = Tcs(served.port(PORT))
        # connect, initialize: response mode, power, attach, leave free mode.
        assert tcs("mode 0") == "0" and tcs("hp 1 20") == "0" and tcs("attach 1") == "0"
        assert tcs("freemode -1") == "0"

        # The configuration, every read the driver makes.
        soft = limits(tcs, 16078, 16077)
        assert soft == {1: (1.5, 401.5), 2: (-93, 93), 3: (12, 348), 4: (-960, 960), 5: (69, 134)}
        assert 6 not in soft  # no rail on this bench: the driver takes has_rail from this
        assert int(scalar(tcs("pd 2003"))) & 0x80 == 0  # axis mask: no dual gripper
        name = data(tcs("pd 2002")).strip()
        assert name and not name.split()[-1].upper().lstrip("0123456789").startswith("V")  # no vision gripper
        server, *modules = (part.strip() for part in data(tcs("version")).split(","))
        assert server and any("PARobot" in m for m in modules) and any("SSGrip" in m for m in modules)
        speed = per_axis(tcs("pd 2700"))
        assert speed == {1: 500, 2: 360, 3: 720, 4: 720, 5: 400}  # mm/s and deg/s at 100 %
        assert per_axis(tcs("pd 2702")) == {1: 3500, 2: 600, 3: 920, 4: 4000, 5: 10000}
        assert [scalar(tcs(f"pd {i}")) for i in (2704, 2705, 2706)] == [150, 300, 300]
        links = per_axis(tcs("pd 16050"))
        assert (links[2], links[3]) == (302, 289)  # the extended PF400 arm, as the driver classes it
        tool = [float(v) for v in data(tcs("pd 16051")).split(",")]
        assert tool[2] == pytest.approx(50.0, abs=0.01)  # flange to the gripper's plate centre, mm
        assert scalar(tcs("pd 2701")) == 1000  # the straight-line speed the cell plans with
        assert scalar(tcs("pd 2703")) == 1000
        for text_id in (100, 101, 102, 103, 110):
            assert data(tcs(f"pd {text_id}")).strip()
        assert int(scalar(tcs("pd 116"))) == 12  # robot type: PF400
        assert int(scalar(tcs("pd 2000"))) == 5 and int(scalar(tcs("pd 2004"))) == 0
        assert limits(tcs, 16076, 16075) == soft  # the twin's hard stops are its soft limits
        assert int(scalar(tcs("pd 234"))) == 21  # power on, attached

        # home, then the out-of-range check: homed, and every axis (the gripper too) in range.
        assert tcs("home") == "0"
        assert scalar(tcs("pd 2800")) == 1.0
        joints = dict(zip(range(1, 6), numbers(tcs("wherej"))))
        assert all(soft[axis][0] <= value <= soft[axis][1] for axis, value in joints.items())

        # Common calls: a joint move with the gripper's value (moveJ j1..j5), the jaws in
        # GripOpenPos/GripClosePos units, a pick at stored angles, the speed, the jaw sensor.
        target = [joints[1] - 20, joints[2] + 10, joints[3], joints[4], joints[5]]
        assert tcs("moveJ 1 " + " ".join(f"{v:g}" for v in target)) == "0"
        assert numbers(tcs("wherej")) == pytest.approx(target, abs=0.05)
        assert tcs("GripOpenPos 120") == "0" and tcs("gripper 1") == "0"
        assert numbers(tcs("wherej"))[4] == 120.0
        assert tcs("GripClosePos 75") == "0" and tcs("gripper 2") == "0"
        assert numbers(tcs("wherej"))[4] == 75.0 and tcs("IsFullyClosed") == "0 -1"
        assert tcs("Speed 1 40") == "0" and float(data(tcs("Speed 1")).split()[1]) == 40.0
        assert tcs("freemode 1").startswith("-714 ")  # the twin has no free mode to enter

        # A pick and a place as the driver makes them, in joints (its own IK gives the
        # angles; here the controller's, taught 100 mm above each nest, J1 the height).
        def nest_angles(x: float, y: float) -> list[float]:
            assert tcs(f"moveC 1 {x} {y} 127.2 0 90 180") == "0" and tcs("hereJ 7") == "0"
            angles = numbers(tcs("locAngles 7"))[2:]
            return [angles[0] - 100.0, *angles[1:]]
        source, target = nest_angles(350.0, -150.0), nest_angles(350.0, 150.0)
        assert tcs("GraspData 85.48 50 10") == "0"
        for station, command, reply in ((source, "pickplate", "0 -1"), (target, "placeplate", "0")):
            assert tcs("locAngles 1 " + " ".join(f"{v:g}" for v in station)) == "0"
            assert tcs("StationType 1 1 0 100 0 10") == "0"
            assert tcs(f"{command} 1 0 0") == reply  # pickplate: -1, a plate between the jaws
        assert numbers(tcs("wherec"))[:3] == pytest.approx([350.0, 150.0, 127.2], abs=0.1)
        assert tcs("IsFullyClosed") == "0 0"  # open, the plate left on the target nest
        tcs.close()
    assert served.returncode == 0, served.stderr
    plate = json.loads(report.read_text())["parts"][0]
    assert plate["region"] == "nest_b" and not plate["dropped"]
    assert plate["pose"][:2] == pytest.approx([350.0, 150.0], abs=2.0)
