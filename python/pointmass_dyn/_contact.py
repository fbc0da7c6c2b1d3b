"""Ground contact and joint ranges: the effects that make a robot stand (docs/contact.md).

=====================  ===========  ================================================
factory                family       law
=====================  ===========  ================================================
``GroundContact``      contact      Hunt–Crossley ``max(0, k δⁿ + c δⁿ δ̇)`` along the
                                    plane's normal, regularised Coulomb friction
``JointLimit``         limits       one-sided spring–damper outside ``[lower, upper]``
=====================  ===========  ================================================

:func:`urdf_contact_points` takes contact points (sphere centres and radii) from a URDF's
``<collision>`` elements (spheres, else the bounds of its meshes and shapes); :func:`contact_forces` evaluates a contact's points, penetrations
and forces along a trajectory (what ``simulate(..., contact=True)`` records);
:func:`torque_saturation` says where limited torques were at their limit (a result's
``.saturated``).
"""

from __future__ import annotations

import os
import warnings
import xml.etree.ElementTree as ET
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from . import _core
from ._collision import MalformedGeometry, link_sphere
from ._core import Effect, Scene
from .errors import InvalidInputError, UrdfWarning


def GroundContact(
    points: Sequence[Any],
    *,
    normal: Sequence[float] = (0.0, 0.0, 1.0),
    height: float = 0.0,
    stiffness: float | None = None,
    exponent: float = 1.5,
    damping: float | None = None,
    friction: float,
    v_eps: float = 1e-3,
    name: str | None = None,
) -> Effect:
    """Compliant contact of body points with the plane ``normal · x = height``, family
    ``contact``.

    ``points``: ``[(body, [x, y, z]), …]`` (a body name or index, a point in its frame), or
    ``(body, [x, y, z], radius)`` for a sphere centred there (it touches the plane when its
    centre is ``radius`` above it). With the penetration ``δ = height + radius − normal · p``
    and its rate ``δ̇``, a point below the plane feels the Hunt–Crossley normal force
    ``F_n = max(0, k δⁿ + c δⁿ δ̇)`` (``stiffness`` k > 0, ``exponent`` n ≥ 1, 1.5 for Hertz;
    ``damping`` c ≥ 0; it never pulls) and regularised Coulomb friction
    ``−μ F_n tanh(|v_t| / v_eps) v_t / |v_t|`` on its tangential velocity (``friction``
    μ ≥ 0). The elastic part's potential ``k δⁿ⁺¹ / (n + 1)`` counts in ``energies``;
    damping and friction only dissipate. Its derivatives are analytic (Radau, ``auto``).

    ``stiffness=None`` and ``damping=None`` take defaults from the robot's weight when the
    effect joins a scene: with the model's total mass ``M`` shared by the ``N`` points,
    ``k = M g₀ / (N δ₀ⁿ)`` (each point sinks ``δ₀`` = 1 mm at rest, ``g₀`` = 9.81 m/s²) and
    ``c`` the critical damping of the contact mode at that sink. The scene's effects hold
    the values it runs with (``scene.effects[i].contact_parameters``, their repr). How to
    choose k and c: docs/contact.md §1."""
    return Effect(
        "ground_contact", points=points, normal=normal, height=height, stiffness=stiffness,
        exponent=exponent, damping=damping, friction=friction, v_eps=v_eps, name=name,
    )


def JointLimit(
    joints: Any = None,
    lower: Any = None,
    upper: Any = None,
    *,
    stiffness: Any,
    damping: Any,
    name: str | None = None,
) -> Effect:
    """Compliant joint ranges on revolute and prismatic joints, family ``limits``: below
    ``lower``, ``τ = max(0, k (lower − q) − c q̇)``; above ``upper``,
    ``τ = −max(0, k (q − upper) + c q̇)``; nothing inside. ``joints=None``: every revolute
    and prismatic joint. ``lower``/``upper``: one number or one per joint (±inf: no bound);
    ``None`` takes the model's own (``Model.joint_limits()``: URDF ``<limit>``, MJCF
    ``range``) when the scene is built. Potential ``½ k δ²`` (in ``energies``)."""
    return Effect(
        "joint_limit", joints=joints, lower=lower, upper=upper, stiffness=stiffness,
        damping=damping, name=name,
    )


def urdf_contact_points(
    urdf: str | os.PathLike, links: Sequence[str], *, package_dirs: Any = None
) -> list[tuple[str, list[float], float]]:
    """Contact points ``(link, [x, y, z], radius)`` for :func:`GroundContact`, from the
    named links of a URDF file, in each link's frame:

    * every ``<collision>`` ``<sphere>`` gives its centre (its ``<origin>``) and radius;
    * a link without one (a mesh foot, say) gives one sphere from the bounding box of its
      ``<collision>`` geometry (meshes, boxes, cylinders, with their ``<origin>`` and
      ``scale``), or of its ``<visual>`` geometry when the collision's cannot be read: the
      box's centre and half its smallest side, the largest sphere inside the box (exact
      for a spherical foot; a flat foot's sole is its bottom);
    * a link without geometry gives its origin with radius 0 (a point).

    Meshes are found as ``Model.from_urdf`` finds them (``package://`` in ``package_dirs``
    and the file's folders). STL and OBJ are read with NumPy; other formats (``.dae``) need
    the extra ``pointmass-dyn[mesh]``: a link whose geometry cannot be read falls back to
    its visual geometry, then to its origin with radius 0, with a :class:`UrdfWarning`
    naming the files and why. Bodies of ``Model.from_urdf`` carry the link names, so the
    points can be used as they are."""
    path = os.fspath(urdf)
    try:
        root = ET.parse(path).getroot()
    except (OSError, ET.ParseError) as e:
        raise InvalidInputError(f"urdf: a readable URDF file; got {path!r} ({e})") from None
    if isinstance(links, str):
        links = [links]
    by_name = {link.get("name"): link for link in root.findall("link")}
    out: list[tuple[str, list[float], float]] = []
    for k, name in enumerate(links):
        link = by_name.get(name)
        if link is None:
            raise InvalidInputError(
                f"links[{k}]: the name of a link of {path} ({', '.join(sorted(map(str, by_name)))}); "
                f"got {name!r}"
            )
        spheres = []
        for col in link.findall("collision"):
            sphere = col.find("geometry/sphere")
            if sphere is None:
                continue
            origin = col.find("origin")
            xyz = [0.0, 0.0, 0.0]
            try:
                if origin is not None and origin.get("xyz"):
                    xyz = [float(x) for x in origin.get("xyz", "").split()]
                radius = float(sphere.get("radius", "0"))
            except ValueError:
                raise InvalidInputError(
                    f"urdf: link '{name}' of {path}: expected a <collision> <origin xyz> of three "
                    f"numbers and a <sphere radius> number, got xyz={origin.get('xyz') if origin is not None else None!r}, "
                    f"radius={sphere.get('radius')!r}"
                ) from None
            if len(xyz) != 3:
                raise InvalidInputError(
                    f"urdf: link '{name}' of {path}: expected <origin xyz> of three numbers, got {xyz}"
                )
            # float() reads "nan" and "inf": a sphere no contact can use.
            if not (np.all(np.isfinite(xyz)) and np.isfinite(radius) and radius >= 0):
                raise InvalidInputError(
                    f"urdf: link '{name}' of {path}: expected a finite <origin xyz> and a finite "
                    f"<sphere radius> >= 0, got xyz={xyz}, radius={radius}"
                )
            spheres.append((name, xyz, radius))
        if not spheres:
            spheres = [_bounding_sphere(link, name, path, package_dirs)]
        out.extend(spheres)
    return out


def _bounding_sphere(
    link: ET.Element, name: str, path: str, package_dirs: Any
) -> tuple[str, list[float], float]:
    """A link's sphere from its geometry's bounds (``_collision.link_sphere``), else its
    origin with radius 0, warned about when the link has geometry that could not be read."""
    try:
        found = link_sphere(link, os.path.dirname(os.path.abspath(path)), package_dirs)
    except MalformedGeometry as e:
        raise InvalidInputError(f"urdf: link '{name}' of {path}: {e}") from None
    if isinstance(found, tuple):
        return (name, *found)
    if found is not None:
        warnings.warn(
            f"urdf_contact_points: link '{name}' of {path}: its geometry could not be read "
            f"({found}); its contact point is the link's origin with radius 0",
            UrdfWarning,
            stacklevel=3,
        )
    return (name, [0.0, 0.0, 0.0], 0.0)


@dataclass
class ContactForces:
    """One ground contact along a trajectory: per output time and point, the point's world
    ``position`` (N, P, 3), its ``penetration`` (N, P; negative above the plane), the
    ``normal_force`` (N, P) and the whole ``force`` on it (N, P, 3, world; normal plus
    friction). Drawable: ``position`` and ``force`` are plain arrays."""

    name: str
    position: np.ndarray
    penetration: np.ndarray
    normal_force: np.ndarray
    force: np.ndarray

    @property
    def total_force(self) -> np.ndarray:
        """Sum over the points (N, 3)."""
        return self.force.sum(axis=1)


def contact_forces(scene: Scene, result: Any) -> dict[str, ContactForces]:
    """Every ground contact of ``scene`` evaluated at the output states of ``result`` (its
    ``q`` and ``v``), by effect name. The contact force is a function of the state, so these
    are exact at the output times."""
    if np.iscomplexobj(result.q) or np.iscomplexobj(result.v):  # NumPy would drop the imaginary part
        raise InvalidInputError("result: expected real q and v, got complex values")
    try:
        q = np.atleast_2d(np.asarray(result.q, dtype=float))
        v = np.atleast_2d(np.asarray(result.v, dtype=float))
    except (TypeError, ValueError):  # NumPy's refusal of strings and ragged lists
        raise InvalidInputError(
            f"result: expected a result with numeric q (N, nq) and v (N, nv), got q = "
            f"{result.q!r:.60}, v = {result.v!r:.60}"
        ) from None
    model = scene.model
    out: dict[str, ContactForces] = {}
    for e in scene.effects:
        if e.kind == "contact":
            d = e.contact_state(model, q, v)
            out[e.name] = ContactForces(name=e.name, **d)
    return out


def torque_saturation(scene: Scene, result: Any, disable: Any = None) -> dict | None:
    """Where each torque effect of ``scene`` with a ``limit`` was at it along ``result``:
    (N, nv) booleans at the output times, by effect name (False on the speeds it does not
    drive); None when no enabled torque has a limit. ``disable`` as :func:`simulate`'s."""
    model = scene.model
    limits = {
        e.name: e.torque_limit_per_speed(model)
        for e in scene.effects
        if e.torque_limit is not None
    }
    if not limits:
        return None
    _, forces = _core.scene_along(scene, result.t, result.q, result.v, disable,
                                   accelerations=False, forces=True)
    out = {name: np.abs(forces[name]) >= lim * (1 - 1e-12)
           for name, lim in limits.items() if name in forces}
    return out or None
