"""The JSON Schemas of twin's file formats, published in docs/ci.md:

* ``report.schema.json``: the placement report (`twin run --report`, twin/report.py);
* ``expect.schema.json``: expectations (`twin check --expect`, twin/check.py), as the
  TOML file reads when converted to JSON.

`twin check` validates with its own checks (clear, located messages); the schemas are for
other tools (editors, CI dashboards) and the test suite keeps them in step with both.
"""

from __future__ import annotations

import json
from importlib.resources import files

__all__ = ["load_schema", "SCHEMAS"]

SCHEMAS = ("report", "expect")


def load_schema(name: str) -> dict:
    """The schema 'report' or 'expect' as a dict."""
    if name not in SCHEMAS:
        raise ValueError(f"no schema {name!r}; there are {', '.join(SCHEMAS)}")
    return json.loads(files(__package__).joinpath(f"{name}.schema.json").read_text(encoding="utf-8"))
