"""Scene files: TOML cell descriptions, validated by the schema in `schema.py` (docs/scene.md)."""

from __future__ import annotations

import tomllib
from pathlib import Path

from ..errors import SceneError
from .schema import Scene, validate_scene

REPO_ROOT = Path(__file__).resolve().parents[2]


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
    """Model paths in a scene are relative to the scene file or to the repository."""
    for base in (Path(scene_path).parent, REPO_ROOT):
        candidate = (base / path).resolve()
        if candidate.exists():
            return candidate
    raise SceneError(f"{key}: {path!r} not found next to the scene nor in {REPO_ROOT}",
                     file=str(scene_path))


__all__ = ["Scene", "load_scene", "resolve", "validate_scene"]
