"""V+ programs written the way a cell programmer writes them, not copied from
the manuals: tabs, mixed case, abbreviated keywords, comments everywhere,
data sections in the same file, a file ending in `.END` without a newline.

The expected output of each program was worked out from the manuals' rules
([000] V+ Language User's Guide v17, [001] eV+ Language User's Guide, line
numbers cite them), not copied from a run.  The second half feeds malformed
programs: every one must give a located V+ error, never a Python exception.
"""

from __future__ import annotations

import random

import pytest

from twin.errors import ProgramError
from twin.language.vplus import messages as msg
from twin.language.vplus.runtime import MAJOR_CYCLE

from vplus_helpers import output_of, run_vplus


def drive_inputs(edges: dict[int, list[tuple[float, bool]]]):
    """each_cycle hook: every input follows its (time, level) changes."""

    def each_cycle(system):
        for signal, changes in edges.items():
            reached = [level for time, level in changes if system.clock() >= time]
            system.io.set(signal, reached[-1] if reached else False)

    return each_cycle


# --------------------------------------------------------------- palletizing
PALLET = """\
.PROGRAM pallet.calc()
; Palletizing: a 3 x 4 grid of places from a taught corner.
\tAUTO row, col, n\t\t; loop counters
\tSET corner = TRANS(400, -150, 20, 0, 180, 0)\t; tool pointing down
\tpitch.x = 55.5\t\t; mm between columns
\tpitch.y = 40\t\t; mm between rows
\tn = 0
\tFOR row = 0 TO 2
\t    FOR col = 0 TO 3
\t        SET place[n] = SHIFT(corner BY col*pitch.x, row*pitch.y, 0)
\t        n = n+1
\t    END\t; col
\tEND\t; row
\tTYPE "places: ", /I0, n
\tTYPE /F8.1, DX(place[0]), DY(place[0]), DZ(place[0])
\tTYPE /F8.1, DX(place[11]), DY(place[11]), DZ(place[11])
\tTYPE /F8.1, DX(place[6]), DY(place[6])
\t; relative to the corner's own axes: x and z turn over with the tool
\tSET q = corner:TRANS(10, 20, 5)
\tTYPE /F8.1, DX(q), DY(q), DZ(q)
.END
"""


def test_palletizing_grid_with_shift_trans_and_nested_for():
    """SHIFT adds to a location's position in world axes ([000] "SHIFT");
    the compound a:b is b relative to a ([000] "Relative Transformations"):
    with the corner turned 180 degrees about y, +x and +z of the corner point
    along -x and -z of the world.  /Fn.m: n wide, m decimals."""
    assert output_of(PALLET) == (
        "places: 12\n"
        "   400.0  -150.0    20.0\n"
        "   566.5   -70.0    20.0\n"
        "   511.0  -110.0\n"
        "   390.0  -130.0    15.0\n"
    )


# -------------------------------------------------------------- state machine
STATES = """\
.PROGRAM Cell.States()
\tstate = 1\t\t\t; 1 idle, 2-3 running, else done
\tcycles = 0
10\tCase state Of
\t  Value 1:
\t    Type "IDLE"
\t    state = 2
\t  VALUE 2, 3:\t\t; either running state
\t    TYPE "RUN ", /I0, state
\t    cycles = cycles+1
\t    IF cycles < 3 THEN
\t        state = 3
\t    ELSE
\t        state = 9
\t    END
\t  ANY
\t    TYPE "DONE after ", /I0, cycles, " cycles"
\t    GOTO 99\t\t; leave the machine
\tEND
\tGOTO 10
99\tTYPE "stop"
.END"""


def test_state_machine_with_case_and_goto_in_mixed_case():
    """CASE ... VALUE a, b: ... ANY ... END ([000] "CASE"), GOTO to a step label
    ([000] "GOTO") out of the CASE; keywords in any case; no newline after .END."""
    assert output_of(STATES) == "IDLE\nRUN 2\nRUN 3\nRUN 3\nDONE after 3 cycles\nstop\n"


# ------------------------------------------------------------ barcode parsing
BARCODE = """\
.PROGRAM scan.main()
\t; the reader sends  LOT:A17-QTY:0042-W:12.5
\t$code = "LOT:A17-QTY:0042-W:12.5"
\tCALL scan.parse($code, qty, weight, $lot)
\tTYPE "lot ", $lot, " qty ", /I0, qty, " weight ", /F5.1, weight
\t; split the same code on "-" with $DECODE (mode 0: the text before "-")
\t$rest = $code
\tWHILE LEN($rest) > 0 DO
\t    $field = $DECODE($rest, "-", 0)
\t    TYPE "[", $field, "]", /S
\t    IF LEN($rest) > 0 THEN
\t        $sep = $DECODE($rest, "-", 1)\t; drop the separator
\t    END
\tEND
\tTYPE ""
\tTYPE "bad qty reads ", /I0, VAL("QTY?"), ", ", POS($code, "XYZ", 1)
.END

.PROGRAM scan.parse($code, qty, weight, $lot)
\tAUTO p, q
\tp = POS($code, "LOT:", 1)
\tq = POS($code, "-", p)
\t$lot = $MID($code, p+4, q-p-4)
\tqty = VAL($MID($code, POS($code, "QTY:", 1)+4, 4))
\tweight = VAL($MID($code, POS($code, "W:", 1)+2, 10))
\tRETURN
.END
"""


def test_barcode_parsing_with_mid_pos_val_decode_and_reference_parameters():
    """POS(string, substring, start) is the 1-based position or 0; $MID(string,
    first, count); VAL reads the leading number, 0 for none ([000] "String
    Functions"); parameters are passed by reference ([000] "Argument Passing");
    $DECODE mode 0 takes the text up to a separator, mode 1 the separators,
    both removed from the string."""
    assert output_of(BARCODE) == (
        "lot A17 qty 42 weight  12.5\n"
        "[LOT:A17][QTY:0042][W:12.5]\n"
        "bad qty reads 0, 0\n"
    )


# ------------------------------------------------------------- REACTI guard
GUARD = """\
.PROGRAM guard()
\tGLOBAL stop.req
\tstop.req = FALSE
\tcount = 0
\tREACTI 1001, on.stop\t; light curtain
\tWHILE NOT stop.req DO
\t    count = count+1
\t    WAIT\t\t\t; one pass per major cycle
\tEND
\tIGNORE 1001
\tTYPE "guard off after reaction"
.END

.PROGRAM on.stop()
\tTYPE "light curtain broken"
\tstop.req = TRUE
\tRETURN
.END
"""


def test_reacti_guarded_loop_runs_the_reaction_then_the_loop_ends():
    """REACTI signal, program: the transition of 1001 interrupts the loop and
    calls the routine, which RETURNs to the interrupted step ([000] L4495-4520);
    a bare WAIT lets one major cycle (16 ms) pass ([000] L1435-1437)."""
    system, task = run_vplus(GUARD, each_cycle=drive_inputs({1001: [(0.1, True)]}))
    assert task.error is None
    assert system.console.output == "light curtain broken\nguard off after reaction\n"
    assert 0.1 / MAJOR_CYCLE - 1 <= system.globals["count"] <= 0.1 / MAJOR_CYCLE + 2


# ------------------------------------------------- conveyor monitor in task 1
CONVEYOR = """\
.PROGRAM main.cell()
\tGLOBAL parts.seen
\tparts.seen = 0
\tSIGNAL -2001, -2002\t; stop request and acknowledge off
\tSIGNAL 3001\t\t; cell busy
\tEXECUTE 1 conv.mon()\t; conveyor monitor
\tWAIT parts.seen >= 3
\tSIGNAL 2001\t\t; ask the monitor to stop
\tWAIT SIG(2002)\t\t; and wait for its answer
\tSIGNAL -3001
\tTYPE "main saw ", /I0, parts.seen, " parts, busy ", SIG(3001)
.END

.PROGRAM conv.mon()
\tlast = SIG(1003)
\tDO
\t    now = SIG(1003)
\t    IF now AND NOT last THEN\t; rising edge: a part passed
\t        parts.seen = parts.seen+1
\t        TYPE "part ", /I0, parts.seen
\t    END
\t    last = now
\t    WAIT
\tUNTIL SIG(2001)
\tSIGNAL 2002
.END
"""


def test_execute_conveyor_monitor_talks_through_globals_and_soft_signals():
    """EXECUTE task program() starts a second task ([000] "EXECUTE"); tasks share
    GLOBAL variables and the soft signals 2001-2512 and 3001-3004 ([000] L328-331,
    L11979-11980); WAIT expr waits until the expression is true ([000] L1437)."""
    pulses = [(t, True) for t in (0.1, 0.3, 0.5, 0.7)]
    edges = sorted(pulses + [(t + 0.05, False) for t, _ in pulses])
    system, task = run_vplus(CONVEYOR, each_cycle=drive_inputs({1003: edges}))
    assert task.error is None
    assert system.console.output == "part 1\npart 2\npart 3\nmain saw 3 parts, busy 0\n"
    assert system.io.sig(2002)


# ------------------------------------------------------------ error trapping
TRAPPED = """\
.PROGRAM safe.calc()
\tREACTE trap\t\t; every error goes to trap
\ta = 10
\tb = 0
\tc = a/b\t\t\t; divide by zero
\tTYPE "resumed, c defined: ", /I0, DEFINED(c)
\tx[3] = 1
\tk = -1
\tTYPE x[k]\t\t; bad index
\tTYPE "end"
.END

.PROGRAM trap()
\tTYPE "trapped: ", $ERROR(ERROR(-1))
\tRETURNE
.END
"""


def test_reacte_traps_each_error_and_returne_goes_on():
    """REACTE program: an error calls it; ERROR(-1) is the code, $ERROR(code) the
    text; RETURNE goes on at the step after the failed one ([000] L4562-4572)."""
    system, task = run_vplus(TRAPPED)
    assert task.error is None
    assert system.console.output == (
        "trapped: *Divide by zero*\n"
        "resumed, c defined: 0\n"
        "trapped: *Illegal array index*\n"
        "end\n"
    )


# -------------------------------------------------------------- report table
REPORT = """\
.PROGRAM shift.report()
; end-of-shift report: one line per part type, then the totals
\t$names[1] = "bolt"
\t$names[2] = "washer"
\t$names[3] = "nut"
\tqty[1] = 120
\tqty[2] = 8
\tqty[3] = 45
\twt[1] = 2.5\t; grams each
\twt[2] = 0.4
\twt[3] = 1.25
\tTYPE "PART", /X6, "QTY", /X4, "GRAMS"
\ttq = 0
\ttw = 0
\tFOR i = 1 TO 3
\t    $pad = $MID("          ", 1, 10-LEN($names[i]))
\t    TYPE $names[i], $pad, /S\t; no line end yet
\t    TYPE /I3, qty[i], /F9.2, wt[i]*qty[i]
\t    tq = tq+qty[i]
\t    tw = tw+wt[i]*qty[i]
\tEND
\tTYPE /C1, "TOTAL", /X5, /I3, tq, /F9.2, tw
\tTYPE "ratio ", /F4.1, 1234.5, " ", /I2, 999
.END
"""


def test_report_table_with_type_format_specifiers():
    """/Xn: n spaces, /S: no line end, /Cn: n line ends, /In: integer n wide,
    /Fn.m: fixed point; a number format holds for the numbers after it; a
    value too wide for its field is shown as asterisks ([000] "Output Format",
    V+ Language Reference "TYPE")."""
    assert output_of(REPORT) == (
        "PART      QTY    GRAMS\n"
        "bolt      120   300.00\n"
        "washer      8     3.20\n"
        "nut        45    56.25\n"
        "\n"
        "TOTAL     173   359.45\n"
        "ratio **** **\n"
    )


# ------------------------------------------------------------------ CALL chain
CHAIN = """\
.PROGRAM chain.main()
\tAUTO total
\tvals[0] = 4
\tvals[1] = 7
\tvals[2] = 1
\tcount = 3
\tCALL stats(vals[], count, total, biggest)
\tTYPE "sum ", /I0, total, " max ", biggest, " count ", count
\tCALL bump((count), count)\t; (count) goes by value
\tTYPE "count now ", /I0, count
.END

.PROGRAM stats(a[], n, sum, mx)
\tAUTO i
\tAUTO work[10]
\tsum = 0
\tmx = a[0]
\tFOR i = 0 TO n-1
\t    work[i] = a[i]*2
\t    CALL add.to(sum, a[i])
\t    IF a[i] > mx THEN
\t        mx = a[i]
\t    END
\tEND
\tn = work[1]\t\t; written back to the caller's count
.END

.PROGRAM add.to(acc, v)
\tacc = acc+v
.END

.PROGRAM bump(byval, byref)
\tbyval = byval+100
\tbyref = byref+1
.END
"""


def test_call_chain_with_reference_parameters_and_auto_arrays():
    """CALL passes variables by reference, a whole array as a[], an expression
    such as (x) by value ([000] "Argument Passing"); AUTO arrays are the
    program's own ([000] "AUTO")."""
    assert output_of(CHAIN) == "sum 12 max 7 count 14\ncount now 15\n"


# ------------------------------------------------------------------ disk log
DISK_LOG = """\
.PROGRAM log.cycle()
\tAUTO lun, i
\tATTACH (lun, 4) "DISK"
\tIF IOSTAT(lun) < 0 GOTO 90
\tFOPENW (lun) "cycle.log"
\tIF IOSTAT(lun) < 0 GOTO 90
\tFOR i = 1 TO 3
\t    WRITE (lun) "cycle ", /I0, i, " time ", /F4.2, i*0.25
\tEND
\tWRITE (lun) "done", /S
\tWRITE (lun) "!"
\tFCLOSE (lun)
\tFOPENR (lun) "cycle.log"
\tREAD (lun) $line
\tWHILE IOSTAT(lun) > 0 DO
\t    TYPE "> ", $line
\t    READ (lun) $line
\tEND
\terror = IOSTAT(lun)\t\t; -504 at the end of the file
\tTYPE $ERROR(error)
\tFCLOSE (lun)
\tDETACH (lun)
\tRETURN
90\tTYPE "disk error ", $ERROR(IOSTAT(lun))
.END
"""


def test_disk_log_written_and_read_back(tmp_path):
    """ATTACH (lun, 4) "DISK" picks a unit; WRITE appends CR LF unless /S;
    READ strips it; the end of the file is IOSTAT -504 ([000] "Disk I/O",
    L7699-7702, L7818-7830)."""
    out = output_of(DISK_LOG, sandbox=tmp_path)
    assert out == ("> cycle 1 time 0.25\n> cycle 2 time 0.50\n> cycle 3 time 0.75\n> done!\n"
                   "*Unexpected end of file*\n")
    assert (tmp_path / "cycle.log").read_bytes() == (
        b"cycle 1 time 0.25\r\ncycle 2 time 0.50\r\ncycle 3 time 0.75\r\ndone!\r\n")


# ------------------------------------------------------------- DO/UNTIL + SIG
HANDSHAKE = """\
.PROGRAM handshake()
\tSIGN 5\t\t\t; request part (SIGNAL abbreviated)
\tDO
\t    WAIT SIG(1005)\t; feeder ready?
\t    TYPE "ready at ", /F4.2, TIMER(1)
\t    SIGNAL -5
\t    WAIT SIG(-1005)
\t    n = n+1
\tUNTIL n >= 2
\tTYPE "handshakes ", /I0, n
.END

.REALS
n = 0
.END
"""


def test_do_until_with_wait_on_signals_and_a_reals_section():
    """DO ... UNTIL runs its body at least once ([000] "DO"); WAIT SIG(n) holds
    the task until the input is on; an instruction keyword may be abbreviated
    to a unique beginning ([000] L2583); a .REALS section in the same file
    defines n ([000] "Storing data in files")."""
    edges = {1005: [(0.2, True), (0.3, False), (0.5, True), (0.6, False)]}
    system, task = run_vplus(HANDSHAKE, setup=lambda s: s.io.set(1005, False), each_cycle=drive_inputs(edges))
    assert task.error is None
    lines = system.console.output.splitlines()
    assert lines[-1] == "handshakes 2"
    assert len(lines) == 3 and all(line.startswith("ready at ") for line in lines[:2])
    first, second = (float(line.split()[-1]) for line in lines[:2])
    assert 0.2 <= first <= 0.2 + 2 * MAJOR_CYCLE and 0.5 <= second <= 0.5 + 2 * MAJOR_CYCLE


# ------------------------------------------------------------- data sections
DATA = """\
.PROGRAM Use.Data()\t; the data sections below load with the program
\tTYPE $greeting, " ", /F5.1, speed.fac*2, " ", /I0, DX(home)
\tFOR i = 0 TO 2
\t    TYPE /I0, bins[i], /S
\t    TYPE " ", /S
\tEND
\tTYPE ""
.END

.REALS
speed.fac = 12.5
bins[0] = 3
bins[1] = 1
bins[2] = 4
.END

.STRINGS
$greeting = "hello"
.END

.LOCATIONS
home  250 0 300 0 180 0
.END"""


def test_reals_strings_and_locations_sections_in_the_program_file():
    """A program file may carry .REALS, .STRINGS and .LOCATIONS sections after
    its programs ([000] "Storing Data", LOAD); the file may end without a
    newline after the last .END."""
    assert output_of(DATA) == "hello  25.0 250\n3 1 4 \n"


# --------------------------------------------------------------- GETC in IF
GETC_IN_IF = """\
.PROGRAM key.menu()
\tAUTO sl
\tATTACH (sl, 4) "SERIAL:1"\t; the operator panel's line
\tDO
\t    IF GETC(sl) == ASC("y") THEN\t; waits for a byte
\t        TYPE "yes at ", /F4.2, TIMER(1)
\t    ELSE
\t        TYPE "no"
\t    END
\tUNTIL GETC(sl) == ASC("q")
\tCASE GETC(sl) OF
\t  VALUE ASC("!"):
\t    TYPE "bang at ", /F4.2, TIMER(1)
\tEND
\tDETACH (sl)
.END
"""


def test_getc_in_if_until_and_case_conditions_waits_for_the_byte():
    """GETC(lun) without the no-wait mode waits for a byte ([000] L7498-7530,
    L8082): in the condition of an IF, an UNTIL or a CASE as in any step."""
    bytes_at = [(0.1, b"y"), (0.2, b"x"), (0.3, b"n"), (0.4, b"q"), (0.5, b"!")]

    def each_cycle(system):
        while bytes_at and system.clock() >= bytes_at[0][0]:
            system.devices.serial(1).feed(bytes_at.pop(0)[1])

    system, task = run_vplus(GETC_IN_IF, each_cycle=each_cycle)
    assert task.error is None
    yes, no, bang = system.console.output.splitlines()
    assert no == "no"
    assert 0.1 <= float(yes.split()[-1]) <= 0.1 + 2 * MAJOR_CYCLE
    assert 0.5 <= float(bang.split()[-1]) <= 0.5 + 2 * MAJOR_CYCLE


# -------------------------------------------------------------- multi PROMPT
def test_prompt_with_several_real_variables():
    """PROMPT "text", x, y, z: the numbers typed, separated by commas or spaces
    (docs/vplus.md, PROMPT); one string variable takes the whole line
    ([000] L7119-7130)."""
    text = """\
.PROGRAM ask()
\tPROMPT "offset x y z? ", dx, dy, dz
\tTYPE /F6.1, dx, dy, dz
\tPROMPT "name? ", $who
\tTYPE "hi ", $who
.END
"""
    assert output_of(text, stdin="1.5, -2 30\nop 7\n") == "offset x y z?    1.5  -2.0  30.0\nname? hi op 7\n"
    system, task = run_vplus(text, stdin="1 2 3 4\nx\n")
    assert task.error.code == msg.UNEXPECTED_TEXT and task.error.line == 2


# ------------------------------------------------------------ malformed programs
def program(body: str) -> str:
    return f".PROGRAM bad()\n\tx = 1\n{body}\n.END\n"


# (body, code, line): the step the error names; line 3 is the body's first line.
MALFORMED = [
    ("IF x == 1 THEN", msg.CONTROL_STRUCTURE, None),  # no END
    ("END", msg.CONTROL_STRUCTURE, 3),
    ("FOR i = 1 TO\nEND", msg.SYNTAX_ERROR, 3),
    ("WHILE x DO\nELSE\nEND", msg.CONTROL_STRUCTURE, 4),
    ("DO\nEND", msg.CONTROL_STRUCTURE, None),
    ("CASE x OF\nVALUE 1:\nTYPE 1\nUNTIL x", msg.CONTROL_STRUCTURE, None),
    ("GOTO 50", msg.UNDEFINED_LABEL, 3),
    ("10 x = 2\n10 x = 3", msg.CONTROL_STRUCTURE, 4),
    ("x = (1 + 2", msg.SYNTAX_ERROR, 3),
    ("x = 1 +* 2", msg.SYNTAX_ERROR, 3),
    ('$s = "abc', msg.SYNTAX_ERROR, 3),
    ("x = ^B123", msg.SYNTAX_ERROR, 3),
    ("FROBNICATE 3", msg.UNKNOWN_KEYWORD, 3),
    ("pi = 3", msg.SYNTAX_ERROR, 3),
    ("AUTO late", msg.SYNTAX_ERROR, 3),
    ('$s = 5', msg.WRONG_TYPE, 3),
    ("EXIT", msg.CONTROL_STRUCTURE, 3),
    ("x = 1/0", msg.DIVIDE_BY_ZERO, 3),
    ("y = nothing.here + 1", msg.UNDEFINED_VALUE, 3),
    ("a[-1] = 2", msg.ILLEGAL_ARRAY_INDEX, 3),
    ("SIGNAL 600", msg.ILLEGAL_SIGNAL, 3),
    ("CALL no.such.prog()", msg.UNDEFINED_PROGRAM, 3),
    ("TYPE SQRT(-1)", msg.ILLEGAL_VALUE, 3),
    ("x = NOSUCHFN(3)", msg.UNDEFINED_PROGRAM, 3),
    ("TYPE $MID(5, 1, 1)", msg.WRONG_TYPE, 3),
    ("FOR i = 1 TO 3 STEP 0\nEND", msg.ILLEGAL_VALUE, 3),
    ("EXIT 0", msg.INVALID_ARGUMENT, 3),
    ("x = 1e40", msg.OVERFLOW, 3),
    ("PROMPT \"a\", $a, b", msg.WRONG_TYPE, 3),
    ("MOVE", msg.INVALID_ARGUMENT, 3),
    ("REACT 5, handler", msg.ILLEGAL_SIGNAL, 3),
    ("WAIT.EVENT 1, 2, 3", msg.INVALID_ARGUMENT, 3),
    ("VALUE 3:", msg.CONTROL_STRUCTURE, 3),
    ("x = = 2", msg.SYNTAX_ERROR, 3),
    ("TYPE /Q", msg.SYNTAX_ERROR, 3),
    ('IF $x THEN\nEND', msg.WRONG_TYPE, 3),
    ('WHILE NOT "a" DO\nEND', msg.WRONG_TYPE, 3),
    ('x = "a" + 1', msg.WRONG_TYPE, 3),
    ("TYPE HERE", msg.DEVICE_NOT_READY, 3),  # the interpreter alone has no robot
    ("DURATION 1 ALWAYS", msg.DEVICE_NOT_READY, 3),
    ("SIGNAL 1, 2, 3004, -3005", msg.ILLEGAL_SIGNAL, 3),
    ("CALL bad(1)", msg.INVALID_ARGUMENT, 3),
    ("timer = TIMER(1)", msg.INVALID_ARGUMENT, 3),
    ("DELAY 1 ALWAYS", msg.INVALID_ARGUMENT, 3),  # TIMER n = value: the instruction
    ("x = " + "+".join(["1"] * 600), msg.SYNTAX_ERROR, 3),  # too long for the compiler's recursion
    ("x = " + "NOT " * 300 + "1", msg.SYNTAX_ERROR, 3),  # too deep for Python's parser
]


def failure(text: str) -> ProgramError:
    """The error a program gives, at load time or when it runs."""
    try:
        system, task = run_vplus(text)
    except ProgramError as error:
        return error
    assert task.error is not None, "the program ran without an error"
    return task.error


@pytest.mark.parametrize("body, code, line", MALFORMED)
def test_a_malformed_program_gives_a_located_v_plus_error(body, code, line):
    """Every mistake is reported as the controller would: its message in
    asterisks, the file, the line and (for a step) its text; never a Python
    traceback."""
    text = program(body)
    error = failure(text)
    assert isinstance(error, ProgramError)
    assert error.message.startswith("*"), error
    assert error.file == "test.pg" and error.line is not None and error.column is not None, error
    if code is not None:
        assert error.code == code, error
    if line is not None:
        assert error.line == line, error
        assert error.text is not None and error.text.strip() == text.splitlines()[line - 1].strip(), error


BROKEN_FILES = [
    ".PROGRAM a(\n.END\n",
    ".PROGRAM a()\nTYPE 1\n",  # no .END
    ".PROGRAM 3x()\n.END\n",
    "TYPE 1\n",  # a step outside any program
    ".PROGRAM a()\n.END\n.PROGRAM a()\n.END\n",  # the same program twice
    ".REALS\nx = \n.END\n",
    ".LOCATIONS\nhome 1 2\n.END\n",
    ".PROGRAM a(b, b)\n.END\n",
    ".PROGRAM a()\nCALL a(1)\n.END\n",
]


@pytest.mark.parametrize("text", BROKEN_FILES)
def test_a_broken_file_is_a_program_error_not_a_python_exception(text):
    """The whole-file mistakes: each one a ProgramError naming the file and a line."""
    with pytest.raises(ProgramError) as info:
        system, task = run_vplus(text)
        if task.error is not None:
            raise task.error
    assert info.value.message.startswith("*") and info.value.file == "test.pg", info.value


# ------------------------------------------------ on the cell: DURATION, #PHERE
def test_duration_always_and_precision_point_here_and_dest_on_the_cell():
    """DURATION t ALWAYS sets the least time of every motion until changed
    ([000] "Motion Modifiers", L6646-6650); #PHERE and #PDEST are HERE and DEST
    as precision points: the joint values now and at the last destination
    ([000] "Precision Points", L5944-5946)."""
    from test_motion_controller import A, B, run_on_cell

    text = """\
.PROGRAM timed()
\tDURATION 1.5 ALWAYS
\tMOVE a
\tMOVE b
\tSET #goal = #PDEST\t; while the robot is still on its way
\tBREAK
\tSET #now = #PHERE
.END
"""
    sim, task, outcome, _ = run_on_cell(text, locations={"a": A, "b": B})
    assert outcome.errors == []
    assert [m.duration_s for m in sim.controller.history] == pytest.approx([1.5, 1.5])
    controller = sim.controller
    assert task.globals["#goal"] == controller.to_user_joints(controller.destination_joints())
    # BREAK waits until the joints settle (FINE): #PHERE is then at the goal.
    assert task.globals["#now"] == pytest.approx(task.globals["#goal"], abs=0.05)
    assert controller.location_of_joints(task.globals["#goal"]).position() == pytest.approx(B.position(), abs=1e-3)


def test_select_robot_in_a_one_robot_cell():
    """SELECT ROBOT = n picks the robot a task drives, SELECT(ROBOT) tells which
    ([000] L5539, L7020-7023); the cell has one robot: unit 1."""
    text = ".PROGRAM pick.robot()\n\tSELECT ROBOT = 1\t; the only arm\n\tTYPE \"robot \", SELECT(ROBOT)\n.END"
    assert output_of(text) == "robot 1\n"
    assert failure(text.replace("= 1", "= 2")).code == msg.ILLEGAL_VALUE
    assert failure(text.replace("SELECT(ROBOT)", "SELECT(VISION)")).code == msg.DEVICE_NOT_READY


# --------------------------------------------- arithmetic, loops, LOCAL state
CALC = """\
.PROGRAM calc()
\tTYPE 1/3, " ", -2.5, " ", 1E6, " ", 123456789\t; reals are singles
\tTYPE SIN(30), " ", COS(60), " ", ATAN2(1, 1), " ", SQRT(2)\t; degrees
\tTYPE INT(-2.7), " ", ABS(-3), " ", MAX(1, 5, 3), " ", MIN(4, -2), " ", 7 MOD 3
\tTYPE ^HFF, " ", ^B101, " ", ^17, " ", 'A, " ", .5, " ", 1.
\tTYPE 5 BAND 3, " ", 5 BOR 3, " ", 5 BXOR 3, " ", COM 0, " ", NOT 0
\tTYPE 1 < 2 AND 2 < 3, " ", 1 == 1 OR 0, " ", 3 > 2 > 1
\tFOR i = 10 TO 1 STEP -3\t; counting down
\t    TYPE i, " ", /S
\tEND
\tTYPE
\tFOR i = 1 TO 3
\t    FOR j = 1 TO 3
\t        IF i*j == 4 GOTO 50\t; out of both loops
\t    END
\tEND
50\tTYPE "out at ", i, ",", j
\tm[1,2] = 12
\tm[2,1] = 21
\tTYPE m[1,2]+m[2,1]
\tCALL cnt()
\tCALL cnt()
\t$a = "Hello"
\tTYPE $a+" "+$CHR(87)+"orld", " ", LEN($a), " ", $a == "HELLO", " ", $ENCODE(/F6.2, PI)
.END

.PROGRAM cnt()
\tLOCAL n\t\t; kept between calls
\tIF NOT DEFINED(n) THEN
\t    n = 0
\tEND
\tn = n+1
\tTYPE "calls ", n
.END
"""


def test_arithmetic_radix_constants_loops_and_local_state():
    """Single-precision reals exact to 16,777,216 ([000] L3868-3895); SIN and
    COS take degrees; ^H ^B ^ (octal) and 'c constants ([000] L3895-3910);
    AND and OR bind tighter than the comparisons, which go left to right
    ([000] L4324-4345); TRUE is -1; FOR with a negative STEP; a GOTO out of
    nested loops; LOCAL variables keep their values between calls; string
    comparison ignores case while UPPER is on ([000] L4315-4321)."""
    assert output_of(CALC) == (
        "0.3333333 -2.5 1000000 123456792\n"
        "0.5 0.5 45 1.414214\n"
        "-2 3 5 -2 1\n"
        "255 5 15 65 0.5 1\n"
        "1 7 6 -1 -1\n"
        "-1 0 0\n"
        "10 7 4 1 \n"
        "out at 2,2\n"
        "33\n"
        "calls 1\ncalls 2\n"
        "Hello World 5 -1   3.14\n"
    )


def test_palletizing_on_the_cell_visits_every_place_with_straight_approaches():
    """The grid of the first program, driven on the SCARA cell: APPRO p, 30 and
    DEPARTS 30 move along the tool's z, which points down (pitch 180), so the
    robot ends 30 mm above the last place ([000] "APPRO, DEPART", "SHIFT")."""
    from test_motion_controller import run_on_cell

    text = """\
.PROGRAM pal.cell()
\tSPEED 50 ALWAYS
\tSET corner = TRANS(300, -100, 200, 0, 180, 180)
\tFOR r = 0 TO 1
\t    FOR c = 0 TO 1
\t        SET p = SHIFT(corner BY c*60, r*60, 0)
\t        APPRO p, 30
\t        MOVES p
\t        DEPARTS 30
\t    END
\tEND
\tBREAK
\tTYPE "at ", /F6.1, DX(HERE), DY(HERE), DZ(HERE)
.END
"""
    sim, task, outcome, _ = run_on_cell(text)
    assert outcome.errors == []
    assert task.system.console.output == "at  360.0 -40.0 230.0\n"
    stops = [(m.straight, tuple(round(v, 3) for v in m.destination.position())) for m in sim.controller.history]
    places = [(300.0 + 60 * c, -100.0 + 60 * r) for r in range(2) for c in range(2)]
    assert stops == [(straight, (x, y, z)) for x, y in places
                     for straight, z in ((False, 230.0), (True, 200.0), (True, 230.0))]


@pytest.mark.parametrize("text, detail", [
    (program("x = (1 + 2"), "unexpected end of line"),
    (".PROGRAM a()\nTYPE 1\n", "unexpected end of file"),
    (program("x = 1 +* 2"), "unexpected '* 2'"),
])
def test_a_syntax_error_names_what_the_parser_met(text, detail):
    """The message says what was found where the line went wrong."""
    assert detail in failure(text).message


def test_parentheses_of_an_empty_argument_list_may_be_left_out():
    """.PROGRAM name(parameter_list): "the parameter list ... optional" ([000]
    L853-855); CALL and EXECUTE of a program without arguments likewise."""
    text = """\
.PROGRAM main\t; no parameter list
\ttask.no = 2
\tEXECUTE task.no worker
\tEXECUTE 3 worker, 1
\tCALL tell
\tWAIT TASK(1, 2) == 0 AND TASK(1, 3) == 0
.END
.PROGRAM worker
\tTYPE "worker in task ", TASK()
.END
.PROGRAM tell()
\tTYPE "told"
.END"""
    out = output_of(text)
    assert sorted(out.splitlines()) == ["told", "worker in task 2", "worker in task 3"]


def test_loops_nested_deeper_than_python_allows_still_run():
    """Python nests at most 20 loop and try blocks; a V+ program may nest its
    loops deeper: such a program is compiled to one flat jump table."""
    depth = 24
    loops = "FOR i0 = 1 TO 3\n" + "".join(f"FOR i{k} = 1 TO 1\n" for k in range(1, depth))
    text = f".PROGRAM deep()\nn = 0\n{loops}IF i0 <> 2 THEN\nn = n + i0\nEND\n" + "END\n" * depth
    assert output_of(text + "TYPE n\n.END\n") == "4\n"


def test_a_compile_error_inside_a_goto_program_is_located():
    """A program with GOTO is lowered to jumps; its load errors still name the step."""
    error = failure(program('10 IF $x THEN\nGOTO 10\nEND'))
    assert error.code == msg.WRONG_TYPE and error.line == 3


def mutants(count: int, seed: int = 3):
    """The programs above with a few random cuts and insertions of V+ words
    and punctuation: what a slip of the keyboard makes of them."""
    rng = random.Random(seed)
    sources = [PALLET, STATES, BARCODE, GUARD, CONVEYOR, TRAPPED, REPORT, CHAIN, HANDSHAKE, DATA, CALC]
    words = ["(", ")", ",", "=", "[", "]", '"', "$", "#", ":", ";", "END", "IF", "THEN", "ELSE", "GOTO",
             "10", "-", "/", "^H", "'", "VALUE", "DO", "UNTIL", "CALL", "TYPE", "/I", "/F9.", ".END",
             ".PROGRAM x()", "\n", "NOT", "AND", "1E99", "0", "SET", "AUTO a[", "WAIT", "REACT", "EXECUTE",
             "READ (", "$MID(", "TIMER(", "FOR", "TO", "STEP", "CASE", "OF", "ANY", "ALWAYS", "PROMPT", "error"]
    for _ in range(count):
        text = list(rng.choice(sources))
        for _ in range(rng.randint(1, 3)):
            at = rng.randrange(len(text))
            if rng.random() < 0.4:
                del text[at:at + rng.randint(1, 6)]
            else:
                text[at:at] = list(f" {rng.choice(words)} ")
        yield "".join(text)


def test_mistyped_programs_never_raise_a_python_exception():
    """200 mangled programs: each loads and runs, or stops with a located V+
    error; none escapes as another Python exception."""
    for text in mutants(200):
        try:
            system, task = run_vplus(text, max_cycles=40, stdin="1\n")
        except ProgramError as error:
            assert error.file == "test.pg" and error.line is not None and error.message.startswith("*"), error
            continue
        for each in [task, *system.tasks]:
            if each.error is not None:
                assert isinstance(each.error, ProgramError) and each.error.line is not None, each.error
