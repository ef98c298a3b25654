"""The global Robot and Controller classes (User Manual ch. 12, L2092-2185).

The twin has one robot, number 1.  Robot members that read state take an
optional robot number; any other number raises -1000.  What needs hardware the
twin does not model (encoders, motor temperatures, the pendant, the parameter
database beyond a few entries, loading other projects) raises -3103 with the
reason; docs/gpl.md lists how each member is treated.
"""

from __future__ import annotations

from ....controller.location import trans
from . import codes
from . import Ref, byref, gpl_class, pdb, shared
from .args import flag, number
from .locations import GplLocation, location_arg
from .motion import GplProfile, destination_joints
from .state import check_robot, config_of, robot_state, to_gpl_angles, tool_pose

# Controller.PowerState values, as DataID 234 numbers them (the manual does not list them;
# PyLabRobot's PreciseFlex DataIDs, pylabrobot/brooks/precise_flex/data_ids.py, do, and the
# TCP Command Server 3.0 labels them the same): 7 off, waiting for the enable signal; 20 on,
# ready for attach; 21 on, a thread attached.
POWER_STATE_OFF, POWER_STATE_ON, POWER_STATE_ATTACHED = 7, 20, 21
# Robot.TrajState values (TCP Command Server 3.0 state labels).
TRAJ_HALTED, TRAJ_IDLE, TRAJ_MOVING = 0, 1, 3


def power_state(rt) -> int:
    """Controller.PowerState, DataID 234: off, on, or on with robot 1 attached to a thread."""
    state = robot_state(rt)
    if not state.power:
        return POWER_STATE_OFF
    holder = state.attached_by
    return POWER_STATE_ATTACHED if holder is not None and getattr(holder, "alive", True) else POWER_STATE_ON


@gpl_class("Robot")
class Robot:
    """The global Robot class."""

    @shared
    def Attached(rt) -> int:
        """1 when the calling thread has robot 1 attached, else 0."""
        return 1 if robot_state(rt).attached_by == rt.current_thread() else 0

    @shared
    def set_Attached(rt, number) -> None:
        """Attach robot `number` to the calling thread (0 detaches).  Only one thread can
        have the robot; another thread's attach is refused while the holder is alive."""
        state = robot_state(rt)
        me = rt.current_thread()
        number = int(number)
        if number == 0:
            if state.attached_by == me:
                state.attached_by = None
            return
        check_robot(number)
        holder = state.attached_by
        if holder is not None and holder != me and getattr(holder, "alive", True):
            raise codes.fail(codes.ROBOT_ALREADY_ATTACHED, "by another thread")
        state.attached_by = me

    @shared
    def Selected(rt) -> int:
        return robot_state(rt).selected

    @shared
    def set_Selected(rt, number) -> None:
        check_robot(number)
        robot_state(rt).selected = int(number)

    @shared
    def Home(rt) -> None:
        """Home the attached robot: the twin's encoders are absolute, so homing only marks
        the robot homed (it needs high power, as on the controller)."""
        state = robot_state(rt)
        if not state.power:
            raise codes.fail(codes.POWER_OFF)
        if state.attached_by is None or state.attached_by != rt.current_thread():
            raise codes.fail(codes.NO_ROBOT_ATTACHED)
        state.homed = True

    @shared
    def Homed(rt, robot=1) -> bool:
        """Whether the robot has been homed since the controller started."""
        check_robot(robot)
        return robot_state(rt).homed

    @shared
    def HomeAll(rt) -> None:
        state = robot_state(rt)
        if not state.power:
            raise codes.fail(codes.POWER_OFF)
        state.homed = True

    @shared
    def Where(rt, robot=1) -> GplLocation:
        """Current Cartesian position, from the measured joints (Base and Tool applied)."""
        check_robot(robot)
        q = rt.robot.joints()
        where = GplLocation.cartesian(rt, tool_pose(rt, q))
        where.Config = config_of(rt, q)
        return where

    @shared
    def WhereAngles(rt, robot=1) -> GplLocation:
        check_robot(robot)
        return GplLocation.angles(rt, to_gpl_angles(rt, rt.robot.joints()))

    @shared
    def Dest(rt, robot=1) -> GplLocation:
        """Cartesian destination of the last motion."""
        check_robot(robot)
        state = robot_state(rt)
        return GplLocation.cartesian(rt, state.base * rt.robot.destination() * state.tool)

    @shared
    def DestAngles(rt, robot=1) -> GplLocation:
        check_robot(robot)
        return GplLocation.angles(rt, to_gpl_angles(rt, destination_joints(rt)))

    @shared
    def Source(rt, robot=1) -> GplLocation:
        """Cartesian start of the last motion (the present position before any motion)."""
        check_robot(robot)
        state = robot_state(rt)
        source = state.source if state.source is not None else rt.robot.destination()
        return GplLocation.cartesian(rt, state.base * source * state.tool)

    @shared
    def SourceAngles(rt, robot=1) -> GplLocation:
        """Angles at the start of the last motion (manual L2182); before any motion, the
        present destination's."""
        check_robot(robot)
        source_q = robot_state(rt).source_q
        return GplLocation.angles(rt, to_gpl_angles(rt, destination_joints(rt) if source_q is None else source_q))

    @shared
    def SpeedAngles(rt, robot=1) -> GplLocation:
        """Instantaneous axis speeds (deg/s or mm/s) as an Angles location."""
        check_robot(robot)
        return GplLocation.angles(rt, to_gpl_angles(rt, rt.robot.cell.robot_qvel()))

    @shared
    def Base(rt, robot=1) -> GplLocation:
        check_robot(robot)
        return GplLocation.cartesian(rt, robot_state(rt).base)

    @shared
    def set_Base(rt, value) -> None:
        robot_state(rt).base = location_arg(value).total()

    @shared
    def Tool(rt, robot=1) -> GplLocation:
        check_robot(robot)
        return GplLocation.cartesian(rt, robot_state(rt).tool)

    @shared
    def set_Tool(rt, value) -> None:
        robot_state(rt).tool = location_arg(value).total()

    @shared
    def RestartBase(rt, robot=1) -> GplLocation:
        """The Base set when the controller starts: DataID 16052 "Base set at restart"."""
        check_robot(robot)
        return GplLocation.cartesian(rt, trans(*pdb.database(rt).of(rt, 16052)[1]))

    @shared
    def RestartTool(rt, robot=1) -> GplLocation:
        """The Tool set when the controller starts: DataID 16051 "Tool set at restart"."""
        check_robot(robot)
        return GplLocation.cartesian(rt, trans(*pdb.database(rt).of(rt, 16051)[1]))

    @shared
    def LastProfile(rt, robot=1) -> GplProfile:
        check_robot(robot)
        last = robot_state(rt).last_profile
        return last.Clone() if last is not None else GplProfile(rt)

    @shared
    def Payload(rt, robot=1) -> float:
        """The last payload set (percent of the maximum); at restart the controller's
        "Dynamic feedforward default %payload" (DataID 16071)."""
        check_robot(robot)
        payload = robot_state(rt).payload
        return float(pdb.value(rt, 16071)) if payload is None else payload

    @shared
    def set_Payload(rt, value) -> None:
        """0 to 100 percent (console Set Payload); kept for reading back: the twin's servo
        model does not use it (the grasped part's mass is simulated by MuJoCo)."""
        percent = number(value)
        if not 0.0 <= percent <= 100.0:
            raise codes.fail(codes.VALUE_OUT_OF_RANGE, f"Payload {percent:g} (0 to 100 percent)")
        robot_state(rt).payload = percent

    @shared
    def RapidDecel(rt, robot=1) -> None:
        """`Robot.RapidDecel(robot)` as a statement, as the TCP Command Server 3.0's halt
        command writes it: stops the motion in progress at once."""
        check_robot(robot)
        rt.robot.stop()

    @shared
    def set_RapidDecel(rt, value) -> None:
        """`Robot.RapidDecel = True` (manual L2176, a property) stops any motion in progress
        at once."""
        if value:
            rt.robot.stop()

    @shared
    def TrajState(rt, robot=1, selector=0) -> int:
        """The trajectory state as the TCP Command Server 3.0 labels it: 0 "Halted" (high
        power off), 1 "Idle", 3 "Position mode - constant" while a motion runs (the twin
        does not report its accel / decel / blend phases, 2, 5, 4).  `Robot.TrajState(rob,
        n)` as field code writes it: the selector is checked as a number and gives the
        same state."""
        check_robot(robot)
        number(selector)
        if not robot_state(rt).power:
            return TRAJ_HALTED
        return TRAJ_MOVING if rt.robot.moving else TRAJ_IDLE

    @shared
    def CartMode(rt, robot=1) -> int:
        """No special Cartesian mode is ever active in the twin."""
        check_robot(robot)
        return 0

    JointToMotor = codes.unsupported("Robot.JointToMotor", "the twin has no motor encoders")
    MotorToJoint = codes.unsupported("Robot.MotorToJoint", "the twin has no motor encoders")
    DefLinComp = codes.unsupported("Robot.DefLinComp", "the twin has no motor encoders")
    MotorTempStatus = codes.unsupported("Robot.MotorTempStatus", "motor temperatures are not simulated")
    Custom = codes.unsupported("Robot.Custom", "kinematic-module parameters")
    RealTimeModAcm = codes.unsupported("Robot.RealTimeModAcm", "real-time path modification")


@gpl_class("Controller")
class Controller:
    """The global Controller class."""

    @shared
    def PowerEnabled(rt, timeout=0) -> bool:
        """Whether high power is on (`timeout` only matters when setting it)."""
        number(timeout)
        return robot_state(rt).power

    @shared
    def set_PowerEnabled(rt, *timeout_and_value) -> None:
        """`Controller.PowerEnabled = v` or `Controller.PowerEnabled(timeout) = v` (GPL
        Dictionary: timeout in seconds to wait for the power sequence).  Power comes on at
        once in the twin (no amplifier sequence), so the timeout never expires; turning
        it off stops any motion."""
        if not 1 <= len(timeout_and_value) <= 2:
            raise codes.fail(codes.INVALID_ARGUMENT, "PowerEnabled takes one index, the timeout")
        *timeout, value = timeout_and_value
        if timeout:
            number(timeout[0])
        state = robot_state(rt)
        state.power = flag(value)
        if not state.power:
            rt.robot.stop()

    @shared
    def PowerState(rt, mode=0) -> int:
        """The high power sequence state (power_state); `mode` (GPL Dictionary,
        Controller.PowerState(mode)) selects nothing else in the twin."""
        number(mode)
        return power_state(rt)

    @shared
    def SoftEStop(rt) -> bool:
        return False

    @shared
    def set_SoftEStop(rt, value) -> None:
        """A soft E-stop stops the robot and turns high power off."""
        if value:
            rt.robot.stop()
            robot_state(rt).power = False

    @shared
    def SystemSpeed(rt) -> float:
        """Global speed (percent) scaling every motion: the controller's monitor speed."""
        return rt.robot.settings.monitor_speed

    @shared
    def set_SystemSpeed(rt, value) -> None:
        value = float(value)
        if not 0.0 < value <= 100.0:
            raise codes.fail(codes.INVALID_ARGUMENT, f"SystemSpeed = {value:g} (0 < percent <= 100)")
        rt.robot.set_speed(value, monitor=True)

    @shared
    def Tick(rt) -> float:
        """Trajectory generator period, s: the twin feeds the servos every physics step."""
        return rt.robot.dt

    @shared
    def Timer(rt) -> float:
        """Simulated seconds since the run started."""
        return rt.clock()

    @shared
    def SleepTick(rt, ticks):
        """Sleep `ticks` trajectory generator periods."""
        end = rt.clock() + max(int(ticks), 0) * rt.robot.dt
        yield lambda: rt.clock() >= end - 1e-9

    @shared
    def SystemMessage(rt, message) -> None:
        """Append to the system message log (kept in the run, shown with the console output)."""
        text = str(message)
        robot_state(rt).messages.append(text)
        rt.console.write(f"[SystemMessage] {text}\n")

    @byref(2)
    @shared
    def ShowDialog(rt, buttons, message, button: Ref) -> None:
        """Headless: nobody can press a button, so the dialog is answered with its first
        button (1), and the message goes to the system message log."""
        Controller.SystemMessage(rt, f"{message} [{buttons}] -> 1")
        button.value = 1

    @byref(2)
    @shared
    def ShowDialogMCP(rt, mask, message, button: Ref) -> None:
        Controller.SystemMessage(rt, f"{message} (MCP) -> 1")
        button.value = 1

    @shared
    def RecordButton(rt) -> bool:
        """No pendant: the RECORD button is never pressed."""
        return False

    @shared
    def set_RecordButton(rt, value) -> None:
        """Clearing the latched flag is accepted; there is no pendant to set it."""

    @shared
    def PDb(rt, dataid, unit=1, unit2=1, array_index=0, key=0) -> str:
        """A parameter database value as a String (array_index 0: every value, comma separated)."""
        return pdb.read(rt, dataid, unit, unit2, array_index, numeric=False)

    @shared
    def set_PDb(rt, dataid, *rest) -> None:
        """Controller.PDb(dataid[, unit[, unit2[, array_index[, key]]]]) = String."""
        pdb.assign(rt, dataid, rest, numeric=False)

    @shared
    def PDbNum(rt, dataid, unit=1, unit2=1, array_index=1, key=0) -> float:
        """A numeric parameter database value (array_index 1: the first one)."""
        return pdb.read(rt, dataid, unit, unit2, array_index, numeric=True)

    @shared
    def set_PDbNum(rt, dataid, *rest) -> None:
        pdb.assign(rt, dataid, rest, numeric=True)

    Command = codes.unsupported("Controller.Command", "console commands")
    ErrorLog = codes.unsupported("Controller.ErrorLog", "the system error log")
    Load = codes.unsupported("Controller.Load", "one project per run")
    Unload = codes.unsupported("Controller.Unload", "one project per run")

