"""Scene files: TOML cell descriptions, validated by the schema in `schema.py` (docs/scene.md)."""

from __future__ import annotations

import sys
from pathlib import Path

from ..errors import SceneError
from ..resources import resource_root
from .schema import Scene, validate_scene

if sys.version_info >= (3, 11):
    import tomllib
else:  # Python 3.10: the same parser, as a package
    import tomli as tomllib


def load_scene(path: str | Path) -> dict:
    """Parse and validate a scene file: the TOML as a dict (SceneError on any problem)."""
    path = Path(path)
    try:
        with path.open("rb") as f:
            scene = tomllib.load(f)
    except FileNotFoundError:
        raise SceneError("no such scene file", file=str(path)) from None
    except tomllib.TOMLDecodeError as e:
        raise SceneError(f"not valid TOML: {e}", file=str(path)) from None
    validate_scene(scene, path)
    return scene


def resolve(path: str, scene_path: Path, key: str = "model") -> Path:
    """Model paths in a scene are relative to the scene file or to twin's bundled
    resources (models/ in the repository or in the installed package)."""
    for base in (Path(scene_path).parent, resource_root()):
        candidate = (base / path).resolve()
        if candidate.exists():
            return candidate
    raise SceneError(f"{key}: {path!r} not found next to the scene nor in {resource_root()}",
                     file=str(scene_path))


__all__ = ["Scene", "load_scene", "resolve", "validate_scene"]
