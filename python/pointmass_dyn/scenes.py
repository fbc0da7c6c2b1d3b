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


def _shown(text: str) -> str:
    """A path as shown in messages: shortened in the middle if longer than 200 characters."""
    if len(text) <= 200:
        return text
    return f"{text[:100]}…{text[-90:]} (a path of {len(text)} characters)"


def resolve_scene_path(path_or_name: str | os.PathLike) -> Path:
    """A bundled scene's file for a bare name, otherwise the path itself (not checked: a path
    that cannot be read is reported by ``load_scene``)."""
    try:
        text = os.fspath(path_or_name)
    except TypeError:
        raise TypeError(
            f"path_or_name: expected a str or os.PathLike, got {type(path_or_name).__name__}"
        ) from None
    if isinstance(text, bytes):
        raise TypeError("path_or_name: expected a str or os.PathLike, got bytes")
    bundled = builtin_scenes()
    if text in bundled:
        return bundled[text]
    return Path(text)


def load_scene(path_or_name: str | os.PathLike) -> Scene:
    """Loads a scene from a TOML file, or a bundled scene by name (see ``builtin_scenes()``).

    Only a regular file of at most 128 MiB is read (a FIFO, a device or a directory is refused
    with ``SceneError`` before it is opened)."""
    path = resolve_scene_path(path_or_name)
    try:
        os.lstat(path)
    except FileNotFoundError:
        bundled = builtin_scenes()
        raise SceneError(
            f"{_shown(str(path))}: no such scene file, and not a bundled scene "
            f"(bundled: {', '.join(bundled) or 'none'})"
        ) from None
    except (OSError, ValueError):
        pass  # reported by the reader, with the path and the reason
    return Scene.from_file(path)
