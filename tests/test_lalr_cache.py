"""The languages' LALR parsers are built once and loaded from the user's cache
(twin/language/lalr.py): same parses, a damaged or unwritable cache is no error."""

from __future__ import annotations

import os
from importlib.resources import files

import pytest

from twin.language import lalr

GRAMMAR = files("twin.language.vplus").joinpath("vplus.lark").read_text()
SOURCE = '.PROGRAM demo()\n    FOR i = 1 TO 3\n        TYPE "part ", i\n    END\n.END\n'


@pytest.fixture
def cache(tmp_path, monkeypatch):
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    return tmp_path / "twin"


def test_the_parser_is_saved_then_loaded_and_parses_the_same(cache):
    built = lalr.lalr_parser(GRAMMAR, "vplus")
    saved = list(cache.glob("vplus-*.lark"))
    assert len(saved) == 1
    loaded = lalr.lalr_parser(GRAMMAR, "vplus")
    assert loaded is not built
    assert loaded.parse(SOURCE) == built.parse(SOURCE)
    assert not list(cache.glob(".vplus-*")), "no temporary file left behind"


def test_an_edited_grammar_gets_its_own_cache_entry(cache):
    lalr.lalr_parser(GRAMMAR, "vplus")
    lalr.lalr_parser(GRAMMAR + "\n// edited\n", "vplus")
    assert len(list(cache.glob("vplus-*.lark"))) == 2


def test_a_damaged_cache_file_is_rebuilt(cache):
    lalr.lalr_parser(GRAMMAR, "vplus")
    (path,) = cache.glob("vplus-*.lark")
    path.write_bytes(b"not a parser")
    parser = lalr.lalr_parser(GRAMMAR, "vplus")
    assert parser.parse(SOURCE) is not None
    assert path.read_bytes() != b"not a parser"


def test_an_unwritable_cache_directory_is_skipped(tmp_path, monkeypatch):
    blocker = tmp_path / "file"
    blocker.write_text("a file where the cache directory would be")
    monkeypatch.setenv("XDG_CACHE_HOME", str(blocker))
    assert lalr.lalr_parser(GRAMMAR, "vplus").parse(SOURCE) is not None


def test_a_cache_that_cannot_be_written_whole_leaves_no_file(tmp_path):
    """A full disk, made real with a file-size limit: the run goes on without the cache and
    leaves neither a cache file nor a half-written temporary one."""
    import subprocess
    import sys

    script = (
        "import os, resource, signal\n"
        "signal.signal(signal.SIGXFSZ, signal.SIG_IGN)\n"
        "resource.setrlimit(resource.RLIMIT_FSIZE, (4096, 4096))\n"
        "from importlib.resources import files\n"
        "from twin.language import lalr\n"
        "grammar = files('twin.language.vplus').joinpath('vplus.lark').read_text()\n"
        f"assert lalr.lalr_parser(grammar, 'vplus').parse({SOURCE!r}) is not None\n"
        "print('ok')\n"
    )
    env = {**os.environ, "XDG_CACHE_HOME": str(tmp_path)}
    out = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, env=env, check=False)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "ok"
    assert list((tmp_path / "twin").iterdir()) == []
