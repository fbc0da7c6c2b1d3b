"""What a link is made of (docs/design.md §4a): density and allowable stress.

``pmd.Material(density, allowable_stress, name=…)``; presets are class methods
(``pmd.Material.steel()``, ``pmd.Material.aluminium()``) — one idiom, so a preset can take a
different allowable stress (``Material.steel(allowable_stress=150e6)``). The allowable
stress is the designer's (yield over whatever margin the shop uses); ``limits={"safety": s}``
divides it once more."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import InvalidInputError


def _positive(value, arg: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)) \
            or not (np.isfinite(value) and value > 0):
        raise InvalidInputError(f"{arg}: expected a finite number > 0, got {value!r}")
    return float(value)


@dataclass(frozen=True)
class Material:
    """A material: ``density`` (kg/m³) and ``allowable_stress`` (Pa, the largest normal
    stress a member may carry; the safety factor is its ratio to the stress found)."""

    density: float
    allowable_stress: float
    name: str = "material"

    def __post_init__(self):
        object.__setattr__(self, "density", _positive(self.density, "density"))
        object.__setattr__(self, "allowable_stress",
                           _positive(self.allowable_stress, "allowable_stress"))
        if not isinstance(self.name, str):
            raise InvalidInputError(f"name: expected a str, got {self.name!r}")

    @classmethod
    def steel(cls, allowable_stress: float = 250e6) -> Material:
        """Structural steel (S275-like): 7850 kg/m³, 250 MPa (its yield) by default."""
        return cls(7850.0, allowable_stress, "steel")

    @classmethod
    def aluminium(cls, allowable_stress: float = 240e6) -> Material:
        """Aluminium 6061-T6: 2700 kg/m³, 240 MPa (its yield) by default."""
        return cls(2700.0, allowable_stress, "aluminium")
