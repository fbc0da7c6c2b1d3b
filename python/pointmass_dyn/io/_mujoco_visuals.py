"""The geoms of a compiled ``mujoco.MjModel`` as ``Model.visuals`` (docs/visualisation.md):
spheres, capsules, ellipsoids, cylinders and boxes as they are, meshes by their file.

MuJoCo moves a mesh's vertices into the mesh's inertial frame when it compiles the model
(``mesh_vert = Rᵀ(v − mesh_pos)``, R from ``mesh_quat``) and puts that frame into the geom's
pose; the file's frame is therefore the geom pose times the inverse of (mesh_pos, mesh_quat).
Geoms of the world body (floors, fixed scenery) are not bodies of ours and are left out, as
are geoms in groups 3 and above (MuJoCo hides those by default: collision shapes by
convention) and planes, height fields and signed-distance fields.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from .._helpers import rotation_of_wxyz


def _mesh_file(m, k: int, mesh_dirs) -> tuple[str, str | None]:
    """(uri, path or None) of mesh ``k``: its file as the MJCF names it, looked for as given
    and in each of ``mesh_dirs`` (an inline mesh has no file)."""
    adr = int(m.mesh_pathadr[k]) if hasattr(m, "mesh_pathadr") else -1
    if adr < 0:
        return f"<inline mesh {k}>", None
    raw = bytes(m.paths[adr:]).split(b"\0", 1)[0].decode("utf-8", "replace")
    for d in [None, *mesh_dirs]:
        p = Path(raw) if d is None else Path(d) / raw
        if p.is_file():
            return raw, str(p.resolve())
    return raw, None


def geom_visuals(m, body_of, anchor_of, mesh_dirs=()) -> tuple[list[dict], list[str]]:
    """``Model.set_visuals`` dicts of ``m``'s geoms: ``body_of[b]`` is our body of MuJoCo body
    ``b``, ``anchor_of[b]`` that body's origin in MuJoCo's body frame. Also returns the mesh
    files not found."""
    import mujoco

    G = mujoco.mjtGeom
    out, missing = [], []
    for g in range(m.ngeom):
        b = int(m.geom_bodyid[g])
        kind, size = int(m.geom_type[g]), np.asarray(m.geom_size[g], dtype=float)
        if b == 0 or int(m.geom_group[g]) >= 3 or body_of.get(b, -1) < 0:
            continue
        rot = rotation_of_wxyz(np.asarray(m.geom_quat[g], dtype=float))
        pos = np.asarray(m.geom_pos[g], dtype=float)
        v: dict = {}
        if kind == G.mjGEOM_SPHERE:
            v = {"kind": "sphere", "radius": size[0]}
        elif kind == G.mjGEOM_CAPSULE:
            v = {"kind": "capsule", "radius": size[0], "length": 2 * size[1]}
        elif kind == G.mjGEOM_CYLINDER:
            v = {"kind": "cylinder", "radius": size[0], "length": 2 * size[1]}
        elif kind == G.mjGEOM_ELLIPSOID:
            v = {"kind": "ellipsoid", "radii": size.tolist()}
        elif kind == G.mjGEOM_BOX:
            v = {"kind": "box", "size": (2 * size).tolist()}
        elif kind == G.mjGEOM_MESH and int(m.geom_dataid[g]) >= 0:
            k = int(m.geom_dataid[g])
            uri, path = _mesh_file(m, k, mesh_dirs)
            if path is None:
                missing.append(uri)
            r_mesh = rotation_of_wxyz(np.asarray(m.mesh_quat[k], dtype=float))
            rot = rot @ r_mesh.T
            pos = pos - rot @ np.asarray(m.mesh_pos[k], dtype=float)
            v = {"kind": "mesh", "uri": uri, "path": path,
                 "scale": np.asarray(m.mesh_scale[k], dtype=float).tolist()}
        else:
            continue
        matid = int(m.geom_matid[g])
        rgba = np.asarray(m.mat_rgba[matid] if matid >= 0 else m.geom_rgba[g], dtype=float)
        v.update(body=body_of[b], rotation=rot.tolist(),
                 translation=(pos - anchor_of[b]).tolist(),
                 rgba=np.clip(rgba, 0, 1).tolist())
        out.append(v)
    return out, missing


def model_name(m) -> str:
    """``<mujoco model="...">``: the first of MuJoCo's names."""
    return bytes(m.names).split(b"\0", 1)[0].decode("utf-8", "replace")


def mesh_dirs_of(mesh_dirs) -> list[str]:
    if mesh_dirs is None:
        return []
    if isinstance(mesh_dirs, (str, os.PathLike)):
        return [os.fspath(mesh_dirs)]
    return [os.fspath(d) for d in mesh_dirs]
