"""Sandbox escapes corpus: a program's file I/O stays inside its `<program>-files` folder
whatever it names and whatever was planted there (symbolic links, FIFOs), the sandbox
folder itself cannot be a planted link, and GPL sockets reach nothing but loopback
(docs/robustness.md, "Sandbox")."""

from __future__ import annotations

import os
import socket

import pytest

from gpl_helpers import run_gpl
from robustness_helpers import run_cli, vplus_file
from twin.controller.sandbox import Sandbox, SandboxError, check_root
from twin.language.gpl.library import codes
from twin.language.vplus import messages as msg
from vplus_helpers import run_vplus

SECRET = "top secret"
# GPL declares variables at the outermost level of a procedure only: the cases assign them.
DECLARATIONS = "".join(f"        Dim {d}\n" for d in (
    "r As StreamReader", "w As StreamWriter", "n As Integer", "a() As String", "c As TcpClient",
    "u As UdpClient", "l As TcpListener", "mb As Modbus"))


@pytest.fixture
def planted(tmp_path):
    """A sandbox folder with links planted in it to a file and a folder outside, a FIFO,
    and an honest file; returns (sandbox, outside folder)."""
    outside = tmp_path / "outside"
    outside.mkdir()
    (outside / "secret.txt").write_text(SECRET)
    box = tmp_path / "box"
    box.mkdir()
    (box / "link.txt").symlink_to(outside / "secret.txt")
    (box / "dirlink").symlink_to(outside, target_is_directory=True)
    os.mkfifo(box / "fifo.txt")
    (box / "plain.txt").write_text("plain\r\n")
    return box, outside


def _vplus_statuses(text: str, sandbox) -> dict:
    system, task = run_vplus(text, sandbox=sandbox)
    assert task.error is None, task.error
    return {name: value for name, value in system.globals.items() if isinstance(value, float)}


VPLUS_ESCAPES = [
    ("read-link", 'FOPENR (5) "link.txt"'),
    ("read-through-folder-link", 'FOPENR (5) "dirlink\\secret.txt"'),
    ("write-through-folder-link", 'FOPENW (5) "dirlink\\new.txt"'),
    ("append-link", 'FOPENA (5) "link.txt"'),
    ("list-folder-link", 'FOPEND (5) "dirlink\\*.*"'),
    ("delete-link", 'FDELETE (5) "link.txt"'),
    ("delete-through-folder-link", 'FDELETE (5) "dirlink\\secret.txt"'),
    ("read-fifo", 'FOPENR (5) "fifo.txt"'),
    ("dotdot", 'FOPENR (5) "..\\outside\\secret.txt"'),
    ("dotdot-unit", 'FOPENR (5) "C:..\\secret.txt"'),
    ("dotdot-write", 'FOPENW (5) "..\\escape.txt"'),
]


@pytest.mark.parametrize("statement", [c[1] for c in VPLUS_ESCAPES], ids=[c[0] for c in VPLUS_ESCAPES])
def test_vplus_file_escape_is_refused(planted, statement):
    box, outside = planted
    status = _vplus_statuses(f'.PROGRAM t()\n    ATTACH (5, 0) "DISK"\n    {statement}\n'
                             f'    s = IOSTAT(5)\n.END\n', box)["s"]
    assert status in (msg.INVALID_FILE_SPEC, msg.NONEXISTENT_FILE)
    assert status == msg.INVALID_FILE_SPEC or statement.startswith("FDELETE")
    assert (outside / "secret.txt").read_text() == SECRET  # never written, never deleted
    assert sorted(p.name for p in outside.iterdir()) == ["secret.txt"]


def test_vplus_listing_leaves_out_links_and_fifos(planted):
    box, _ = planted
    system, task = run_vplus('.PROGRAM t()\n    ATTACH (5, 0) "DISK"\n    FOPEND (5) "*.*"\n'
                             '    READ (5) $a\n    READ (5) $b\n    s = IOSTAT(5)\n.END\n', sandbox=box)
    assert task.error is None
    listing = system.globals["$a"] + system.globals.get("$b", "")
    assert "PLAIN" in listing and "LINK" not in listing and "FIFO" not in listing
    assert system.globals["s"] == msg.UNEXPECTED_EOF


def test_vplus_honest_file_still_reads(planted):
    box, _ = planted
    system, task = run_vplus('.PROGRAM t()\n    ATTACH (5, 0) "DISK"\n    FOPENR (5) "plain.txt"\n'
                             '    READ (5) $a\n.END\n', sandbox=box)
    assert task.error is None and system.globals["$a"] == "plain"


GPL_ESCAPES = [
    ("read-link", 'r = New StreamReader("/flash/x")', "flash/x", "link"),
    ("write-link", 'w = New StreamWriter("/flash/x")', "flash/x", "link"),
    ("append-link", 'w = New StreamWriter("/flash/x", True)', "flash/x", "link"),
    ("copy-from-link", 'File.Copy("/flash/x", "/flash/y")', "flash/x", "link"),
    ("copy-onto-link", 'File.Copy("/flash/plain.txt", "/flash/x", True)', "flash/x", "link"),
    ("delete-link", 'File.DeleteFile("/flash/x")', "flash/x", "link"),
    ("crc-of-link", 'n = File.ComputeCRC("/flash/x")', "flash/x", "link"),
    ("length-of-link", 'n = File.ComputeLength("/flash/x")', "flash/x", "link"),
    ("read-through-dir-link", 'r = New StreamReader("/flash/d/secret.txt")', "flash/d", "dirlink"),
    ("write-through-dir-link", 'w = New StreamWriter("/flash/d/new.txt")', "flash/d", "dirlink"),
    ("list-dir-link", 'a = File.GetFiles("/flash/d")', "flash/d", "dirlink"),
    ("mkdir-in-dir-link", 'File.CreateDirectory("/flash/d/sub")', "flash/d", "dirlink"),
    ("rmdir-dir-link", 'File.DeleteDirectory("/flash/d")', "flash/d", "dirlink"),
    ("device-is-link", 'r = New StreamReader("/flash2/secret.txt")', "flash2", "dirlink"),
    ("read-fifo", 'r = New StreamReader("/flash/f")', "flash/f", "fifo"),
    ("dotdot", 'r = New StreamReader("/flash/../../outside/secret.txt")', None, None),
    ("absolute-host-path", 'r = New StreamReader("/etc/passwd")', None, None),
]


@pytest.mark.parametrize("statement, where, kind", [c[1:] for c in GPL_ESCAPES], ids=[c[0] for c in GPL_ESCAPES])
def test_gpl_file_escape_is_refused_with_a_catchable_error(tmp_path, statement, where, kind):
    outside = tmp_path / "outside"
    outside.mkdir()
    (outside / "secret.txt").write_text(SECRET)
    box = tmp_path / "box"
    (box / "flash").mkdir(parents=True)
    (box / "flash" / "plain.txt").write_text("plain")
    if kind is not None:
        planted = box / where
        if kind == "link":
            planted.symlink_to(outside / "secret.txt")
        elif kind == "dirlink":
            planted.symlink_to(outside, target_is_directory=True)
        else:
            os.mkfifo(planted)
    text = ("Module M\n    Public Sub Main()\n" + DECLARATIONS + "        Try\n            " + statement + "\n"
            "            Console.WriteLine(\"escaped\")\n        Catch ex As Exception\n"
            "            Console.WriteLine(\"refused \" & CStr(ex.ErrorCode))\n        End Try\n"
            "    End Sub\nEnd Module\n")
    system, thread = run_gpl(text, sandbox=box)
    assert thread.error is None, thread.error
    assert system.console.output.strip() == f"refused {codes.INVALID_PATH[0]}"
    assert (outside / "secret.txt").read_text() == SECRET
    assert sorted(p.name for p in outside.iterdir()) == ["secret.txt"]


def test_gpl_listing_leaves_out_links(tmp_path):
    box = tmp_path / "box"
    (box / "flash").mkdir(parents=True)
    (box / "flash" / "plain.txt").write_text("x")
    (box / "flash" / "link.txt").symlink_to(tmp_path)
    text = ('Module M\n    Public Sub Main()\n        Dim a() As String = File.GetFiles("/flash")\n'
            '        Console.WriteLine(CStr(a.Length) & " " & a(0))\n    End Sub\nEnd Module\n')
    system, thread = run_gpl(text, sandbox=box)
    assert thread.error is None, thread.error
    assert system.console.output.strip() == "1 plain.txt"


# ------------------------------------------------------------------ the sandbox module itself
@pytest.mark.parametrize("parts", [("..",), (".",), ("",), ("a/b",), ("a\\b",), ("a\0",), ("ok", "..")])
def test_sandbox_refuses_names_that_are_not_names(tmp_path, parts):
    with pytest.raises(SandboxError):
        Sandbox(tmp_path).path(*parts)


def test_sandbox_root_may_not_be_a_link(tmp_path):
    (tmp_path / "real").mkdir()
    (tmp_path / "root").symlink_to(tmp_path / "real")
    with pytest.raises(SandboxError, match="symbolic link"):
        check_root(tmp_path / "root")
    with pytest.raises(SandboxError, match="symbolic link"):
        Sandbox(tmp_path / "root").path("a.txt")


def test_sandbox_root_may_not_be_a_file(tmp_path):
    (tmp_path / "root").write_text("x")
    with pytest.raises(SandboxError, match="not a folder"):
        check_root(tmp_path / "root")


def test_sandbox_open_does_not_follow_a_final_link(tmp_path):
    (tmp_path / "box").mkdir()
    (tmp_path / "target").write_text(SECRET)
    (tmp_path / "box" / "l").symlink_to(tmp_path / "target")
    box = Sandbox(tmp_path / "box")
    for mode in ("rb", "wb", "ab"):
        with pytest.raises(SandboxError):
            box.open(tmp_path / "box" / "l", mode)
    assert (tmp_path / "target").read_text() == SECRET


def test_sandbox_outside_path_is_refused(tmp_path):
    with pytest.raises(SandboxError, match="outside"):
        Sandbox(tmp_path / "box").inside(tmp_path / "elsewhere")


# ------------------------------------------------------------------ the planted root, end to end
def test_planted_sandbox_link_beside_the_report_is_refused_before_the_run(tmp_path, capsys):
    program = vplus_file(tmp_path, '.PROGRAM w()\n    ATTACH (5, 0) "DISK"\n    FOPENW (5) "x.txt"\n.END')
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    (tmp_path / "prog-files").symlink_to(elsewhere, target_is_directory=True)
    result = run_cli(capsys, "run", program, "--report", tmp_path / "r.json")
    assert result.status == 2
    assert "prog-files" in result.err and "symbolic link" in result.err
    assert not (tmp_path / "r.json").exists() and list(elsewhere.iterdir()) == []


def test_sandbox_beside_the_report_is_a_file(tmp_path, capsys):
    program = vplus_file(tmp_path, ".PROGRAM w()\n.END")
    (tmp_path / "prog-files").write_text("x")
    result = run_cli(capsys, "run", program, "--report", tmp_path / "r.json")
    assert result.status == 2 and "not a folder" in result.err


# ------------------------------------------------------------------ sockets: a closed network
NON_LOOPBACK = ["192.168.0.2", "10.0.0.9", "8.8.8.8", "172.16.0.1", "example.com", "169.254.1.1"]


def _socket_program(statement: str) -> str:
    return ("Module M\n    Public Sub Main()\n" + DECLARATIONS + "        Try\n            " + statement + "\n"
            "            Console.WriteLine(\"reached\")\n        Catch ex As Exception\n"
            "            Console.WriteLine(\"refused \" & CStr(ex.ErrorCode))\n        End Try\n"
            "    End Sub\nEnd Module\n")


@pytest.mark.parametrize("address", NON_LOOPBACK)
def test_tcp_connect_to_a_non_loopback_address_is_refused(address):
    system, thread = run_gpl(_socket_program(f'c = New TcpClient(New IPEndPoint("{address}", 80))'))
    assert thread.error is None, thread.error
    assert system.console.output.strip() == f"refused {codes.INVALID_NETWORK_ADDRESS[0]}"


@pytest.mark.parametrize("statement", [
    'u = New UdpClient()\n            u.Client.SendTo("x", 0, New IPEndPoint("192.168.1.1", 9))',
    'u = New UdpClient(New IPEndPoint("10.1.1.1", 0))',
    'l = New TcpListener(New IPEndPoint("192.168.0.1", 0))\n            l.Start()',
    'mb = New Modbus(New IPEndPoint("192.168.0.150", 502))',
], ids=["udp-sendto", "udp-bind", "listener-bind", "modbus"])
def test_other_non_loopback_uses_are_refused(statement):
    system, thread = run_gpl(_socket_program(statement))
    assert thread.error is None, thread.error
    assert system.console.output.strip() == f"refused {codes.INVALID_NETWORK_ADDRESS[0]}"


@pytest.mark.parametrize("address", ["127.0.0.1", "localhost", "127.0.0.2", ""])
def test_loopback_connect_still_works(address):
    server = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    server.bind(("127.0.0.1", 0))
    server.listen(1)
    port = server.getsockname()[1]
    try:
        system, thread = run_gpl(_socket_program(f'c = New TcpClient(New IPEndPoint("{address}", {port}))'))
    finally:
        server.close()
    assert thread.error is None, thread.error
    assert system.console.output.strip() == "reached"
