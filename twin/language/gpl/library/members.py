"""Small builders for members that are plain stored values.

The interpreter resolves members from the class (library/__init__.py's
``gpl_members``), so a read/write value must be a class-level property, not an
attribute set in ``__init__``."""

from __future__ import annotations

from typing import Any, Callable


def stored(attr: str, convert: Callable[[Any], Any] = lambda v: v, readonly: bool = False) -> property:
    """A property over ``self.<attr>``; assignments go through `convert`."""

    def get(self):
        return getattr(self, attr)

    def put(self, value) -> None:
        setattr(self, attr, convert(value))

    return property(get) if readonly else property(get, put)
