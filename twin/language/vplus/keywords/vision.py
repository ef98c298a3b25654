"""The AdeptSight / ACE Sight vision keywords, served by the twin's vision server
(twin/vision/server.py): VRUN, VWAITI, VSTATE, VRESULT, VLOCATION, VPARAMETER, and the
VTIMEOUT parameter.  Arguments follow the public AdeptSight and ACE Sight reference
guides' V+ forms (the vision server's IP address first; sequence, tool, instance, result
or parameter, index, frame; all 1-based, the optional ones default to 1):

    VRUN $ip, sequence
    VWAITI (sequence) $ip, type
    status = VSTATE($ip, sequence)
    value = VRESULT($ip, sequence, tool, instance, result, index, frame)
    SET loc = VLOCATION($ip, sequence, tool, instance, result, index, frame)
    value = VPARAMETER($ip, sequence, tool, parameter, index, object)
    VPARAMETER (sequence, tool, parameter, index, object) $ip = value

A sequence is a [[vision.process]] of the cell file (1 = the first); tool 1 is its image
acquisition, the file's tools are 2, 3, ...  The result and parameter numbers are in
docs/vision.md (RESULT_IDS, PARAMETER_IDS below); any IP address reaches the twin's server.
"""

from __future__ import annotations

from ....controller.location import trans
from ....errors import ProgramError
from .. import messages as msg
from ..values import fail, to_int
from . import Str, function, instruction

# VRESULT result numbers (the Locator's, as in the guides: count, X, Y, rotation; the
# others twin-chosen), and what each reads from an instance.
INSTANCE_COUNT = 1310
RESULT_IDS = {
    1311: "x", 1312: "y", 1313: "z", 1314: "angle",  # mm, deg, robot frame
    1316: "score",  # match quality, 0..1
    2000: "area", 2001: "width", 2002: "length",  # mm^2, mm
    2100: "passed", 2101: "actual",  # inspection: 1/0, the measured value
}
LOCATION = 1311  # VLOCATION: the instance's location (x, y, z, rotation about z)
# VPARAMETER numbers -> tool properties (twin-chosen).
PARAMETER_IDS = {5000: "threshold", 5001: "min_area", 5002: "max_area", 5010: "min_score",
                 5011: "coarse_step"}


def _server(rt):
    server = getattr(rt.system, "vision", None)
    if server is None:
        raise fail(msg.DEVICE_NOT_READY, "no vision server in this cell (the cell file has no [vision])")
    return server


def _vision_error(err) -> ProgramError:
    return ProgramError(f"*{err}*", err.code)


def _address(ip) -> None:
    """The address in VWAITI's and VPARAMETER's items (the functions' is checked by the
    compiler: its parameter is a Str)."""
    if not isinstance(ip, str):
        raise fail(msg.WRONG_TYPE, "the vision server's IP address is a string")


def _one(value) -> int:
    return 1 if value is None else to_int(value)


def _run(rt, sequence):
    from ....vision.server import VisionError

    server = _server(rt)
    try:
        process = server.process(_one(sequence))
    except VisionError as err:
        raise _vision_error(err) from None
    run = server.last_run(process)
    if run is None:
        raise _vision_error(VisionError(-3205, f"sequence {_one(sequence)}"))
    return server, run


@instruction("VRUN")
def _vrun(rt, ip: Str, sequence=None):
    """Start a sequence: the picture is taken now, the results are ready after the
    modelled processing time (VWAITI waits for them)."""
    from ....vision.server import VisionError

    try:
        _server(rt).run(_one(sequence))
    except VisionError as err:
        raise _vision_error(err) from None


@instruction("VWAITI", waits=True)
def _vwaiti(rt, unit: tuple, items: tuple):
    """VWAITI (sequence) $ip, type: wait until the sequence's last run is complete (type 0,
    and the twin waits the same for any type); longer than VTIMEOUT seconds is an error."""
    sequence = unit[0] if unit else None
    ip = items[0] if items else None
    _address(ip)
    server, run = _run(rt, sequence)
    clock = rt.system.clock
    timeout = float(rt.system.parameters.get("VTIMEOUT", 0.0))
    if timeout > 0 and run.ready_at - clock() > timeout:
        raise ProgramError("*Vision server timeout*", -3208)
    yield lambda: clock() >= run.ready_at - 1e-9


@function("VSTATE")
def _vstate(rt, ip: Str, sequence=None):
    """0 never run, 1 running, 2 done with an error, 3 done."""
    server = _server(rt)
    from ....vision.server import VisionError

    try:
        run = server.last_run(server.process(_one(sequence)))
    except VisionError as err:
        raise _vision_error(err) from None
    return 0.0 if run is None else float(run.status(rt.system.clock()))


def _instances(rt, sequence, tool):
    from ....vision.server import VisionError

    server, run = _run(rt, sequence)
    tools = run.process.tools
    t = _one(tool)
    if not 1 <= t <= len(tools):
        raise _vision_error(VisionError(-3202, f"tool {t} of sequence {_one(sequence)} ({len(tools)} tools)"))
    if run.status(rt.system.clock()) == 1:
        raise ProgramError("*Vision sequence still running*", -3209)
    return server, run, run.results[tools[t - 1].name]


def _instance(rt, sequence, tool, instance):
    from ....vision.server import VisionError

    server, run, instances = _instances(rt, sequence, tool)
    i = _one(instance)
    if not 1 <= i <= len(instances):
        raise _vision_error(VisionError(-3204, f"instance {i} of {len(instances)}"))
    server.told_result(run, i, instances[i - 1])
    return instances[i - 1]


@function("VRESULT")
def _vresult(rt, ip: Str, sequence=None, tool=None, instance=None, result=None, index=None, frame=None):
    rid = to_int(result) if result is not None else INSTANCE_COUNT
    if rid == INSTANCE_COUNT:
        server, run, instances = _instances(rt, sequence, tool)
        server.told_count(run, len(instances))
        return float(len(instances))
    if rid not in RESULT_IDS:
        raise fail(msg.INVALID_ARGUMENT, f"result {rid} (docs/vision.md lists the result numbers)")
    inst = _instance(rt, sequence, tool, instance)
    value = getattr(inst, RESULT_IDS[rid])
    if value is None:
        raise fail(msg.INVALID_ARGUMENT, f"result {rid}: tool {_one(tool)} is not an inspection")
    return float(value)


@function("VLOCATION")
def _vlocation(rt, ip: Str, sequence=None, tool=None, instance=None, result=None, index=None, frame=None):
    if result is not None and to_int(result) != LOCATION:
        raise fail(msg.INVALID_ARGUMENT, f"VLOCATION result {to_int(result)} (only {LOCATION}, the location)")
    inst = _instance(rt, sequence, tool, instance)
    return trans(inst.x, inst.y, inst.z, inst.angle, 0.0, 0.0)


def _tool(rt, sequence, tool):
    from ....vision.server import VisionError

    server = _server(rt)
    try:
        process = server.process(_one(sequence))
    except VisionError as err:
        raise _vision_error(err) from None
    t = _one(tool)
    if not 1 <= t <= len(process.tools):
        raise _vision_error(VisionError(-3202, f"tool {t} of sequence {_one(sequence)}"))
    return process.tools[t - 1]


def _parameter_name(parameter) -> str:
    pid = to_int(parameter)
    if pid not in PARAMETER_IDS:
        raise fail(msg.INVALID_ARGUMENT, f"parameter {pid} (docs/vision.md lists the parameter numbers)")
    return PARAMETER_IDS[pid]


@function("VPARAMETER")
def _vparameter(rt, ip: Str, sequence=None, tool=None, parameter=None, index=None, obj=None):
    t = _tool(rt, sequence, tool)
    name = _parameter_name(parameter)
    params = t.parameters()
    if name not in params:
        raise fail(msg.INVALID_ARGUMENT, f"tool {t.name!r} has no {name}")
    return float(params[name])


@instruction("VPARAMETER")
def _set_vparameter(rt, unit: tuple, items: tuple):
    """VPARAMETER (sequence, tool, parameter, index, object) $ip = value."""
    if len(items) != 2:
        raise fail(msg.INVALID_ARGUMENT, "VPARAMETER (sequence, tool, parameter, index, object) $ip = value")
    ip, value = items
    _address(ip)
    sequence, tool, parameter = (list(unit) + [None] * 3)[:3]
    t = _tool(rt, sequence, tool)
    name = _parameter_name(parameter)
    try:
        t.set_parameter(name, value)
    except KeyError as err:
        raise fail(msg.INVALID_ARGUMENT, str(err.args[0])) from None
