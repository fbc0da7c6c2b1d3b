"""The designed model written back (docs/design.md §5): the designed bodies' mass, COM and
inertia into a copy of the scene file (``[[body]]`` tables) and, for bodies that came from a
URDF, into a copy of the URDF's ``<inertial>`` elements. Everything else in the files is
kept as written; the values are written with 17 significant digits, so a reloaded model has
the designed dynamics to round-off."""

from __future__ import annotations

import json
import os
import re
import xml.etree.ElementTree as ET
from pathlib import Path
from typing import Any

import numpy as np

from .._core import Scene
from ..errors import InvalidInputError, SceneError
from ..scenes import resolve_scene_path

_INERTIAL_KEYS = ("mass", "com", "inertia", "inertia_diag")


def _toml():
    try:
        import tomllib
    except ImportError:  # pragma: no cover - Python < 3.11
        try:
            import tomli as tomllib
        except ImportError as exc:
            raise InvalidInputError(
                "write_scene: reading the scene needs Python >= 3.11 or the tomli package"
            ) from exc
    return tomllib


def _num(x: float) -> str:
    return repr(float(x))


def _body_lines(body: Any) -> list[str]:
    i = np.asarray(body.inertia, float)
    rows = ", ".join("[" + ", ".join(_num(v) for v in r) + "]" for r in i)
    return [
        f"mass = {_num(body.mass)}",
        "com = [" + ", ".join(_num(v) for v in body.com) + "]",
        f"inertia = [{rows}]",
    ]


def _drop_key(lines: list[str], start: int) -> int:
    """The index after the key's value that begins on line ``start`` (arrays may span lines)."""
    depth, k = 0, start
    while k < len(lines):
        text = lines[k].split("#", 1)[0]
        depth += text.count("[") - text.count("]")
        k += 1
        if depth <= 0:
            break
    return k


def _edit_sections(lines: list[str], names: list[str], bodies: dict[str, Any]) -> list[str]:
    """Replaces the inertial keys of each ``[[body]]`` table named in ``bodies``; ``names``:
    the tables' names in file order."""
    out, k, index = [], 0, -1
    header = re.compile(r"^\s*\[")
    key = re.compile(r"^\s*(" + "|".join(_INERTIAL_KEYS) + r")\s*=")
    current = None
    pending: list[str] = []
    while k < len(lines):
        line = lines[k]
        if header.match(line):
            out.extend(pending)
            pending = []
            current = None
            if re.match(r"^\s*\[\[\s*body\s*\]\]", line):
                index += 1
                name = names[index]
                if name in bodies:
                    current = name
                    pending = _body_lines(bodies[name])
            out.append(line)
            k += 1
            continue
        if current is not None and key.match(line):
            k = _drop_key(lines, k)
            continue
        out.append(line)
        k += 1
    out.extend(pending)
    return out


def write_urdf(bodies: dict[str, Any], source: str | os.PathLike, path: str | os.PathLike) -> Path:
    """A copy of the URDF ``source`` with the ``<inertial>`` of each link named in ``bodies``
    (name → :class:`RigidBody`, in the link's frame) replaced: origin at the COM, no
    rotation, the full inertia about the COM."""
    source, path = Path(source), Path(path)
    try:
        tree = ET.parse(source)
    except (OSError, ET.ParseError) as exc:
        raise InvalidInputError(f"source: expected a readable URDF file, got '{source}' ({exc})") from exc
    links = {ln.get("name"): ln for ln in tree.getroot().iter("link")}
    missing = sorted(set(bodies) - set(links))
    if missing:
        raise InvalidInputError(f"bodies: expected links of '{source}', got {missing} (links: {sorted(links)})")
    for name, body in bodies.items():
        link = links[name]
        for old in link.findall("inertial"):
            link.remove(old)
        inertial = ET.Element("inertial")
        ET.SubElement(inertial, "origin", xyz=" ".join(_num(v) for v in body.com), rpy="0 0 0")
        ET.SubElement(inertial, "mass", value=_num(body.mass))
        i = np.asarray(body.inertia, float)
        ET.SubElement(
            inertial,
            "inertia",
            ixx=_num(i[0, 0]),
            ixy=_num(i[0, 1]),
            ixz=_num(i[0, 2]),
            iyy=_num(i[1, 1]),
            iyz=_num(i[1, 2]),
            izz=_num(i[2, 2]),
        )
        link.insert(0, inertial)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        tree.write(path, encoding="utf-8", xml_declaration=True)
    except OSError as exc:
        raise InvalidInputError(f"path: expected a writable file path, got '{path}' ({exc})") from None
    return path


def write_scene(bodies: dict[str, Any], source: str | os.PathLike, path: str | os.PathLike) -> Path:
    """A copy of the scene file ``source`` with the designed ``bodies`` (name →
    :class:`RigidBody`): a body of a ``[[body]]`` table gets its ``mass``, ``com`` and full
    ``inertia`` replaced; a body from the scene's ``urdf`` is written into a copy of that URDF
    beside ``path`` (``<stem>.urdf``), which the new scene then loads. ``source`` may also
    be a :class:`Scene` (one built in Python, say): its model with the designed bodies is
    written whole (:meth:`Scene.write`). Returns ``path``."""
    if isinstance(source, Scene):
        return _write_designed_scene(bodies, source, Path(path))
    source, path = resolve_scene_path(source), Path(path)
    try:
        text = source.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise SceneError(
            f"source: expected a bundled scene name or a readable scene file, got '{source}' ({exc})"
        ) from None
    try:
        data = _toml().loads(text)
    except ValueError as exc:
        raise SceneError(f"{source}: not TOML ({exc})") from exc
    names = [str(b.get("name")) for b in data.get("body", [])]
    in_toml = {n: b for n, b in bodies.items() if n in names}
    rest = {n: b for n, b in bodies.items() if n not in names}
    lines = _edit_sections(text.splitlines(), names, in_toml)
    if rest and "urdf" not in data:
        raise InvalidInputError(
            f"bodies: {sorted(rest)} are neither [[body]] tables of '{source}' nor from a urdf"
        )
    if "urdf" in data:
        urdf = (source.parent / str(data["urdf"])).resolve()
        if rest:
            urdf = path.with_suffix(".urdf")
            write_urdf(rest, (source.parent / str(data["urdf"])).resolve(), urdf)
        # The scene names its URDF relative to itself: the copy's path from where it is.
        rel = Path(os.path.relpath(urdf, path.resolve().parent)).as_posix()
        pattern = re.compile(r"^\s*urdf\s*=")
        lines = [f"urdf = {json.dumps(rel)}" if pattern.match(ln) else ln for ln in lines]
    _write_text(path, "\n".join(lines) + "\n")
    return path


def _write_designed_scene(bodies: dict[str, Any], scene: Scene, path: Path) -> Path:
    """``scene`` with the designed ``bodies`` (by name), written as a whole scene file."""
    model = scene.model
    unknown = sorted(n for n in bodies if n not in model.body_names)
    if unknown:
        raise InvalidInputError(f"bodies: {unknown} are not bodies of the scene's model "
                                f"(bodies: {', '.join(model.body_names)})")
    for name, body in bodies.items():
        model = model.with_body(name, body)
    _write_text(path, scene.replace(model=model).to_toml())
    return path


def _write_text(path: Path, text: str) -> None:
    """Writes ``text`` to ``path``, creating its directory (as ``Shape.write_stl`` does); a
    path that cannot be written is an ``InvalidInputError`` naming it."""
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text, encoding="utf-8")
    except OSError as exc:
        raise InvalidInputError(f"path: expected a writable file path, got '{path}' ({exc})") from None
