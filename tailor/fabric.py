"""Fabric: the three numbers a designer understands, plus friction and thickness.

Carignan et al. (seed 002, §5) derive every simulation parameter from areal density ρ,
the stretch percentage λ a panel shows when suspended under its own weight, and a bending
number c. :class:`Fabric` stores those user numbers in SI; the parameter derivation
(Eq. 21–26) lives in :mod:`tailor.params`.

Examples
--------
>>> f = preset("denim")
>>> f.density  # kg/m²
0.4
>>> fabric_names()[:3]
('chiffon', 'silk', 'cotton')
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields, replace

from .errors import FabricError

__all__ = ["Fabric", "PRESETS", "preset", "fabric_names", "DEFAULT_FABRIC"]


@dataclass(frozen=True, slots=True)
class Fabric:
    """A fabric in SI units.

    Attributes
    ----------
    name : str
        Preset name or a user label.
    density : float
        Areal density ρ [kg/m²] (Eq. 21). Silk ≈ 0.05, denim ≈ 0.4, heavy leather 10 (the
        paper's 1.0 g/cm²).
    stretch_warp, stretch_weft : float
        Elongation λ under own weight as a fraction (0.02 = 2 %), along the warp (grain)
        and the weft (Eq. 22a/b).
    bending : float
        Carignan's bending number c (Eq. 25): the cube of the fabric's Peirce bending length in
        cm (see :mod:`tailor.params`); 0 means no bending resistance. Silk ≈ 1, denim ≈ 60.
    friction : float
        Coulomb friction coefficient μ against bodies (Eq. 14).
    thickness : float
        Cloth thickness [m], used as the collision margin.
    """

    name: str
    density: float
    stretch_warp: float
    stretch_weft: float
    bending: float
    friction: float = 0.4
    thickness: float = 1.0e-3

    def __post_init__(self):
        for f in fields(self):
            if f.name == "name":
                continue
            value = getattr(self, f.name)
            if not isinstance(value, (int, float)) or isinstance(value, bool) or not math.isfinite(value):
                raise FabricError(f"fabric {self.name!r}: {f.name} must be a finite number, got {value!r}")
        if self.density <= 0:
            raise FabricError(f"fabric {self.name!r}: density must be positive, got {self.density * 1e3:g} g/m²")
        for key in ("stretch_warp", "stretch_weft"):
            v = getattr(self, key)
            if not 0.0 < v <= 1.0:
                raise FabricError(f"fabric {self.name!r}: {key} must be in (0, 100] %, got {v * 100:g} %")
        if self.bending < 0:
            raise FabricError(f"fabric {self.name!r}: bending must be >= 0, got {self.bending:g}")
        if self.friction < 0:
            raise FabricError(f"fabric {self.name!r}: friction must be >= 0, got {self.friction:g}")
        if self.thickness <= 0:
            raise FabricError(f"fabric {self.name!r}: thickness must be positive, got {self.thickness * 1e3:g} mm")

    def with_values(self, **values) -> "Fabric":
        """A copy with some fields replaced (validated again)."""
        return replace(self, **values)


def _p(name, g_m2, stretch_pct, bending, friction=0.4, thickness_mm=1.0, weft_pct=None):
    w = stretch_pct if weft_pct is None else weft_pct
    return Fabric(name, g_m2 * 1e-3, stretch_pct * 1e-2, w * 1e-2, bending, friction, thickness_mm * 1e-3)


PRESETS: dict[str, Fabric] = {
    f.name: f
    for f in (
        _p("chiffon", 35, 3.0, 0.3, 0.3, 0.3),
        _p("silk", 50, 2.0, 1.0, 0.25, 0.3),
        _p("cotton", 120, 1.0, 8.0, 0.4, 0.5),
        _p("jersey", 180, 8.0, 4.0, 0.5, 0.8, weft_pct=15.0),
        _p("wool", 280, 1.5, 15.0, 0.5, 1.5),
        _p("denim", 400, 0.5, 60.0, 0.5, 1.0),
        _p("leather", 1000, 0.3, 300.0, 0.6, 1.2),
        _p("heavy_leather", 10000, 0.2, 1000.0, 0.6, 3.0),
    )
}
"""Named fabrics, light to heavy. ``heavy_leather`` is Carignan's 1.0 g/cm² extreme."""

DEFAULT_FABRIC = "cotton"
"""Fabric used when a pattern names none."""


def fabric_names() -> tuple[str, ...]:
    """Preset names, light to heavy."""
    return tuple(PRESETS)


def preset(name: str) -> Fabric:
    """The preset fabric called ``name``; raises :class:`FabricError` naming the choices."""
    try:
        return PRESETS[name]
    except (KeyError, TypeError):
        import difflib

        close = difflib.get_close_matches(str(name), PRESETS, n=1)
        hint = f" (did you mean {close[0]!r}?)" if close else ""
        raise FabricError(
            f"unknown fabric {name!r}{hint}; choose one of {', '.join(PRESETS)}"
        ) from None
