"""The strength of designed links inside a design (docs/design.md §4a): each strength-checked
link's stress rows as a quantity of the program (``limits={"safety": s}``: every sample,
section and corner at most the allowable stress over ``s``), the re-analysed safety factors
of the result, and an infeasible request named by link and by how much."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import InfeasibleDesignError, InvalidInputError
from ._strength import (
    LinkStrength,
    Member,
    analyse,
    check_sections,
    link_pins,
    members,
    stress_rows,
    with_sections,
)

PREFIX = "safety:"


@dataclass
class Checked:
    """A strength-checked link: its body, material, pins and members with sections."""

    body: str
    material: object
    pins: list
    members: list[Member]


def safety_limit(limits: dict) -> float | None:
    """Takes ``"safety"`` out of ``limits`` (it bounds stresses, not a regressor quantity)."""
    s = limits.pop("safety", None)
    if s is not None and not s >= 1.0:
        raise InvalidInputError(f"limits['safety']: expected a safety factor >= 1, got {s!r}")
    return None if s is None else float(s)


def checked_links(model, parts, safety: float | None) -> list[Checked]:
    """The links with a material among a design's parts (``_Variables.parts``)."""
    out = []
    for kind, name, spec, _sl in parts:
        if kind != "shape" or spec.material is None:
            continue
        centers, lower, cap = spec.cells(model)
        full = lower >= cap
        pins = link_pins(model, name)
        r = spec.boss_radius()
        ms = [with_sections(m, centers, full, spec.cell, r, spec.web_width())
              for m in members(pins, r)]
        check_sections(name, ms)
        out.append(Checked(name, spec.material, pins, ms))
    if safety is not None and not out:
        raise InvalidInputError(
            "limits['safety']: expected some LinkShape with material=pmd.Material(...), got none"
        )
    return out


def quantities(checked: list[Checked], motion, data, actuated, cols, phi_base, phi_now,
               safety: float | None) -> list[dict]:
    """One peak quantity per checked link with members: its corner stresses (Pa)."""
    out = []
    if safety is None:
        return out
    n = len(motion.t)
    for c in checked:
        if not c.members:
            continue
        block = stress_rows(motion.model, c.body, c.members, c.pins, motion.q, data, list(actuated))
        before = float(np.abs(block @ phi_now).max(initial=0.0))
        allowed = c.material.allowable_stress / safety
        out.append({
            "name": PREFIX + c.body,
            "rows": np.ascontiguousarray(block[:, cols]),
            "constant": block @ phi_base,
            "dim": 1,
            "samples": n,
            "weight": 0.0,
            "reference": before if before > 0 else allowed,
            "limit": allowed,
            "zero": False,
            "peak": True,
        })
    return out


def raise_infeasible(message: str, relaxation: dict, binding: tuple, alone: dict,
                     checked: list[Checked], safety: float | None) -> None:
    """The solver's infeasibility, with each binding link's reachable safety factor."""
    lines = []
    for c in checked:
        key = PREFIX + c.body
        if key in relaxation and key in binding:
            asked, needed = relaxation[key]
            reach = c.material.allowable_stress / needed if needed > 0 else np.inf
            relaxation[key] = (safety, reach)
            lines.append(
                f"link '{c.body}': safety factor {safety:g} asked, {reach:.3g} in the nearest "
                f"design that exists (the least relaxation; its web's stress is "
                f"{needed / asked:.4g}x the allowed: widen web= or thicken the plate)"
            )
    if lines:
        message = "; ".join(lines) + f" [{message}]"
    raise InfeasibleDesignError(message, relaxation, binding, alone)


def analysed(checked: list[Checked], after, inputs=None) -> dict[str, LinkStrength]:
    """Each checked link's stresses re-analysed from the design's bearing forces
    (``inputs``: the driver's position per sample, to say where)."""
    return {c.body: analyse(after, c.body, c.material, c.members, c.pins, inputs) for c in checked}
