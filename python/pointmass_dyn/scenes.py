"""Scene files: the bundled ones and loading from a path."""

from __future__ import annotations

import os
from pathlib import Path

from ._core import Scene
from .errors import SceneError

_BUNDLED = Path(__file__).with_name("scenes")


def builtin_scenes() -> dict[str, Path]:
    """Names of the bundled scenes and their files."""
    return {p.stem: p for p in sorted(_BUNDLED.glob("*.toml"))}


def resolve_scene_path(path_or_name: str | os.PathLike) -> Path:
    """A bundled scene's file for a bare name, otherwise the path itself."""
    text = os.fspath(path_or_name)
    bundled = builtin_scenes()
    if text in bundled:
        return bundled[text]
    path = Path(text)
    if path.is_file():
        return path
    raise SceneError(
        f"{text}: no such scene file, and not a bundled scene "
        f"(bundled: {', '.join(bundled) or 'none'})"
    )


def load_scene(path_or_name: str | os.PathLike) -> Scene:
    """Loads a scene from a TOML file, or a bundled scene by name (see ``builtin_scenes()``)."""
    path = resolve_scene_path(path_or_name)
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise SceneError(f"{path}: cannot read the scene file: {exc}") from exc
    return Scene.from_toml(text, str(path))
