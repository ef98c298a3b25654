"""V+ as public field servers write it (issue #10's sweep of field programs).

The public V+ servers read for this (the ROS-Industrial Adept drivers:
ros-industrial-attic/swri-ros-pkg `adept/adept_common/V+/ros.v2` and its
further development BenjaminSchellenbeck/adept_experimental
`adept_driver/V+/adept_ros.v2`, `adept_ros_scara.v2`) use constructs that the
twin rejected or mishandled.  Each test below is a program of our own that uses
the construct the way those servers do (none of their code is copied); the last
one is a whole server in their structure, driven by a client.

[000] V+ Language User's Guide v17, [001] eV+ Language User's Guide.
"""

from __future__ import annotations

import socket
import struct
import threading
import time

import numpy as np

from twin.controller import network
from twin.language.vplus import messages as msg
from twin.runner import finish_run, run_program, start_program

from test_clients_ros import connect, receive
from test_clients_tcp import ScriptedPeer, free_port
from vplus_helpers import output_of, run_vplus


# ------------------------------------------------ arguments passed by reference
def test_an_undefined_array_element_passed_by_reference_is_defined_by_the_callee():
    # [001] L504-610: arguments are passed by reference; the drivers pass the
    # elements of a fresh AUTO string array as output parameters of a helper
    # that reverses bytes, so the element is undefined when the CALL is made.
    text = """
.PROGRAM main()
    AUTO $out[4], i
    FOR i = 1 TO 3
        CALL flip($CHR(64+i)+"z", $out[i])
    END
    CALL flip("ab", $g[2])
    TYPE $out[1], $out[2], $out[3], " ", $g[2], " ", DEFINED($out[4]), " ", DEFINED($out[1])
.END
.PROGRAM flip($in, $rev)
    AUTO k
    TYPE DEFINED($rev)
    $rev = ""
    FOR k = LEN($in) TO 1 STEP -1
        $rev = $rev+$MID($in, k, 1)
    END
.END
"""
    out = output_of(text).split("\n")
    assert out[:4] == ["0", "0", "0", "0"]  # the callee sees an undefined parameter
    assert out[4] == "zAzBzC ba 0 -1"


def test_a_defined_element_is_still_passed_and_written_back():
    out = output_of("""
.PROGRAM main()
    AUTO n[2]
    n[1] = 5
    CALL twice(n[1])
    TYPE n[1]
.END
.PROGRAM twice(x)
    x = 2*x
.END
""")
    assert out == "10\n"


# --------------------------------------------------------------- GETC modes
def test_getc_mode_2_suppresses_echo_and_still_waits():
    # [000] L7224-7225: an optional mode suppresses echo; L7530-7533: another
    # selects no-wait.  The mode is bit flags (1 no-wait, 2 no echo), so the
    # drivers' GETC(lun, 2) waits for its byte; GETC(lun, mode) with mode 3 does not.
    text = """
.PROGRAM main()
    ATTACH (s, 4) "SERIAL:2"
    nowait = 3
    TYPE GETC(s, nowait)
    c = GETC(s, 2)
    TYPE c, " ", GETC(s, nowait)
.END
"""
    fed = []

    def feed_late(system):
        fed.append(1)
        if len(fed) == 10:
            system.devices.serial(2).feed("A")

    system, task = run_vplus(text, each_cycle=feed_late, max_cycles=50)
    assert task.error is None and task.finished
    assert system.console.output == f"{msg.NO_DATA}\n65 {msg.NO_DATA}\n"


# ------------------------------------------------------------------ FCMND
IO_SERVER = """
.PROGRAM io.srv()
    AUTO lun, h, st, served, $in
    ATTACH (lun, 4) "TCP"
    FOPEN (lun, 16) "/LOCAL_PORT {port} /CLIENTS 2 /BUFFER_SIZE 64"
    served = 0
    WHILE served < 2 DO
        READ (lun, h, 0) $in
        st = IOSTAT(lun)
        CASE st OF
          VALUE 100:
            TYPE "new ", h
          VALUE 1:
            TYPE "data ", h, " ", $in
            IF $in == "bye" THEN
                FCMND (lun, 600) $INTB(h)
                TYPE "closed ", IOSTAT(lun)
                served = served+1
            END
          VALUE 101:
            FCMND (lun, 600) $INTB(h)
            TYPE "gone ", h, " ", IOSTAT(lun)
            served = served+1
        END
    END
    FCMND (lun, 601) $INTB(1)
    TYPE "601 ", IOSTAT(lun)
    FCMND (lun, 600) $INTB(9)
    TYPE "9 ", IOSTAT(lun)
    FCLOSE (lun)
    DETACH (lun)
.END
"""


def test_fcmnd_600_closes_a_client_and_frees_a_handle_already_gone():
    # The drivers answer IOSTAT 101 (a client left) with FCMND (lun, 600)
    # $INTB(handle) and stop serving if its IOSTAT is negative; a server may also
    # close a client itself.  Other command numbers: *Illegal I/O device command*.
    port = free_port()
    leaves = ScriptedPeer(port, [(2, "connect", b""), (4, "send", b"hi"), (6, "close", b"")])
    stays = ScriptedPeer(port, [(3, "connect", b""), (9, "send", b"bye")])

    def both(system):
        leaves(system)
        stays(system)

    system, task = run_vplus(IO_SERVER.format(port=port), each_cycle=both, max_cycles=200)
    assert task.error is None
    assert system.console.output.split("\n")[:-1] == [
        "new 1", "new 2", "data 1 hi", "gone 1 1", "data 2 bye", "closed 1",
        f"601 {msg.ILLEGAL_IO_COMMAND}", f"9 {msg.ILLEGAL_VALUE}"]
    stays.sock.setblocking(True)
    stays.sock.settimeout(5)
    assert stays.sock.recv(10) == b""  # the server closed the connection
    stays.sock.close()


def test_fcmnd_on_a_disk_file_is_an_illegal_io_command(tmp_path):
    out = output_of("""
.PROGRAM main()
    ATTACH (d, 4) "DISK"
    FOPENW (d) "f.txt"
    FCMND (d, 600) $INTB(1)
    TYPE IOSTAT(d)
.END
""", sandbox=tmp_path)
    assert out == f"{msg.ILLEGAL_IO_COMMAND}\n"


def test_a_server_that_only_writes_sees_its_client_connect():
    # A feedback server never READs: the network still accepts its client, and
    # WRITE (lun) reaches it (the drivers' joint feedback port).
    port = free_port()
    text = f"""
.PROGRAM fdb()
    AUTO lun, k
    ATTACH (lun, 4) "TCP"
    FOPEN (lun, 16) "/LOCAL_PORT"+$ENCODE(port)+" /CLIENTS 1"
    FOR k = 1 TO 12
        WRITE (lun) $LNGB(k), /S
        TYPE IOSTAT(lun)
        WAIT.EVENT , 0.016
    END
.END
"""
    text = text.replace("port)", f"{port})")
    peer = ScriptedPeer(port, [(4, "connect", b"")])
    system, task = run_vplus(text, each_cycle=peer, max_cycles=200)
    peer.take()
    assert task.error is None
    statuses = [int(s) for s in system.console.output.split()]
    first = statuses.index(1)
    assert statuses[:first] == [msg.NETWORK_CLOSED] * first and set(statuses[first:]) == {1}
    values = struct.unpack(f">{len(peer.received) // 4}i", bytes(peer.received))
    assert values == tuple(range(first + 1, 13))


# --------------------------------------------- a whole server in their structure
DRIVER = """
.PROGRAM drv.main()
; Start the servers and a supervisor, then leave (task 0 is free again).
        cmd.port = 11000
        fdb.port = 11002
        fdb.period = 0.05
        run = TRUE
        EXECUTE 1 drv.fdb()
        EXECUTE 2 drv.watch()
        RETURN
.END
.PROGRAM drv.watch()
; Restart the command server in task 0 whenever it is not executing.
        WHILE run DO
            IF TASK(1, 0) <> 4 THEN
                EXECUTE 0 drv.cmd()
            END
            WAIT.EVENT , 0.2
        END
.END
.PROGRAM drv.long(lun, got)
        AUTO c, i, $b
        $b = ""
        FOR i = 1 TO 4
            c = GETC(lun, 2)
            IF c < 0 THEN
                got = c
                RETURN
            END
            $b = $b+$CHR(c)
        END
        got = LNGB($b)
.END
.PROGRAM drv.float(lun, got)
        AUTO i, $b
        $b = ""
        FOR i = 1 TO 4
            $b = $b+$CHR(GETC(lun, 2))
        END
        got = FLTB($b)
.END
.PROGRAM drv.cmd()
        AUTO REAL jts[4]
        AUTO lun, st, idx, size, seq
        LOCAL #goal
        ATTACH (lun, 4) "TCP"
        FOPEN (lun, 16) "/LOCAL_PORT"+$ENCODE(cmd.port)+" /CLIENTS 1 /BUFFER_SIZE 1024"
        st = IOSTAT(lun)
        IF (st < 0) THEN
            TYPE "cmd: "+$ERROR(st)
            GOTO 100
        END
        SELECT ROBOT = 1
        ATTACH ()
        SPEED 100 ALWAYS
        ACCEL (1) 100, 100
        WHILE run DO
            CALL drv.long(lun, size)
            IF size == -562 THEN
                TYPE "cmd: client left"
                GOTO 90
            END
            CALL drv.long(lun, seq)
            FOR idx = 1 TO 4
                CALL drv.float(lun, jts[idx])
            END
            IF seq < 0 THEN
                run = FALSE
                GOTO 90
            END
            SET #goal = #PPOINT(jts[1]*180/PI, jts[2]*180/PI, jts[3]*1000, jts[4]*180/PI)
            MOVE #goal
            BREAK
            WRITE (lun) $ENCODE($LNGB(4), $LNGB(seq)), /S
        END
   90   FCLOSE (lun)
        DETACH (lun)
  100   RETURN
.END
.PROGRAM drv.fdb()
        AUTO lun, st, idx
        AUTO REAL q[10]
        AUTO LOC #now
        AUTO $msg
        ATTACH (lun, 4) "TCP"
        FOPEN (lun, 16) "/LOCAL_PORT"+$ENCODE(fdb.port)+" /CLIENTS 1 /BUFFER_SIZE 1024"
        WHILE run DO
            HERE #now
            DECOMPOSE q[1] = #now
            $msg = $LNGB(20)+$LNGB(STATE(4) BAND 4)
            FOR idx = 1 TO 4
                IF idx == 3 THEN
                    $msg = $msg+$FLTB(q[idx]/1000)
                ELSE
                    $msg = $msg+$FLTB(q[idx]*PI/180)
                END
            END
            WRITE (lun) $msg, /S
            WAIT.EVENT , fdb.period
        END
        FCLOSE (lun)
        DETACH (lun)
.END
"""

TARGETS = [[0.3, 0.5, 0.015, 0.2], [-0.4, 1.0, 0.03, -1.0], [1.0, -1.2, 0.0, 2.0]]


def test_a_server_in_the_field_drivers_structure_moves_the_robot(tmp_path):
    """Two TCP ports (commands read byte by byte with GETC and LNGB/FLTB; feedback
    written with $LNGB/$FLTB every 50 ms), a supervisor task that restarts the
    command server in task 0 with EXECUTE when TASK(1, 0) is not 4, and the
    command server's robot set-up (SELECT ROBOT, ATTACH (), SPEED ... ALWAYS,
    ACCEL (1) ...).  The first client leaves without a word: the command server
    ends, the supervisor restarts it and the second client is served."""
    program = tmp_path / "driver.v2"
    program.write_text(DRIVER)
    network.port_map.update({11000: 0, 11002: 0})
    log: list = []
    done = threading.Event()
    try:
        started = start_program(program)

        def client():
            try:
                feedback = connect(11002)
                first = connect(11000)
                time.sleep(0.2)
                first.close()  # the command server ends; the supervisor restarts it
                time.sleep(0.5)
                command = connect(11000)
                for seq, target in enumerate(TARGETS):
                    command.sendall(struct.pack(">ii4f", 20, seq, *target))
                    log.append(struct.unpack(">ii", receive(command, 8)))
                    time.sleep(0.2)
                    while True:  # the newest feedback message
                        feedback.setblocking(False)
                        try:
                            feedback.recv(65536)
                        except BlockingIOError:
                            break
                    feedback.setblocking(True)
                    log.append(struct.unpack(">ii4f", receive(feedback, 24)))
                command.sendall(struct.pack(">ii4f", 20, -1, 0, 0, 0, 0))
                command.close()
                feedback.close()
            except BaseException as err:  # reported below, not lost in the thread
                log.append(err)
            finally:
                done.set()

        threading.Thread(target=client, daemon=True).start()
        # The client sleeps in wall time while the idle cell runs far faster than real time:
        # the limit is only a guard, the run ends when the client is done.
        outcome = started.simulation.run(max_sim_time=3600.0, on_cycle=done.is_set)
        result = finish_run(started, outcome)
    finally:
        for port in (11000, 11002):
            network.port_map.pop(port, None)
    assert not any(isinstance(entry, BaseException) for entry in log), (log, result.report.errors)
    assert result.report.errors == []
    assert result.report.output.count("cmd: client left") == 1
    replies, feedback = log[0::2], log[1::2]
    assert replies == [(4, 0), (4, 1), (4, 2)]
    for target, (size, estop, *joints) in zip(TARGETS, feedback):
        assert (size, estop) == (20, 0)
        error = np.abs(np.array(joints) - target)
        assert np.degrees(error[[0, 1, 3]]).max() < 0.01 and error[2] < 1e-5


# ------------------------------------------------------ command programs (MC lines)
def test_a_command_program_runs_its_monitor_commands(tmp_path):
    # An auto-start file's program is a command program: "MC" and a monitor command
    # on each line ([000] "Auto-Starting Programs With the MCP": the program "is invoked
    # as though with a COMMANDS monitor command").  Those a program instruction also
    # does run as that instruction; monitor SPEED sets the monitor speed; LOAD of a
    # file the run was given does nothing; "mc" is still a variable name.
    (tmp_path / "cell.v2").write_text('.PROGRAM work()\n    TYPE "working"\n.END\n')
    (tmp_path / "auto.v2").write_text("""
.PROGRAM auto()
    MC LOAD D:\\CELL.V2       ; the module twin run was also given
    MC DISABLE POWER
    MC ENABLE POWER
    MC CALIBRATE
    MC SPEED 80
    MC EXECUTE 1 work()
    TYPE "speed ", SPEED(1), " power ", SWITCH(POWER)
    mc = 3
    mc[2] = 4
    TYPE mc+mc[2]
    WAIT.EVENT , 0.1
    MC ZERO
    TYPE "not reached"
.END
""")
    result = run_program([tmp_path / "auto.v2", tmp_path / "cell.v2"], max_sim_time=5)
    assert result.report.output == "speed 80 power -1\n7\nworking\n"
    (error,) = result.report.errors
    assert error["code"] == msg.DEVICE_NOT_READY and error["line"] == 14
    assert "MC ZERO: there is no monitor" in error["message"]


def test_a_command_program_that_loads_a_file_the_run_lacks_stops_there():
    system, task = run_vplus('.PROGRAM auto()\n    MC LOAD other.v2\n    TYPE "no"\n.END\n')
    assert system.console.output == ""
    assert task.error.code == msg.NONEXISTENT_FILE and task.error.line == 2
    assert "name this one on its command line" in str(task.error)


def test_a_malformed_monitor_command_is_a_located_error():
    from twin.errors import ProgramError
    from twin.language.vplus.parser import parse

    try:
        parse(".PROGRAM auto()\n    MC EXECUTE 1 (\n.END\n", "auto.v2")
    except ProgramError as err:
        assert err.code == msg.SYNTAX_ERROR and err.line == 2 and "monitor command" in str(err)
    else:
        raise AssertionError("no error")
    # "MC" and nothing else (blanks, a comment) is MCS abbreviated, absent like MCS
    for line in ("MC ", "MC \t", "MC   ; nothing"):
        system, task = run_vplus(f'.PROGRAM auto()\n    TYPE "a"\n    {line}\n.END\n')
        assert task.error.code == msg.DEVICE_NOT_READY and task.error.line == 3 and system.console.output == "a\n"


# ------------------------------------------------------- device error variables
def test_the_error_variable_of_setdevice_and_device_receives_the_status(tmp_path):
    # [001] "Using DEVICE and SETDEVICE": SETDEVICE (0, unit, error, command) and
    # DEVICE(0, unit, error, select) name a variable for the device's error status, which
    # a program does not set beforehand; the twin's encoders report no error (0).
    program = tmp_path / "enc.pg"
    program.write_text("""
.PROGRAM enc()
    SETDEVICE (0, 0, err, 0)
    SETDEVICE (0, 0, err, 8) 0.5
    TYPE "setdevice ", err
    x = DEVICE(0, 0, status[1], 1)
    TYPE "device ", status[1], " ", DEFINED(x)
.END
""")
    result = run_program(program, scene="scenes/scara_conveyor.toml", max_sim_time=1)
    assert result.report.output == "setdevice 0\ndevice 0 -1\n"
    assert [e["code"] for e in result.report.errors] == [None]  # only the time limit
