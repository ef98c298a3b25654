"""Scene files: TOML cell descriptions, validated by the schema in `schema.py` (docs/scene.md)."""

from __future__ import annotations

import copy
import sys
from pathlib import Path

import mujoco

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
    if not path.exists():
        raise SceneError("no such scene file", file=str(path))
    if not path.is_file():  # a folder, or a FIFO that would wait for a writer forever
        raise SceneError("not a file (a scene is a TOML file)", file=str(path))
    try:
        # utf-8-sig: a byte order mark, as some editors write one, is not part of the TOML
        scene = tomllib.loads(path.read_bytes().decode("utf-8-sig"))
    except UnicodeDecodeError as e:
        raise SceneError(f"not valid TOML: not UTF-8 text (byte {e.start})", file=str(path)) from None
    except tomllib.TOMLDecodeError as e:
        raise SceneError(f"not valid TOML: {e}", file=str(path)) from None
    except OSError as e:
        raise SceneError(f"cannot read it: {e.strerror}", file=str(path)) from None
    validate_scene(scene, path)
    return scene


def apply_overrides(scene: dict, overrides: dict[str, object], path: str | Path) -> dict:
    """A copy of `scene` with values set by dotted key paths, as `twin sweep --param` gives
    them: ``controller.monitor_speed``, ``conveyor.infeed.speed`` (an array of tables is
    addressed by an element's ``name`` or its 0-based index).  A missing table is created;
    what the key names is then checked by the schema like any scene key."""
    scene = copy.deepcopy(scene)
    for key, value in overrides.items():
        *tables, last = key.split(".")
        node: object = scene
        for i, part in enumerate(tables):
            if isinstance(node, list):
                node = _element(node, part, ".".join(tables[:i + 1]), path)
            elif isinstance(node, dict):
                node = node.setdefault(part, {})
            else:
                raise SceneError(f"{key}: {'.'.join(tables[:i])} is a value, not a table", file=str(path))
        if isinstance(node, list):
            raise SceneError(f"{key}: name an element of {'.'.join(tables)} (its name or index)", file=str(path))
        if not isinstance(node, dict):
            raise SceneError(f"{key}: {'.'.join(tables)} is a value, not a table", file=str(path))
        node[last] = value
    return scene


def _element(items: list, part: str, where: str, path: str | Path) -> dict:
    for item in items:
        if isinstance(item, dict) and item.get("name") == part:
            return item
    if part.isdigit() and int(part) < len(items):
        return items[int(part)]
    names = [str(item.get("name")) for item in items if isinstance(item, dict) and "name" in item]
    raise SceneError(f"{where}: no element named {part!r} (names: {', '.join(names) or 'none'}; "
                     f"or an index below {len(items)})", file=str(path))


def resolve(path: str, scene_path: Path, key: str = "model") -> Path:
    """Model paths in a scene are relative to the scene file or to twin's bundled
    resources (models/ in the repository or in the installed package)."""
    for base in (Path(scene_path).parent, resource_root()):
        candidate = (base / path).resolve()
        if candidate.is_file():
            return candidate
        if candidate.exists():
            raise SceneError(f"{key}: {path!r} is not a file", file=str(scene_path))
    raise SceneError(f"{key}: {path!r} not found next to the scene nor in {resource_root()}",
                     file=str(scene_path))


def load_model(path: str, scene_path: Path, key: str) -> mujoco.MjSpec:
    """The MuJoCo model file (MJCF or URDF) a scene names at `key`, as a spec."""
    found = resolve(path, scene_path, key)
    try:
        return mujoco.MjSpec.from_file(str(found))
    except ValueError as e:  # MuJoCo's own parse message
        raise SceneError(f"{key}: {path!r} is not a MuJoCo model ({str(e).strip().splitlines()[0]})",
                         file=str(scene_path)) from None


__all__ = ["Scene", "apply_overrides", "load_model", "load_scene", "resolve", "validate_scene"]
