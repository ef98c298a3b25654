"""Logical-unit I/O: ATTACH, DETACH, FOPEN_, READ, WRITE, GETC, IOSTAT ...
(V+ guide v17, "Input/Output Control"; the devices are in ../fileio.py).

Each instruction takes `unit` (what its parentheses hold: lun, mode, record
...) and `items` (what follows).  The outcome of every operation is stored as
IOSTAT(lun); an I/O error never stops the program.
"""

from __future__ import annotations

from .. import messages as msg
from ....controller.scheduler import NETWORK_CYCLE
from ..fileio import RETURN_LUN, TERMINAL_LUN, IoError
from ..formats import render
from ..values import MAX_STRING, _str, fail, to_int
from . import Any, function, instruction
from .strings import leading_number

ROBOT_LUN = 0
NO_WAIT = 1  # READ mode bit


def _arg(unit: tuple, i: int, default: int = 0) -> int:
    return to_int(unit[i]) if len(unit) > i and unit[i] is not None else default


def _devices(rt):
    return rt.system.devices


@instruction("ATTACH", returns_unit=True)
def _attach(rt, unit: tuple, items: tuple):
    """ATTACH (lun, mode) $device.  Mode 4 picks a free unit and returns it."""
    mode = _arg(unit, 1)
    device = _str(items[0]).strip().upper() if items else None
    lun = unit[0] if unit else None
    if not mode & RETURN_LUN and (lun is None or to_int(lun) == ROBOT_LUN):
        rt.attach_robot()  # ATTACH () / (0): the robot (tasking.py)
        return None
    devices = _devices(rt)
    if device is None:
        device = "TERMINAL" if lun is not None and to_int(lun) == TERMINAL_LUN else "PENDANT"
    if mode & RETURN_LUN:
        try:
            number = devices.free_lun(rt.number, device)
        except IoError:
            return None  # every unit of the kind is taken: lun is left as it was
    else:
        number = to_int(lun)
    devices.run(rt.number, number, devices.attach, device)
    attached = devices.units.get((rt.number, number))
    if attached is not None and attached.serial is not None:
        attached.serial.listener = rt.set_event  # arriving bytes wake WAIT.EVENT
    return float(number) if mode & RETURN_LUN else None


@instruction("DETACH")
def _detach(rt, unit: tuple, items: tuple):
    lun = _arg(unit, 0)
    if lun == ROBOT_LUN:
        rt.detach_robot()  # DETACH () / (0): the robot is free for another task or the pendant
    else:
        _devices(rt).run(rt.number, lun, _devices(rt).detach)


def _opener(mode: str):
    def fopen(rt, unit: tuple, items: tuple):
        if not items:
            raise fail(msg.INVALID_ARGUMENT, "file specification")
        devices = _devices(rt)
        devices.run(rt.number, _arg(unit, 0), devices.fopen, mode, _str(items[0]), _arg(unit, 1), _arg(unit, 2),
                    rt.system.dialect)

    return fopen


for _name, _mode in (("FOPENR", "R"), ("FOPENW", "W"), ("FOPENA", "A"), ("FOPEND", "D")):
    instruction(_name)(_opener(_mode))


@instruction("FCLOSE")
def _fclose(rt, unit: tuple, items: tuple):
    _devices(rt).run(rt.number, _arg(unit, 0), _devices(rt).fclose)


@instruction("FDELETE")
def _fdelete(rt, unit: tuple, items: tuple):
    if not items:
        raise fail(msg.INVALID_ARGUMENT, "file specification")
    _devices(rt).run(rt.number, _arg(unit, 0), _devices(rt).fdelete, _str(items[0]))


@instruction("FSEEK")
def _fseek(rt, unit: tuple, items: tuple):
    record = to_int(items[0]) if items else _arg(unit, 1)
    _devices(rt).run(rt.number, _arg(unit, 0), _devices(rt).fseek, record)


@instruction("FEMPTY")
def _fempty(rt, unit: tuple, items: tuple):
    # WRITE goes straight to the file: there is never a buffer to empty.
    devices = _devices(rt)
    devices.run(rt.number, _arg(unit, 0), devices.unit)


@instruction("FSET")
def _fset(rt, unit: tuple, items: tuple):
    # Serial and terminal attributes (baud rate, parity...) change nothing on
    # an in-memory line; windows are absent.
    devices = _devices(rt)

    def check(task, lun):
        if devices.unit(task, lun).device == "DISK":
            raise IoError(msg.ILLEGAL_IO_COMMAND)

    devices.run(rt.number, _arg(unit, 0), check)


def _refuse(rt, unit: tuple, items: tuple):
    """An operation the unit's device cannot do: *Not attached to logical unit*
    when nothing is attached, else *Illegal I/O device command* (IOSTAT)."""
    devices = _devices(rt)

    def refuse(task, lun):
        devices.unit(task, lun)
        raise IoError(msg.ILLEGAL_IO_COMMAND)

    devices.run(rt.number, _arg(unit, 0), refuse)


@instruction("FCMND")
def _fcmnd(rt, unit: tuple, items: tuple):
    """FCMND (lun, command) $data.  On a TCP unit, the network commands servers
    use (../tcp.py: 600 closes a client).  The disk and serial commands (rename,
    format, mkdir, rmdir, DDCMP settings) have numbers only the Language
    Reference Guide gives, which we do not have: *Illegal I/O device command*."""
    devices = _devices(rt)

    def command(task, lun):
        attached = devices.unit(task, lun)
        if attached.tcp is None:
            raise IoError(msg.ILLEGAL_IO_COMMAND)
        attached.tcp.command(_arg(unit, 1), _str(items[0]) if items else "")

    devices.run(rt.number, _arg(unit, 0), command)


@instruction("FOPEN")
def _fopen(rt, unit: tuple, items: tuple):
    """FOPEN (lun, mode) "/LOCAL_PORT n /CLIENTS n /BUFFER_SIZE n" on a TCP unit
    (../tcp.py); graphics windows, the other use of FOPEN, are absent."""
    devices = _devices(rt)
    devices.run(rt.number, _arg(unit, 0), devices.open_network, _str(items[0]) if items else "")


@instruction("WRITE")
def _write(rt, unit: tuple, items: tuple):
    """WRITE (lun, record) items: formatted like TYPE; CR LF ends the record unless /S."""
    text, newline = render(items)
    devices = _devices(rt)
    devices.run(rt.number, _arg(unit, 0), devices.write, text, newline, _arg(unit, 1))


@instruction("READ", waits=True, targets=True, writes_back=True)
def _read(rt, unit: tuple, kinds: tuple):
    """READ (lun, record) var, ...: one record.  A single variable takes the
    whole record (a real its leading number, as VAL reads it; a string its
    first 128 characters); several take the record's comma- or space-separated
    fields in order.  A serial READ waits for a whole line; after an error the
    variables keep their values.  On a TCP unit, READ (lun, handle, mode) takes
    the bytes that have arrived and sets `handle` (../tcp.py).  The last value
    returned is for `handle` (None: unchanged)."""
    devices = _devices(rt)
    lun, record = _arg(unit, 0), _arg(unit, 1)
    attached = devices.units.get((rt.number, lun))
    if attached is not None and attached.tcp is not None:
        values = yield from _read_network(rt, devices, lun, _arg(unit, 2), kinds)
        return values
    values = yield from _read_record(rt, devices, lun, record, kinds)
    return values + [None]


def _read_network(rt, devices, lun: int, mode: int, kinds: tuple):
    while (outcome := devices.read_network(rt.number, lun, wait=not mode & NO_WAIT)) is None:
        yield NETWORK_CYCLE  # the network is polled once per cycle
    text, handle = outcome
    if devices.iostat(rt.number, lun) < 0:
        return [None] * len(kinds) + [None]
    fields = [text] if len(kinds) == 1 else _fields(text, len(kinds))
    return [f if kind == "s" else leading_number(f) for kind, f in zip(kinds, fields)] + [float(handle)]


def _read_record(rt, devices, lun: int, record: int, kinds: tuple):
    while True:
        text = devices.run(rt.number, lun, devices.read_record, record)
        if text is not None or devices.iostat(rt.number, lun) < 0:
            break
        yield rt.SLICE  # a serial line without a whole line yet: wait for it
    if text is None:
        return [None] * len(kinds)
    fields = [text] if len(kinds) == 1 else _fields(text, len(kinds))
    # A record may hold up to 512 bytes, a string 128: the rest is not kept.
    return [f[:MAX_STRING] if kind == "s" else leading_number(f) for kind, f in zip(kinds, fields)]


def _fields(text: str, count: int) -> list[str]:
    parts = [p for p in text.replace(",", " ").split(" ") if p]
    return (parts + [""] * count)[:count]


@function("IOSTAT")
def _iostat(rt, lun, select=None):
    return _devices(rt).iostat(rt.number, to_int(lun), 0 if select is None else to_int(select))


@function("GETC")
def _getc(rt, lun, mode=None):
    """GETC(lun, mode): mode 1 is no-wait; in wait mode the step has already
    waited for a byte (compile_library.py), so both read the same way here."""
    if mode is not None:
        to_int(mode)
    return float(_devices(rt).getc(rt.number, to_int(lun)))


@function("PENDANT")
def _pendant(rt, select):
    # No pendant is connected: no key is pressed, the speed bar is at rest and
    # PENDANT(-3) matches none of the states 1-4, so the manuals' programs take
    # their "busy or not connected" path.
    to_int(select)
    return 0.0


# Hardware the twin's cell does not have: graphics windows (FOPEN, G*,
# GETEVENT) act on units ATTACH could never open, so they report
# *Not attached to logical unit* through IOSTAT.
for _name in ("GARC", "GCHAIN", "GCLEAR", "GCLIP", "GCOLOR", "GCOPY", "GFLOOD", "GICON", "GLINE",
              "GLINES", "GLOGICAL", "GPANEL", "GPOINT", "GRECTANGLE", "GSCAN", "GSLIDE", "GTEXTURE", "GTRANS",
              "GTYPE"):
    instruction(_name)(_refuse)


@instruction("GETEVENT", targets=True)
def _getevent(rt, unit: tuple, kinds: tuple):
    _refuse(rt, unit, ())
    return [None] * len(kinds)


def _no_pendant(rt, *args: Any):
    # The T20 pendant screens of eV+ ([001] "Programming the T20 Pendant"):
    # with no pendant connected there is nothing to draw on.
    raise fail(msg.DEVICE_NOT_READY, "no pendant is connected")


for _name in ("PDNT.WRITE", "PDNT.NOTIFY", "PDNT.CLEAR"):
    instruction(_name)(_no_pendant)


def _no_camera(rt, *args: Any):
    # The vision option ([000] "label.blob()"): the twin's cell has no camera.
    raise fail(msg.DEVICE_NOT_READY, "no vision system is installed")


for _name in ("VDISPLAY", "VPICTURE", "VLOCATE"):
    instruction(_name)(_no_camera)
function("VFEATURE")(_no_camera)


@instruction("KEYMODE")
def _keymode(rt, mode, first, last=None):
    # Key modes of a pendant that is not connected: nothing to change.
    to_int(mode)

