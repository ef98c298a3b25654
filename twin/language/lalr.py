"""The LALR parsers of the two languages, built once per grammar and kept in a cache.

Building the V+ grammar's LALR tables is most of a one-line program's load time (about
0.3 s; lark's analysis is pure Python).  The built parser is saved with lark's own
`Lark.save` under the user's cache directory ($XDG_CACHE_HOME or ~/.cache, `twin/`),
keyed by a hash of the grammar text, the options, lark's and Python's versions, so an
edited grammar or an upgraded lark never loads a stale one.  The file is written to a
temporary name and renamed, so a run reading it while another writes never sees half a
file; a cache that cannot be read or written is skipped (the parser is then built).
"""

from __future__ import annotations

import hashlib
import os
import sys
import tempfile
from pathlib import Path

import lark
from lark import Lark

OPTIONS = {"parser": "lalr", "lexer": "contextual", "propagate_positions": True, "maybe_placeholders": True}


def cache_dir() -> Path:
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return Path(base) / "twin"


def lalr_parser(grammar: str, name: str) -> Lark:
    """The parser of `grammar` (`name` names its cache file: "vplus", "gpl")."""
    key = hashlib.sha256(repr((grammar, sorted(OPTIONS.items()), lark.__version__,
                               sys.version_info[:2])).encode()).hexdigest()[:16]
    path = cache_dir() / f"{name}-{key}.lark"
    try:
        with open(path, "rb") as f:
            return Lark.load(f)
    except Exception:  # absent, unreadable or damaged: build it
        pass
    parser = Lark(grammar, **OPTIONS)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        with tempfile.NamedTemporaryFile("wb", dir=path.parent, prefix=f".{name}-", delete=False) as f:
            try:
                parser.save(f)
            except BaseException:  # a full disk: no half-written file left behind
                os.unlink(f.name)
                raise
        os.replace(f.name, path)
    except OSError:  # a read-only or full home: run without the cache
        pass
    return parser
