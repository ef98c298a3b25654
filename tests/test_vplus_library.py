"""The V+ function and instruction library (issue #3): strings, numbers,
locations, switches and parameters, digital I/O, TYPE formats, errors, and
logical-unit I/O on the sandbox disk, serial lines and absent devices.

[000] is the V+ Language User's Guide v17, [001] the eV+ Language User's Guide
(../shared/seeds/); line numbers cite them.
"""

from __future__ import annotations

import math

import pytest

from twin.controller.scheduler import Scheduler
from twin.errors import ProgramError
from twin.language.vplus import messages as msg
from twin.language.vplus.runtime import MAJOR_CYCLE

from vplus_helpers import output_of, run_vplus


def program(body: str, name: str = "t") -> str:
    return f".PROGRAM {name}()\n{body}\n.END\n"


def run_ok(body: str, **kw):
    system, task = run_vplus(program(body), **kw)
    if task.error is not None:
        raise task.error
    return system


def v_plus(system):
    """setup= for a run under the V+ v17 rules where the guides differ."""
    system.dialect = "V+"


def error_of(body: str, **kw) -> ProgramError:
    """The error the program stops with, at load time or when it runs."""
    try:
        _system, task = run_vplus(program(body), **kw)
    except ProgramError as err:
        return err
    assert task.error is not None, "the program should have stopped with an error"
    return task.error


# ------------------------------------------------------------------ strings
def test_string_functions():
    # [000] "String-Related Functions" table: LEN, POS, $MID, ASC, $CHR, VAL.
    out = output_of(program(
        'TYPE LEN("hello"), " ", POS("hello", "l"), " ", POS("hello", "l", 4), " ", POS("hello", "z")\n'
        'TYPE $MID("abcdef", 2, 3), " ", ASC("ABC", 2), " ", ASC("A"), " ", ASC("", 1)\n'
        'TYPE VAL("  12.5abc"), " ", VAL("x"), " ", VAL("-3E2")\n'
        'TYPE $TRUNCATE("ab"+$CHR(0)+"cd"), LEN($CHR(0))'))
    assert out == "5 3 4 0\nbcd 66 65 -1\n12.5 0 -300\nab1\n"


# (body, output): string functions that write back or work on packed strings.
STRING_CASES = {
    # $DECODE($var, $breaks, mode): mode 0 the text up to a break, mode 1 the breaks.
    "decode takes a token and removes it from the variable": (
        '$s = "12, 34"\n'
        '$a = $DECODE($s, ", ", 0)\n$b = $DECODE($s, ", ", 1)\n$c = $DECODE($s, ", ", 0)\n'
        'TYPE $a, "|", $b, "|", $c, "|", $s, "|"',
        "12|, |34||\n"),
    "decode writes back into auto and array variables": (
        'AUTO $line\n$line = "a;b"\n$t[2] = "x y"\n'
        'TYPE $DECODE($line, ";", 0), $line, " ", $DECODE($t[2], " ", 0), $t[2]',
        "a;b x y\n"),
    "pack and unpack": (
        '$buf[0] = "abcdef"\nPACK $buf[0], 3, 2 = "XYZ"\nPACK $buf[1], 2, 3 = "q"\n'
        'TYPE $buf[0], "|", $buf[1], "|", $UNPACK($buf[0], 2, 3)',
        "abXYef| q  |bXY\n"),
    "binary conversions round trip big endian": (
        'TYPE INTB($INTB(-2)), " ", LNGB($LNGB(^D123456789)), " ", FLTB($FLTB(1.5)), " ", DBLB($DBLB(0.1))\n'
        'TYPE ASC($INTB(258), 1), " ", ASC($INTB(258), 2), " ", LEN($DBLB(1)), " ", INTB("xx"+$INTB(7), 3)\n'
        'SET loc = TRANS(10, 20, 30, 0, 180, 45)\n'
        'TYPE LEN($TRANSB(loc)), " ", IDENTICAL(TRANSB($TRANSB(loc)), loc)',
        "-2 123456789 1.5 0.1\n1 2 8 7\n48 -1\n"),
}


@pytest.mark.parametrize("body, output", STRING_CASES.values(), ids=STRING_CASES)
def test_string_functions_that_write_back_or_pack(body, output):
    assert output_of(program(body)) == output


def test_pack_and_unpack_span_128_character_elements():
    # A string array is read as consecutive 128-character strings.
    system = run_ok('PACK $a[3], 127, 4 = "wxyz"\n$s = $UNPACK($a[3], 126, 6)\n$t = $UNPACK($a[4], 1, 2)')
    a = system.globals["$a[]"]
    assert a[3] == " " * 126 + "wx" and a[4] == "yz"
    assert system.globals["$s"] == " wxyz " and system.globals["$t"] == "yz"


def test_encode_uses_the_type_formats_and_string_length_is_limited():
    # [000] L5359-5367: $ENCODE with /I0.
    out = output_of(program('$m = "The length of this line is: "\n'
                            'TYPE $ENCODE($m, /I0, LEN($m)+14), " characters."'))
    assert out == "The length of this line is: 42 characters.\n"
    err = error_of('$s = $ENCODE(/X129)')
    assert err.code == msg.STRING_TOO_LONG


# ------------------------------------------------------------------ numbers
def test_numeric_functions():
    # [000] L3925-3929: x = 3, 6/2, SQRT(9), SQR(2)-1, 9 MOD 6 all give 3.
    out = output_of(program('TYPE SQRT(9), SQR(2)-1, 9 MOD 6, 6/2\n'
                            'TYPE BCD(1234), " ", DCB(^H1234), " ", CUBRT(-27), " ", ABS(-2.5), " ", SIGN(-4)\n'
                            'TYPE OUTSIDE(1, 5, 10), " ", OUTSIDE(1, 11, 10), " ", MAX(1, 7, 3), " ", MIN(4, -2)\n'
                            'TYPE INT(-2.7), " ", FRACT(2.25), " ", ATAN2(1, 1), " ", COS(60), " ", PI'))
    assert out == "3333\n4660 1234 -3 2.5 -1\n0 -1 7 -2\n-2 0.25 45 0.5 3.141593\n"


def test_random_gives_integers_0_to_9():
    # [000] L5464-5471: x = INT(RANDOM*10).
    system = run_ok("FOR i = 0 TO 199\nr[i] = INT(RANDOM*10)\nEND")
    values = set(system.globals["r[]"].values())
    assert values <= set(range(10)) and len(values) == 10


def test_bcd_of_a_non_bcd_value_is_an_error():
    assert error_of("x = DCB(^HA1)").code == msg.ILLEGAL_VALUE


# ---------------------------------------------------------------- locations
def test_frame_builds_the_pallet_frame():
    # [000] L6200-6231: FRAME(origin, point on x, point on +y, origin).
    system = run_ok("SET o = TRANS(100, 100, 0)\nSET px = TRANS(100, 200, 0)\nSET py = TRANS(0, 150, 0)\n"
                    "SET f = FRAME(o, px, py, o)\nSET cell = f:TRANS(50, 100)")
    cell = system.globals["cell"]
    assert (round(cell.x, 6), round(cell.y, 6), round(cell.z, 6)) == (0.0, 150.0, 0.0)


def test_scale_decompose_identical_normal():
    system = run_ok("SET a = SCALE(TRANS(1, 2, 3, 0, 90, 0) BY 2)\nDECOMPOSE parts[] = a\n"
                    "DECOMPOSE more[10] = TRANS(7)\n"
                    "same = IDENTICAL(NORMAL(a), a)\ndiff = IDENTICAL(a, TRANS(2, 4, 6))")
    parts = system.globals["parts[]"]
    assert [round(parts[i], 6) for i in range(6)] == [2, 4, 6, 0, 90, 0]
    assert system.globals["more[]"][10] == 7.0 and 9 not in system.globals["more[]"]
    assert system.globals["same"] == -1.0 and system.globals["diff"] == 0.0


def test_relative_transformations_as_the_guide_computes_them():
    # [000] L6134-6183: loc_a:TRANS(-50, 20, 30) is (350, 70, 320, 0, 180, 0).
    system = run_ok("SET loc_a = TRANS(300, 50, 350, 0, 180, 0)\nSET loc_c = loc_a:TRANS(-50, 20, 30)\n"
                    "SET back = loc_c:INVERSE(TRANS(-50, 20, 30))")
    c, back = system.globals["loc_c"], system.globals["back"]
    assert [round(v, 6) for v in c.components()] == [350, 70, 320, 0, 180, 0]
    assert [round(v, 6) for v in back.components()] == [300, 50, 350, 0, 180, 0]


# --------------------------------------------------- switches and parameters
def test_switch_and_parameter_defaults_are_the_manuals():
    # [000] "System Switches"/"System Parameters": CP, UPPER, MESSAGES on; DRY.RUN, TRACE off.
    out = output_of(program('TYPE SWITCH(CP), SWITCH(UPPER), SWITCH(MESSAGES), SWITCH(DRY.RUN), SWITCH(TRACE)\n'
                            'TYPE PARAMETER(HAND.TIME), " ", PARAMETER(TERMINAL), " ", PARAMETER(KERMIT.RETRY)'))
    assert out == "-1-1-100\n0.05 4 15\n"


def test_parameter_instruction_and_function():
    # [000] L5621-5644 / [001] L2033-2059.
    out = output_of(program('TYPE "HAND.TIME parameter =", PARAMETER(HAND.TIME)\n'
                            'PARAMETER HAND.TIME = PARAMETER(HAND.TIME) + 0.15\nTYPE PARAMETER(H)\n'
                            'PARAMETER HAND.TIME = 0.5\nTYPE PARAMETER(HAND.TIME)'))
    assert out == "HAND.TIME parameter =0.05\n0.2\n0.5\n"
    assert error_of("PARAMETER TERMINAL = 9").code == msg.ILLEGAL_VALUE


def test_switch_instruction_enable_disable():
    # [000] L5792-5810: ENABLE BELT; DISABLE BELT, CP; SWITCH CP = SIG(1001).
    def input_on(system):
        system.io.set(1001, True)

    out = output_of(program('ENABLE BELT\nTYPE SWITCH(BELT)\nDISABLE BELT, CP\nTYPE SWITCH(BELT), SWITCH(CP)\n'
                            'SWITCH CP = SIG(1001)\nTYPE SWITCH(CP)\nSWITCH UPPER = FALSE\nTYPE "a" == "A"'),
                    setup=input_on)
    assert out == "-1\n00\n-1\n0\n"


# -------------------------------------------------------------- digital I/O
def test_signal_sig_bits_reset_sig_ins():
    # [000] L7254-7295: SIGNAL(33), (-34), (35); SIG with negative numbers.
    system = run_ok("SIGNAL(33), (-34), (35)\nSIGNAL 2010\na = SIG(33, -34, 35)\nb = SIG(34)\n"
                    "BITS 1, 8 = ^B10100101\nc = BITS(1, 8)\nd = BITS(3, 2)\ne = SIG.INS(33)\nf = SIG.INS(600)\n"
                    "RESET\ng = SIG(33) OR SIG(1) OR BITS(1, 8)\nh = SIG(2010)")
    g = system.globals
    assert (g["a"], g["b"], g["c"], g["d"], g["e"], g["f"]) == (-1.0, 0.0, 165.0, 1.0, -1.0, 0.0)
    assert g["g"] == 0.0 and g["h"] == -1.0  # RESET turns outputs off, not soft signals


def test_setting_an_input_is_an_illegal_signal():
    assert error_of("SIGNAL 1001").code == msg.ILLEGAL_SIGNAL
    assert error_of("BITS 1001, 2 = 3").code == msg.ILLEGAL_SIGNAL


# ------------------------------------------------------------------- timers
def test_timer_counts_simulated_seconds_from_when_it_was_set():
    system = run_ok("TIMER 1 = 0\nWAIT TIMER(1) >= 0.5\nt = TIMER(1)\n$now = $TIME()\nticks = TPS")
    assert 0.5 <= system.globals["t"] < 0.5 + MAJOR_CYCLE + 1e-9
    assert system.globals["$now"] == "01-JAN-00 00:00:00"
    assert system.globals["ticks"] == 1000.0


# ------------------------------------------------------------ TYPE / PROMPT
@pytest.mark.parametrize("items, text", [
    ("/I5, 42", "   42"), ("/I0, -7.6", "-8"), ("/I0, 2.5", "3"), ("/F8.3, 3.14159", "   3.142"), ("/F0.1, 2.25", "2.2"),
    ("/E10.2, 1234.5", "  1.23E+03"), ("/G8.3, 0.5", "     0.5"), ("/H4, 255", "  FF"), ("/O4, 8", "  10"),
    ("/D, 2.5", "2.5"), ("/I2, 123", "**"), ("/X3, \"a\"", "   a"), ("/B", "\a"), ("/U2", "\x1bM\x1bM"),
    ("/C2, \"a\"", "\n\na"), ("/I3, 1, 2", "  1  2"), ("\"a\", /N", "a"),
])
def test_type_format_specifiers(items, text):
    assert output_of(program(f"TYPE {items}")) == text + "\n"


def test_type_s_suppresses_the_line_end_and_bare_type_prints_a_blank_line():
    assert output_of(program('TYPE "a", /S\nTYPE "b"\nTYPE')) == "ab\n\n"


def test_messages_switch_off_silences_type():
    assert output_of(program('DISABLE MESSAGES\nTYPE "hidden"\nENABLE MESSAGES\nTYPE "shown"')) == "shown\n"


def test_prompt_reads_numbers_and_strings():
    # [000] L7119-7139: PROMPT prints without a line end and waits for a line.
    out = output_of(program('PROMPT "x? ", x\nPROMPT "s? ", $s\nTYPE x * 2, " ", $s'), stdin="21\nhello there\n")
    assert out == "x? s? 42 hello there\n"


def test_prompt_into_a_real_rejects_letters_and_end_of_input_stops():
    # [000] L7119-7130: a wrong type "generates an error message and halts execution";
    # the messages are those [000] L10362-10368 prints for "++97" and "11+1".
    assert error_of('PROMPT "x? ", x', stdin="abc\n").code == msg.INVALID_NUMBER
    assert error_of('PROMPT "x? ", x', stdin="++97\n").code == msg.INVALID_NUMBER
    assert error_of('PROMPT "x? ", x', stdin="11+1\n").code == msg.UNEXPECTED_TEXT
    assert error_of('PROMPT "x? ", x', stdin="nan\n").code == msg.INVALID_NUMBER
    assert output_of(program('PROMPT "", x\nTYPE x'), stdin=" -1.5E2 \n") == "-150\n"
    assert error_of('PROMPT "x? ", x', stdin="").code == msg.UNEXPECTED_EOF


# ------------------------------------------------------------------- errors
def test_error_text_and_codes():
    # [000] L5359: TYPE $ERROR(-504) prints *Unexpected end of file*.
    out = output_of(program("TYPE $ERROR(-504)\nTYPE $ERROR(-526)\nTYPE ERROR(-1)"))
    assert out == "*Unexpected end of file*\n*No data received*\n0\n"


def test_error_function_reports_the_last_error_of_a_task():
    system, task = run_vplus(program("x = undefined.var + 1"))
    assert task.error.code == msg.UNDEFINED_VALUE
    checker = system.load_text(program("code = ERROR(0)", name="check"))[0]
    other = system.start(checker, number=1)
    scheduler = Scheduler()
    scheduler.add(other)
    while scheduler.alive:
        scheduler.run_cycle()
    assert system.globals["code"] == msg.UNDEFINED_VALUE


def test_tas_returns_the_old_value_and_sets_the_new_one():
    out = output_of(program("AUTO lock\nlock = 0\nTYPE TAS(lock, 1), TAS(lock, 1), lock"))
    assert out == "011\n"


# --------------------------------------------------------------- disk files
def test_disk_writes_append_and_random_access_records(tmp_path):
    # [000] "Disk I/O": FOPENA appends (and names are case-insensitive); /S joins
    # WRITEs into one record; fixed-length records are zero-padded or cut, and a
    # random-access WRITE puts record n at byte 1 + (n - 1) * length.
    run_ok('ATTACH (d, 4) "DISK"\nFOPENA (d) "log.txt"\nWRITE (d) "one"\nFCLOSE (d)\n'
           'FOPENA (d) "LOG.TXT"\nWRITE (d) "two", /S\nWRITE (d) "three"\nFCLOSE (d)\n'
           'FOPENW (d, 4, 1) "C:\\recs\\fixed.dat"\nWRITE (d, 3) "cc"\nWRITE (d, 1) "aaaaaa"\nDETACH (d)',
           sandbox=tmp_path)
    assert (tmp_path / "log.txt").read_bytes() == b"one\r\ntwothree\r\n"
    assert (tmp_path / "C" / "recs" / "fixed.dat").read_bytes() == b"aaaa\0\0\0\0cc\0\0"


def test_disk_reads_fixed_records_and_directory_entries(tmp_path):
    (tmp_path / "data.txt").write_bytes(b"abc\r\nlast")
    (tmp_path / "fixed.dat").write_bytes(b"aaaa\0\0\0\0cc\0\0")
    system = run_ok('ATTACH (d, 4) "DISK"\nFOPENR (d, 4, 1) "fixed.dat"\nREAD (d, 3) $r3\nREAD (d, 1) $r1\n'
                    'n = IOSTAT(d, 2)\nFCLOSE (d)\nFOPEND (d) "*.*"\nREAD (d) $e1\nREAD (d) $e2\nREAD (d) $e3\n'
                    's3 = IOSTAT(d)\nFCLOSE (d)\nFOPENR (d) "data.txt"\nc1 = GETC(d)\nREAD (d) $rest\n'
                    'READ (d) $last\nREAD (d) $none\ns = IOSTAT(d)\nDETACH (d)', sandbox=tmp_path,
                    setup=v_plus)
    g = system.globals
    assert (g["$r3"], g["$r1"], g["n"]) == ("cc\0\0", "aaaa", 4.0)
    # [000] "Disk Directory Format": name 8, ".", ext 3, sectors 8, " ", attributes 7, date 9, " ", time 8.
    assert g["$e1"] == "DATA    .TXT       1 " + " " * 7 + " " * 9 + " " + " " * 8
    assert g["$e2"].startswith("FIXED   .DAT       1 ") and len(g["$e2"]) == 46
    assert g["s3"] == msg.UNEXPECTED_EOF
    assert (g["c1"], g["$rest"], g["$last"], g["s"]) == (ord("a"), "bc", "last", msg.UNEXPECTED_EOF)
    assert "$none" not in g  # a READ that fails leaves its variable alone


def test_directory_listing_filters_by_pattern_in_the_ev_plus_layout(tmp_path):
    # [001] "Disk Directory Format": attributes, TAB, sectors (10), TAB, date,
    # TAB, time, TAB, name (eV+, the default dialect).
    for name in ("a.txt", "b.dat", "c.TXT"):
        (tmp_path / name).write_text("x")
    system = run_ok('ATTACH (d, 4) "DISK"\nFOPEND (d) "*.txt"\nREAD (d) $e1\nREAD (d) $e2\nREAD (d) $e3\n'
                    's = IOSTAT(d)\nFCLOSE (d)\nFOPENR (d) "*.txt"\nw = IOSTAT(d)', sandbox=tmp_path)
    g = system.globals
    assert [g["$e1"], g["$e2"]] == [" " * 7 + "\t" + "1".rjust(10) + "\t" + " " * 9 + "\t" + " " * 8 + "\t" + n
                                    for n in ("A.TXT", "C.TXT")]
    assert g["s"] == msg.UNEXPECTED_EOF and "$e3" not in g
    assert g["w"] == msg.INVALID_FILE_SPEC  # wildcards only for directories


def test_disk_errors_go_to_iostat_and_the_program_goes_on(tmp_path):
    (tmp_path / "old.txt").write_text("x")
    system = run_ok('ATTACH (d, 4) "DISK"\nFOPENR (d) "missing.txt"\na = IOSTAT(d)\n'
                    'FOPENW (d) "old.txt"\nb = IOSTAT(d)\nFOPENR (d) "..\\escape.txt"\nc = IOSTAT(d)\n'
                    'FOPENR (d) "toolongname.txt"\ne = IOSTAT(d)\nREAD (d) $x\nf = IOSTAT(d)\n'
                    'WRITE (7) "x"\ng = IOSTAT(7)\nATTACH (d) "DISK"\nh = IOSTAT(d)\n'
                    'FOPENR (d) "old.txt"\nFOPENR (d) "old.txt"\ni = IOSTAT(d)\nFDELETE (d) "old.txt"\n'
                    'j = IOSTAT(d)\nFDELETE (d) "old.txt"\nk = IOSTAT(d)\nFCMND (d, 1) "x"\nl = IOSTAT(d)',
                    sandbox=tmp_path)
    g = system.globals
    assert (g["a"], g["b"], g["c"], g["e"]) == (msg.NONEXISTENT_FILE, msg.FILE_EXISTS, msg.INVALID_FILE_SPEC,
                                                msg.INVALID_FILE_SPEC)
    assert (g["f"], g["g"], g["h"], g["i"]) == (msg.FILE_NOT_OPEN, msg.NOT_ATTACHED, msg.ALREADY_ATTACHED,
                                                msg.FILE_ALREADY_OPEN)
    assert (g["j"], g["k"], g["l"]) == (1.0, msg.NONEXISTENT_FILE, msg.ILLEGAL_IO_COMMAND)
    assert not (tmp_path / "old.txt").exists() and not (tmp_path.parent / "escape.txt").exists()


def test_a_run_without_a_sandbox_has_no_disk():
    out = output_of(program('d = 5\nATTACH (d) "DISK"\nTYPE IOSTAT(d), " ", $ERROR(IOSTAT(d))'))
    assert out == f"{msg.DEVICE_NOT_READY} *Device not ready*\n"


def test_units_are_released_when_a_program_ends_normally(tmp_path):
    text = program('ATTACH (5) "DISK"\nFOPENW (5) "f.txt"\nWRITE (5) "x"\nTYPE IOSTAT(5)')
    system, task = run_vplus(text, sandbox=tmp_path)
    assert system.devices.units == {} and task.error is None
    assert (tmp_path / "f.txt").read_bytes() == b"x\r\n"


# ------------------------------------------------------------ serial lines
def test_serial_read_waits_for_a_whole_line():
    text = program('ATTACH (s, 4) "SERIAL:2"\nWRITE (s) "ping"\nREAD (s) $reply, n\nTYPE $reply, n\n'
                   'c = GETC(s, 1)\nTYPE c\nDETACH (s)')
    system, task = run_vplus(text, max_cycles=5)
    line = system.devices.serial(2)
    assert not task.finished and line.sent == b"ping\r\n"  # blocked in READ
    line.feed("abc 12\r")
    scheduler = Scheduler()
    scheduler.add(task)
    for _ in range(5):
        scheduler.run_cycle()
    assert not task.finished  # no LF yet
    line.feed("\n")
    while scheduler.alive:
        scheduler.run_cycle()
    assert system.console.output == f"abc12\n{msg.NO_DATA}\n" and line.owner is None


def test_getc_in_wait_mode_waits_for_a_byte():
    # GETC(lun) without no-wait mode waits for the next byte ([000] "Serial I/O").
    text = program('ATTACH (s, 4) "SERIAL:3"\nc = GETC(s)\nTYPE c, " ", GETC(s, 1)')
    system, task = run_vplus(text, max_cycles=5)
    assert not task.finished
    system.devices.serial(3).feed("Z")
    scheduler = Scheduler()
    scheduler.add(task)
    while scheduler.alive:
        scheduler.run_cycle()
    assert system.console.output == f"90 {msg.NO_DATA}\n"


def test_getc_reads_bytes_from_a_serial_line():
    def feed(system):
        system.devices.serial(1).feed(b"A\x03")

    out = output_of(program('ATTACH (s, 4) "SERIAL:1"\nTYPE GETC(s), " ", GETC(s, 1), " ", GETC(s, 1)'),
                    setup=feed)
    assert out == f"65 3 {msg.NO_DATA}\n"


# ----------------------------------------------------------- absent devices
def test_pendant_and_graphics_are_absent_and_errors_go_to_iostat():
    # Without a pendant ATTACH (1) fails through IOSTAT ([000] "ATTACH"): the
    # program goes on.  Graphics instructions on an unattached unit do likewise.
    out = output_of(program('ATTACH (1)\nTYPE IOSTAT(1), " ", PENDANT(-3)\n'
                            'ATTACH (g, 4) "GRAPHICS"\nTYPE g, " ", IOSTAT(g)\nGTYPE (g) 10, 10, "Hello!"\n'
                            'TYPE IOSTAT(g)\nKEYMODE 1, 4 = 0\nTYPE "on"'))
    assert out == f"{msg.DEVICE_NOT_READY} 0\n20 {msg.DEVICE_NOT_READY}\n{msg.NOT_ATTACHED}\non\n"


def test_terminal_unit_writes_to_the_console():
    out = output_of(program('WRITE (4) "via lun", /S\nATTACH (4)\nREAD (4) $line\nWRITE (4) " ", $line'),
                    stdin="typed\n")
    assert out == "via lun typed\n"


def test_unknown_argument_types_stop_the_program():
    assert error_of('x = LEN(5)').code == msg.WRONG_TYPE  # at load time: a constant
    assert error_of('n = 5\nx = LEN(n)').code == msg.WRONG_TYPE  # when it runs
    assert error_of('x = IOSTAT("a")').code == msg.WRONG_TYPE
    assert math.isclose(run_ok("x = VAL(\"1e3\")").globals["x"], 1000.0)


def test_cas_sets_only_when_the_value_matches():
    out = output_of(program("lock = 0\nTYPE CAS(lock, 0, 5), lock, CAS(lock, 0, 9), lock"))
    assert out == "0555\n"


def test_analog_io_is_absent():
    # [000] L7363-7378: IF AIO.INS(4) THEN AIO.OUT 4 = 0.56 END -- no board here.
    assert output_of(program("IF AIO.INS(4) THEN\nAIO.OUT 4 = 0.56\nEND\nTYPE \"skipped\"")) == "skipped\n"
    assert error_of("x = AIO.IN(1004)").code == msg.DEVICE_NOT_READY


def test_attach_and_detach_of_unit_0_take_and_free_the_robot():
    # [000] L899-930: DETACH (0) frees the robot, ATTACH (0) takes it back.
    text = program("ATTACH (0)\nWAIT\nDETACH ()\nWAIT\nATTACH ()\nWAIT\nWAIT")
    system, task = run_vplus(text, max_cycles=0)
    scheduler = Scheduler()
    scheduler.add(task)
    holders = []
    for _ in range(3):
        scheduler.run_cycle()
        holders.append(system.robot_holder)
    assert holders == [task, None, task]


def test_error_and_error_text_inside_a_reacte_handler():
    # [000] L4562-4572: the REACTE routine reads ERROR() and $ERROR(), then RETURNE.
    text = (program("REACTE trap\nx = undefined.thing\nTYPE \"after\"", name="main")
            + program('TYPE ERROR(-1), " ", $ERROR(ERROR(-1))\nRETURNE', name="trap"))
    assert output_of(text) == f"{msg.UNDEFINED_VALUE} *Undefined value*\nafter\n"


def test_a_wrong_argument_to_an_io_statement_stops_at_its_step(tmp_path):
    # A type error is not an I/O error: it stops the program and names the step.
    err = error_of('ATTACH (d, 4) "DISK"\nFOPENR (d) 5', sandbox=tmp_path)
    assert err.code == msg.WRONG_TYPE and err.step == 3 and err.line == 3


def test_a_file_open_for_write_can_be_read_back(tmp_path):
    # [000] "Disk I/O": FOPENW allows both read and write operations.
    system = run_ok('ATTACH (d, 4) "DISK"\nFOPENW (d) "rw.txt"\nWRITE (d) /X200, "tail"\nREAD (d) $back\n'
                    'n = IOSTAT(d, 2)\nREAD (d) $more\ns = IOSTAT(d)', sandbox=tmp_path)
    g = system.globals
    assert g["$back"] == " " * 128 and g["n"] == 204 and g["s"] == msg.UNEXPECTED_EOF


def test_graphics_statements_of_the_manual_parse_and_report_the_absent_window():
    # [000] L9262-9302 slide bar: GSLIDE (glun, 0) 1 = x, y, length, max_pos, arrow_inc, handle_pos.
    out = output_of(program('GSLIDE (20, 0) 1 = 10, 20, 100, 50, 1, 0\nTYPE IOSTAT(20)\n'
                            'GPANEL (20, 0) 100, 100, 45, 45\nGETEVENT (20) event[]\nTYPE IOSTAT(20)'))
    assert out == f"{msg.NOT_ATTACHED}\n{msg.NOT_ATTACHED}\n"


def test_getc_on_the_terminal_returns_the_typed_characters_then_cr():
    out = output_of(program("ATTACH (4)\nTYPE GETC(4), GETC(4), GETC(4), GETC(4)"), stdin="ab\n")
    assert out == f"979813{msg.UNEXPECTED_EOF}\n"


def test_vision_instructions_load_and_stop_when_run():
    assert error_of("VPICTURE (1)").code == msg.DEVICE_NOT_READY
    assert error_of("x = VFEATURE(1)").code == msg.DEVICE_NOT_READY


def test_attach_mode_4_ignores_the_old_value_of_the_unit_variable(tmp_path):
    system = run_ok('d = 0\nATTACH (d, 4) "DISK"\ns = IOSTAT(d)', sandbox=tmp_path)
    assert (system.globals["d"], system.globals["s"]) == (5.0, 1.0)


def test_serial_line_errors_reach_getc_and_read_in_order():
    # [000] "Serial I/O" error table: -524 overrun, -504 for a BREAK.
    def faults(system):
        line = system.devices.serial(1)
        line.fail(-524)
        line.fail(msg.UNEXPECTED_EOF)
        line.feed("ok\n")

    out = output_of(program('ATTACH (s, 4) "SERIAL:1"\nTYPE GETC(s, 1)\nREAD (s) $x\nTYPE IOSTAT(s)\n'
                            'READ (s) $x\nTYPE IOSTAT(s), " ", $x'), setup=faults)
    assert out == f"-524\n{msg.UNEXPECTED_EOF}\n1 ok\n"
