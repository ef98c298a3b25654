"""Complete example programs of the V+ and eV+ guides that exercise the
library (issue #3), run with the output the manuals show.

[000] is the V+ Language User's Guide v17, [001] the eV+ Language User's Guide
(../shared/seeds/); line numbers cite them.  The listings are copied as
printed, except for the extraction artefacts the digest lists (page-break
markers, running headers, and strings or comments wrapped onto a second line,
which are re-joined).
"""

from __future__ import annotations

import pytest

from twin.controller.scheduler import Scheduler
from twin.language.vplus import messages as msg

from vplus_helpers import output_of, run_vplus

# [000] L7755-7798 "Disk I/O Example"; identical in [001] L3178-3219.
DISK_EXAMPLE = r"""
.PROGRAM disk.example()
AUTO dlun, i
AUTO $file.name
$file.name = "data.tst"

; Attach to a disk logical unit
ATTACH (dlun, 4) "DISK"
IF IOSTAT(dlun) < 0 GOTO 100

; Open a new file and check status
FOPENW (dlun) $file.name
IF IOSTAT(dlun) < 0 GOTO 100

; Write the text
FOR i = 1 TO 10

WRITE (dlun) "Line "+$ENCODE(i)
IF IOSTAT(dlun) < 0 GOTO 100

END

; Close the file
FCLOSE (dlun)
IF IOSTAT(dlun) < 0 GOTO 100

; Reopen the file and read its contents
FOPENR (dlun) $file.name
IF IOSTAT(dlun) < 0 GOTO 100
READ (dlun) $txt
WHILE IOSTAT(dlun) > 0 DO

TYPE $txt
READ (dlun) $txt

END ;End of file or error
IF (IOSTAT(dlun) < 0) AND (IOSTAT(dlun) <> -504) THEN

100 TYPE $ERROR(IOSTAT(dlun)) ;Report any errors
END
FCLOSE (dlun) ;Close the file
IF IOSTAT(dlun) < 0 THEN

TYPE $ERROR(IOSTAT(dlun))
END
DETACH (dlun) ;Detach the LUN
.END
"""


def test_disk_io_example_writes_and_reads_back_ten_lines(tmp_path):
    """[000] L7755-7798: the file holds ten CR LF records and the terminal shows them."""
    out = output_of(DISK_EXAMPLE, sandbox=tmp_path)
    assert out == "".join(f"Line {i}\n" for i in range(1, 11))
    assert (tmp_path / "data.tst").read_bytes() == b"".join(b"Line %d\r\n" % i for i in range(1, 11))


def test_disk_io_example_run_twice_reports_the_existing_file(tmp_path):
    """[000] L7755-7798 with data.tst already there: FOPENW refuses to overwrite
    ([000] L3194-3205), GOTO 100 prints the error, and the FCLOSE of a unit with
    no open file prints a second one.  The file is left as it was."""
    output_of(DISK_EXAMPLE, sandbox=tmp_path)
    before = (tmp_path / "data.tst").read_bytes()
    out = output_of(DISK_EXAMPLE, sandbox=tmp_path)
    assert out == "*File already exists*\n*File not opened*\n"
    assert (tmp_path / "data.tst").read_bytes() == before


# [000] L8105-8139 "Serial I/O Examples"; identical in [001] L3388-3422.
SERIAL_IO = r"""
.PROGRAM serial.io()
; ABSTRACT: Example program to write and read lines of
; text to and from serial port 1 on the SIO module.

AUTO slun ;Logical unit to communicate to serial port
AUTO $text

; Attach to a logical unit(open communications path
; to serial port)

ATTACH (slun, 4) "SERIAL:1"
IF IOSTAT(slun) < 0 GOTO 100

; Write text out to the serial port

WRITE (slun) "Hello there! "
IF IOSTAT(slun) < 0 GOTO 100

; Read a line of text from the serial port. The incoming
; line of text must be terminated by a carriage return and
; line feed. The READ instruction will wait until a line of
; text is received.

READ (slun) $text
IF IOSTAT(slun) < 0 GOTO 100

; Display any errors

100 IF (IOSTAT(slun) < 0) THEN
TYPE IOSTAT(slun), " ", $ERROR(IOSTAT(slun))

END

DETACH (slun) ;Detach from logical unit
.END
"""


def test_serial_io_example_writes_a_line_and_waits_for_the_reply():
    """[000] L8105-8139: "Hello there! " goes out with CR LF; READ waits for a
    line; with no error nothing is typed and the line is detached at the end."""
    system, task = run_vplus(SERIAL_IO, max_cycles=10)
    line = system.devices.serial(1)
    assert line.sent == b"Hello there! \r\n" and not task.finished  # waiting in READ
    line.feed(b"OK from the peer\r\n")
    scheduler = Scheduler()
    scheduler.add(task)
    while scheduler.alive:
        scheduler.run_cycle()
    assert task.error is None and system.console.output == ""
    assert line.owner is None and line.received == b""


def test_serial_io_example_reports_an_attach_error():
    """[000] L8105-8139, error path: the line is held by another task, so ATTACH
    fails and label 100 types the code and message."""
    def busy(system):
        system.devices.serial(1).owner = 5

    out = output_of(SERIAL_IO, setup=busy)
    assert out == f"{msg.DEVICE_NOT_READY} *Device not ready*\n"


# [000] L12278-12322 "Menu Program"; identical in [001] L5048-5092.
SUB_MENU = r"""
.PROGRAM sub.menu()

; ABSTRACT: This program provides the operator with a menu of
; operation selections on the system terminal. After accepting
; input from the keyboard, the program executes the desired
; operation. In this case, the menu items include execution of
; the pick and place program, teaching locations for the pick
; and place program, and returning to a main menu.
;
; SIDE EFFECTS: The pick and place program may be executed, and
; locations may be defined.

AUTO choice, quit, $answer

quit = FALSE

DO

TYPE /C2, "PICK AND PLACE OPERATIONAL MENU"
TYPE /C1, " 1 => Initiate pick and place"
TYPE /C1, " 2 => Teach locations"
TYPE /C1, " 3 => Return to previous menu", /C1

PROMPT "Enter selection and press RETURN: ", $answer

choice = VAL($answer) ;Convert string to number

CASE choice OF ;Process menu request...
VALUE 1: ;...selection 1

TYPE /C2, "Initiating Operation..."
CALL move.parts()

VALUE 2: ;...selection 2
CALL teach()

VALUE 3: ;...selection 3
quit = TRUE

ANY ;...any other selection
TYPE /B, /C1, "** Invalid input **"
END ;End of CASE structure
UNTIL quit ;End of DO structure

.END
"""

MENU = ("\n\nPICK AND PLACE OPERATIONAL MENU\n"
        "\n 1 => Initiate pick and place\n"
        "\n 2 => Teach locations\n"
        "\n 3 => Return to previous menu\n\n"
        "Enter selection and press RETURN: ")


def test_menu_program_returns_on_selection_3():
    """[000] L12278-12322 with the answer 3: the menu, the prompt, then the end."""
    assert output_of(SUB_MENU, stdin="3\n") == MENU


@pytest.mark.parametrize("banner", ["** Invalid input **", "*** Invalid input ***"])
def test_menu_program_rejects_other_input_and_shows_the_menu_again(banner):
    """[000] L12278-12322 (and the eV+ copy, [001] L5048-5092, whose banner has
    three asterisks): VAL("x") is 0, so ANY rings the bell and shows the banner
    before the menu comes back."""
    text = SUB_MENU.replace('"** Invalid input **"', f'"{banner}"')
    out = output_of(text, stdin="x\n3\n")
    assert out == MENU + f"\a\n{banner}\n" + MENU


def test_menu_program_selection_1_calls_the_pick_and_place_program():
    """[000] L12278-12322: selection 1 types "Initiating Operation..." and CALLs
    move.parts (here a stand-in that only reports it ran)."""
    stand_in = '.PROGRAM move.parts()\nTYPE "move.parts ran"\n.END\n'
    out = output_of(SUB_MENU + stand_in, main="sub.menu", stdin="1\n3\n")
    assert out == MENU + "\n\nInitiating Operation...\nmove.parts ran\n" + MENU


# [000] L10044-10226 "MCP menu" programs (mcp.main, mcp.disp.main, mcp.main.quit);
# the strings "MAIN MENU" and " QUIT" and the call $CHR(mcp.noblink.cha) are
# re-joined where the typesetter wrapped them (L10169-10170, L10177-10178, L10212-10213).
MCP_MENU = r"""
.PROGRAM mcp.main( )

; ABSTRACT: This program creates and monitors a menu structure on the
; MCP.

AUTO button ;Number of the soft button pressed
AUTO quit ;Boolean indicating menu structure should be exited

mcp = 1
quit = FALSE
mcp.clr.scr = 12
mcp.cur.pos = 18
mcp.off.led = 28
mcp.blink.char = 2
mcp.noblink.cha = 3
mcp.beep = 7
mcp.tab = 9
mcp.on.led = 31

; Check to see if the MCP is free

IF PENDANT(-3) <> 2 THEN
GOTO 100

END

; Attach to the MCP

ATTACH (mcp)

; Verify ATTACH was successful

IF IOSTAT(mcp) <> 1 THEN
GOTO 100
END

DO ;Main processing loop

; Display the top-level menu

CALL mcp.disp.main()

; Get the operator selection (must be between 1 and 5)

DO
button = PENDANT(0)

UNTIL (button < 6)

; Turn on the LED of the selected button

WRITE (mcp) $CHR(mcp.on.led), $CHR(button), /S

; Respond to the menu item selected

CASE button OF
VALUE 1: ;Verify program exit

CALL mcp.main.quit(quit)

VALUE 2:
CALL mcp.option.2()

VALUE 3:
CALL mcp.option.3()

VALUE 4:
CALL mcp.option.4()

VALUE 5:
CALL mcp.option.5()

END ;CASE button of

; Turn off LED

WRITE (mcp) $CHR(mcp.off.led), $CHR(button), /S

UNTIL quit

; Detach from the MCP

DETACH (mcp)

100 IF NOT quit THEN ;Exit on MCP busy
TYPE /C34, /U17, "The MCP is busy or not connected."
TYPE "Press the REC/DONE button to clear.", /C5

END
.END

.PROGRAM mcp.disp.main( )

; Clear the display and write the top line

WRITE (mcp) $CHR(mcp.clr.scr), $CHR(mcp.cur.pos), $CHR(16), "MAIN MENU", /S

; Write the menu options

WRITE (mcp) $CHR(mcp.cur.pos), $CHR(41), /S
WRITE (mcp) "Option5", $CHR(mcp.tab), "Option4", $CHR(mcp.tab), /S
WRITE (mcp) "Option3", $CHR(mcp.tab), "Option2", $CHR(mcp.tab), " QUIT", /S

; Beep the MCP

WRITE (mcp) $CHR(mcp.beep), /S

.END

.PROGRAM mcp.main.quit(quit)

quit = FALSE ;assume quit will not be verified

; Display submenu and start the "NO" option blinking

WRITE (mcp) $CHR(mcp.clr.scr), "Quit. Are you sure?"
WRITE (mcp) $CHR(mcp.tab), $CHR(mcp.tab), $CHR(mcp.tab), " YES", /S
WRITE (mcp) $CHR(mcp.tab), $CHR(mcp.blink.char), " NO", $CHR(mcp.noblink.cha), /S
button = PENDANT(0)

; Set quit to true if verified, else turn off the "NO" soft button LED

IF button == 2 THEN
quit = TRUE

ELSE
WRITE (mcp) $CHR(mcp.off.led), $CHR(1), /S

END

.END
"""


def test_mcp_menu_without_a_pendant_reports_it_is_not_connected():
    """[000] L10044-10150: with no pendant PENDANT(-3) is not 2 ("background"),
    so the program jumps to 100: 34 line ends, 17 lines up (ESC M, TERMINAL
    type 4), the message, and the REC/DONE line followed by 5 line ends."""
    out = output_of(MCP_MENU, main="mcp.main")
    assert out == ("\n" * 34 + "\x1bM" * 17 + "The MCP is busy or not connected.\n"
                   + "Press the REC/DONE button to clear." + "\n" * 5 + "\n")


# [000] L8887-8910 "Custom Window Example"; [001] L3601-3624.
CUSTOM_WINDOW = r"""
.PROGRAM window.demo()
AUTO glun ; Graphics window LUN

ATTACH (glun, 4) "GRAPHICS" ; Attach to a window LUN

; Open the window "Test" with a maximum size of
; 400 x 300 pixels

FOPEN(glun) "Test","/MAXSIZE 400 300"

; Your code for processing within the window
; goes here; e.g:

GTYPE (glun) 10, 10, "Hello!"

; When the window is no longer needed, close and delete the
; window and detach from the logical unit

FCLOSE (glun)
FDELETE (glun) "Test"
DETACH (glun)
TYPE IOSTAT(glun)
.END
"""


def test_custom_window_example_runs_on_with_graphics_absent():
    """[000] L8887-8910 (plus a final TYPE of the status): the twin has no
    graphics windows, so each step fails through IOSTAT and the program runs
    to its end, as I/O errors never stop a program ([000] "IOSTAT")."""
    out = output_of(CUSTOM_WINDOW)
    assert out == f"{msg.NOT_ATTACHED}\n"


def test_terminal_io_examples():
    """[000] L7097-7139: TYPE text, TYPE with a variable (x = 27), the screen-
    centre idiom /C34, /U17, PROMPT into a real, and the VAL loop that asks
    again until the entry is positive."""
    text = (".PROGRAM terminal()\n"
            'TYPE "This is a terminal output instruction."\n'
            "x = 27\n"
            'TYPE "The value of x is ", x, "."\n'
            'TYPE /C34, /U17, "This is the screen center."\n'
            'PROMPT "Enter a value for x: ", x\n'
            "DO\n"
            'PROMPT "Enter a value greater than 0: ", $x\n'
            "x = VAL($x)\n"
            "UNTIL x > 0\n"
            "TYPE x\n"
            ".END\n")
    out = output_of(text, stdin="5\nabc\n-2\n7\n")
    assert out == ("This is a terminal output instruction.\n"
                   "The value of x is 27.\n"
                   + "\n" * 34 + "\x1bM" * 17 + "This is the screen center.\n"
                   "Enter a value for x: "
                   + "Enter a value greater than 0: " * 3 + "7\n")


def test_string_examples():
    """[000] L4313-4322 concatenation; [000] L5359-5367 $ERROR and $ENCODE;
    [000] L5464-5471 SQRT(VAL("16")); [000] L12693-12697 $CHR(229) is byte 229."""
    text = (".PROGRAM strings()\n"
            '$name = "Adept "\n$incorp = ", Inc."\n$coname = $name + "Technology" + $incorp\n'
            "TYPE $coname\n"
            "TYPE $ERROR(-504)\n"
            '$message = "The length of this line is: "\n'
            'TYPE $ENCODE($message, /I0, LEN($message)+14), " characters."\n'
            '$a = "16"\nx = SQRT(VAL($a))\nTYPE x\n'
            "TYPE $CHR(229)\n"
            ".END\n")
    out = output_of(text)
    assert out == ("Adept Technology, Inc.\n*Unexpected end of file*\n"
                   "The length of this line is: 42 characters.\n4\n\u00e5\n")


def test_digital_io_fragment():
    """[000] L7254-7295: WAIT SIG(1001); IF SIG(1002) THEN CALL service.feeder();
    SIGNAL(-33); SIGNAL(33); IF SIG.INS(33); SIGNAL(33), (-34), (35)."""
    text = (".PROGRAM io.demo()\n"
            "WAIT SIG(1001)\n"
            "IF SIG(1002) THEN\nCALL service.feeder()\nEND\n"
            "SIGNAL(-33)\nSIGNAL(33)\n"
            "IF SIG.INS(33) THEN\nSIGNAL(33), (-34), (35)\nEND\n"
            ".END\n"
            ".PROGRAM service.feeder()\nSIGNAL 34\n.END\n")

    def inputs(system):
        system.io.set(1001, True)
        system.io.set(1002, True)

    system, task = run_vplus(text, setup=inputs)
    assert task.error is None
    assert [system.io.sig(s) for s in (33, 34, 35)] == [True, False, True]
    assert (34, True) in system.io.changes and (34, False) in system.io.changes


# [001] L4338-4466 "operatorcontrol" (eV+, T20 pendant), with the digest's errata
# fixed: the stray END lines after the two CASE blocks (L4409-4411, L4432) are
# removed and the wrapped string and statements (L4407-4408, L4426-4427,
# L4436-4437) are re-joined.
OPERATOR_CONTROL = r"""
.PROGRAM operatorcontrol()
    AUTO $p.title, $p.msg[15], $p.f[15], key, app.sel
    AUTO pendant.lun

    pendant.lun = 1

; Attach to the Pendant

    ATTACH (pendant.lun)

; Verify ATTACH was successful

    IF IOSTAT(pendant.lun) <> 1 THEN
        TYPE "Pendant is either busy or not connected"
        GOTO 100      ;ERROR
    END

    $prog.list[0] = "Cookie1"
    $prog.list[1] = "Cookie2"
    $prog.list[2] = "Cookie3"
    $prog.list[3] = "Cookie4"
    $prog.list[4] = "Cookie5"
    prog.len = 5

    key = -1
    app.sel = 0
    $p.title = ""
    FOR i = 0 TO 10
        $p.msg[i] = ""
    END
    FOR i = 0 TO 4
        $p.f[i] = ""
    END

    $p.title = "Operator Control"
    $p.msg[0] = "Select Option from buttons below"
    $p.f[1] = "Apps"
    $p.f[2] = "Status"
    $p.f[3] = ""
    $p.f[4] = ""

PDNT.WRITE $p.title, $p.msg[], $p.f[1], $p.f[2], $p.f[3], $p.f[4]

WHILE TRUE DO
    KEYMODE 1, 4 = 0      ;Set Keymode of F keys detect next keypress
    key = PENDANT(0)      ;Obtain Pressed key
    CASE key OF
        VALUE 1:          ;Apps pressed, continue to Screen 2
            GOTO 10
        VALUE 2:          ;Display Filler Notification
            PDNT.NOTIFY "Status", "No Program Running" ;Obtain info of task 1 here
    END
END

10 $p.title = "List of Applications"
   $p.f[1] = "Run"
   $p.f[2] = "Up"
   $p.f[3] = "Down"
   $p.f[4] = "Done"
   FOR i = 0 TO 10
       $p.msg[i] = ""
   END
   FOR i = 0 TO prog.len-1
       IF i == app.sel THEN
           $p.msg[i] = $p.msg[i]+"<center><u>"+$prog.list[i]+"</u></center>"
       ELSE
           $p.msg[i] = $p.msg[i]+"<center>"+$prog.list[i]+"</center>"
       END
   END

PDNT.WRITE (prog.len) $p.title, $p.msg[], $p.f[1], $p.f[2], $p.f[3], $p.f[4]
KEYMODE 1, 28 = 0
WHILE TRUE DO
    key = PENDANT(0)
    CASE key OF
        VALUE 1, 18:      ;F1 or OK
            CALLS $prog.list[app.sel]()
            GOTO 10 ;
        VALUE 2, 17:      ;F2 or Up arrow
            app.sel = (app.sel-1) MOD prog.len
            GOTO 10
        VALUE 3, 21:      ;F3 or Down arrow
            app.sel = (app.sel+1) MOD prog.len
            GOTO 10
        VALUE 4:          ;F4
            GOTO 90
    END
END

    90  PDNT.CLEAR
        DETACH (1)

    100 RETURN

.END
"""


def test_operator_control_without_a_pendant_says_so_and_returns():
    """[001] L4338-4466: with no T20 connected, ATTACH (1) fails, the program
    types its message and RETURNs without touching the pendant screens."""
    system, task = run_vplus(OPERATOR_CONTROL)
    assert task.error is None and task.finished
    assert system.console.output == "Pendant is either busy or not connected\n"


# [000] L8146-8190 second serial example; identical in [001] L3428-3466.
DISPLAY = r"""
.PROGRAM display()
; ABSTRACT: Monitor a serial line and read data when
; available

AUTO $buffer, c, done, etx, ienod, line
etx = 3 ;ASCII code for ETX character
ienod = -526 ;Error code for no data
ATTACH (line, 4) "SERIAL:1"
IF IOSTAT(line) < 0 GOTO 90 ;Check for errors
$buffer = "" ;Initialize buffer to empty
done = FALSE ;Assert not done
DO

CLEAR.EVENT
c = GETC(line,1) ;Read byte from the ser. line
WHILE c == ienod DO ;While there is no data...

WAIT.EVENT 1 ;Wait for an event
CLEAR.EVENT
c = GETC(line,1) ;Read byte from the ser. line

END
IF c < 0 GOTO 90 ;Check for errors
IF c == etx THEN ;If ETX seen...

TYPE $buffer, /N ;Type buffer
done = (LEN($buffer) == 0) ;Done if buffer length is 0
$buffer = "" ;Set buffer to empty

ELSE
$buffer = $buffer+$CHR(c) ;Append next byte
;to buffer
END
UNTIL done ;Loop until empty buffer seen

GOTO 100 ;Exit
90 TYPE "SERIAL LINE I/O ERROR: ", $ERROR(IOSTAT(line))

PAUSE
100 DETACH (line)

RETURN
.END
"""


def test_display_example_types_etx_records_until_an_empty_one():
    """[000] L8146-8190: records end with ETX (not shown); the program sleeps in
    WAIT.EVENT until bytes arrive (arriving bytes set the task's event flag),
    types each record, and stops after the empty one, detaching the line."""
    system, task = run_vplus(DISPLAY, max_cycles=20)
    line = system.devices.serial(1)
    assert not task.finished and system.console.output == ""  # waiting for data
    scheduler = Scheduler()
    scheduler.add(task)
    for chunk in (b"AB", b"C\x03DE", b"F\x03", b"\x03"):
        line.feed(chunk)
        for _ in range(3):
            scheduler.run_cycle()
    assert task.finished and task.error is None
    assert system.console.output == "ABC\nDEF\n\n" and line.owner is None


# [000] L9452-9492 "label.blob()"; [001] L4088-4123.
LABEL_BLOB = r"""
.PROGRAM label.blob()

; ABSTRACT: This program demonstrates how to attach to the
; vision window and how to use the millimeter scaling mode of
; the GTRANS instruction to label a "blob" in the vision
; window.
;

AUTO vlun
cam = 1
; Attach the vision window and get a logical unit number
ATTACH (vlun, 4) "GRAPHICS"
IF IOSTAT(vlun) < 0 GOTO 100
FOPEN (vlun) "Vision" ;Open the vision window
IF IOSTAT(vlun) < 0 GOTO 100
; Select display mode and graphics mode
VDISPLAY (cam) 1, 1 ;Display grayscale frame and graphics
; Take a picture and locate an object
VPICTURE (cam) ;Take a processed picture
VLOCATE (cam, 2) "?" ;Attempt to locate an object
IF VFEATURE(1) THEN ;If an object was found...

GCOLOR (vlun) 1 ;Select the color black
GTRANS (vlun, 2) ;Select millimeter scaling
GTYPE (vlun) DX(vis.loc), DY(vis.loc), "Blob", 3

ELSE ;Else if object was NOT found...
GCOLOR (vlun) 3 ;Select the color red
GTRANS (vlun, 0) ;Select pixel scaling
GTYPE (vlun) 100, 100, "No object found!", 3

END
; Detach (frees up the communications path)
DETACH (vlun)

100 IF (IOSTAT(vlun) < 0) THEN ; Check for errors
TYPE $ERROR(IOSTAT(vlun))

END

.END
"""


def test_label_blob_without_graphics_reports_the_attach_error():
    """[000] L9452-9492: without a graphics system (the eV+ v2 case, and the
    twin's), ATTACH fails, GOTO 100 and the error text is typed; the vision
    instructions are never reached."""
    assert output_of(LABEL_BLOB) == "*Device not ready*\n"


def test_serial_io_example_reports_a_line_error():
    """[000] L8105-8139 with a parity error on the line ([000] "Serial I/O":
    -522 *Data error on device*): the READ fails, label 100 types code and text."""
    system, task = run_vplus(SERIAL_IO, max_cycles=5)
    system.devices.serial(1).fail(msg.DATA_ERROR)
    scheduler = Scheduler()
    scheduler.add(task)
    while scheduler.alive:
        scheduler.run_cycle()
    assert system.console.output == f"{msg.DATA_ERROR} *Data error on device*\n"
