"""Automatic parameters (Carignan Eq. 21–26): definitions, limits, discretisation independence."""

import math

import pytest

from tailor.fabric import PRESETS, preset
from tailor.params import (
    REFERENCE_HEIGHT,
    bending_rigidity,
    fabric_params,
    hanging_strain,
    stretch_stiffness,
)
from tailor.units import GRAVITY


@pytest.mark.parametrize("stretch", [0.001, 0.01, 0.1, 0.5])
def test_stretch_stiffness_inverts_the_hanging_strip(stretch):
    k = stretch_stiffness(0.15, stretch)
    assert hanging_strain(0.15, k, REFERENCE_HEIGHT) == pytest.approx(stretch, rel=1e-9)


def test_small_stretch_limit_is_eq22():
    # η = ρ·g·H/(2λ) for small λ
    assert stretch_stiffness(0.2, 1e-4) == pytest.approx(0.2 * GRAVITY * 1.0 / (2 * 1e-4), rel=1e-3)


def test_parameters_that_must_not_depend_on_resolution_do_not():
    fabric = preset("wool")
    coarse, fine = fabric_params(fabric, 0.04), fabric_params(fabric, 0.01)
    for name in ("density", "stretch_warp", "stretch_weft", "stretch_shear", "wave_speed_warp", "bending_rigidity"):
        assert getattr(coarse, name) == getattr(fine, name)
    # Eq. 24: the step shrinks with the element size; Eq. 26: damping is per element
    ratio = coarse.time_step / fine.time_step  # ∝ h for stretch waves, ∝ h² where bending waves are faster
    assert 4.0 * (1 - 1e-9) <= ratio <= 16.0 * (1 + 1e-9)
    assert coarse.damping_warp / fine.damping_warp == pytest.approx(4.0)


def test_wave_speed_and_time_step():
    p = fabric_params(preset("cotton"), 0.02)
    assert p.wave_speed_warp == pytest.approx(math.sqrt(p.stretch_warp / p.density))
    assert p.time_step <= 0.02 * math.sqrt(3) / 2 / p.wave_speed_warp / 2 * (1 + 1e-12)


def test_shear_is_geometric_mean_and_bending_is_peirce():
    p = fabric_params(preset("jersey"), 0.02)
    assert p.stretch_shear == pytest.approx(math.sqrt(p.stretch_warp * p.stretch_weft))
    # c is the cube of the bending length in cm: B/(ρg) = (c^(1/3) cm)³
    b = bending_rigidity(0.2, 27.0)
    assert (b / (0.2 * GRAVITY)) ** (1 / 3) == pytest.approx(0.03)
    assert bending_rigidity(0.2, 0.0) == 0.0


def test_presets_span_silk_to_heavy_leather():
    densities = [f.density for f in PRESETS.values()]
    assert min(densities) <= 0.05 and max(densities) == pytest.approx(10.0)  # Carignan's 0.005 … 1.0 g/cm²
    assert densities == sorted(densities)
