"""Scene files: TOML cell descriptions (see scenes/scara_pick.toml for the layout)."""

from __future__ import annotations

import sys
from pathlib import Path

from ..resources import resource_root

if sys.version_info >= (3, 11):
    import tomllib
else:  # Python 3.10: the same parser, as a package
    import tomli as tomllib

REQUIRED = ("robot", "gripper", "table", "feeder", "conveyor", "bin", "part", "regions", "locations")


def load_scene(path: str | Path) -> dict:
    """Parse a scene file; raise ValueError naming what is missing."""
    path = Path(path)
    with path.open("rb") as f:
        scene = tomllib.load(f)
    missing = [k for k in REQUIRED if k not in scene]
    if missing:
        raise ValueError(f"{path}: scene lacks {', '.join(missing)}")
    for name in ("start", "pick", "place"):
        loc = scene["locations"].get(name)
        if loc is None or len(loc) != 6:
            raise ValueError(f"{path}: location {name!r} must be [x, y, z, yaw, pitch, roll]")
    return scene


def resolve(path: str, scene_path: Path) -> Path:
    """Model paths in a scene are relative to the scene file or to twin's bundled
    resources (models/ in the repository or in the installed package)."""
    for base in (Path(scene_path).parent, resource_root()):
        candidate = (base / path).resolve()
        if candidate.exists():
            return candidate
    raise FileNotFoundError(f"{path}: not found next to {scene_path} nor in {resource_root()}")
