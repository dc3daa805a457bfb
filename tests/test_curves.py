import math

import numpy as np
import pytest

from tailor.curves import Curve, arc_center, curve_length, loop_area, sample_curve


def test_straight_length_and_even_sampling():
    c = Curve("straight", ((0.0, 0.0), (3.0, 4.0)))
    assert curve_length(c) == pytest.approx(5.0)
    pts = sample_curve(c, np.linspace(0, 1, 6))
    assert np.allclose(np.diff(pts, axis=0), [0.6, 0.8])


@pytest.mark.parametrize("sweep,large,expect_y", [(True, False, -1.0), (False, False, 1.0)])
def test_arc_sweep_flag_is_counter_clockwise(sweep, large, expect_y):
    # From (-1, 0) to (1, 0) with radius 1: CCW passes below (y = -1), CW above (y = +1).
    c = Curve("circle", ((-1.0, 0.0), (1.0, 0.0)), radius=1.0, large_arc=large, sweep=sweep)
    mid = sample_curve(c, [0.5])[0]
    assert mid == pytest.approx([0.0, expect_y], abs=1e-12)
    assert curve_length(c) == pytest.approx(math.pi)


def test_large_arc_takes_the_long_way():
    r, chord = 2.0, 2.0  # chord subtends 60°, the large arc 300°
    small = Curve("circle", ((0.0, 0.0), (chord, 0.0)), radius=r, large_arc=False, sweep=True)
    large = Curve("circle", ((0.0, 0.0), (chord, 0.0)), radius=r, large_arc=True, sweep=True)
    assert curve_length(small) == pytest.approx(r * math.pi / 3)
    assert curve_length(large) == pytest.approx(r * 5 * math.pi / 3)
    center, _, _ = arc_center((0, 0), (chord, 0), r, True, True)
    assert np.hypot(*center - [1.0, 0.0]) == pytest.approx(math.sqrt(3.0))


def test_bezier_sampling_is_even_in_arc_length():
    c = Curve("cubic", ((0.0, 0.0), (0.1, 0.5), (0.9, -0.4), (1.0, 0.0)))
    pts = sample_curve(c, np.linspace(0, 1, 41))
    seg = np.hypot(*np.diff(pts, axis=0).T)
    assert seg.std() / seg.mean() < 2e-3  # chords of equal arcs differ only by curvature
    assert np.allclose(pts[[0, -1]], [[0, 0], [1, 0]])


def test_quadratic_length_matches_closed_form():
    # Parabola y = x² from 0 to 1 as a quadratic Bézier: control (0.5, 0).
    c = Curve("quadratic", ((0.0, 0.0), (0.5, 0.0), (1.0, 1.0)))
    exact = (2 * math.sqrt(5) + math.asinh(2)) / 4
    assert curve_length(c) == pytest.approx(exact, rel=1e-6)


def test_loop_area_of_a_disc_from_four_arcs():
    r = 0.15
    pts = [(r, 0.0), (0.0, r), (-r, 0.0), (0.0, -r)]
    arcs = [Curve("circle", (pts[i], pts[(i + 1) % 4]), radius=r, sweep=True) for i in range(4)]
    assert loop_area(arcs) == pytest.approx(math.pi * r * r, rel=1e-7)
    assert loop_area([Curve(c.kind, c.points[::-1], c.radius, c.large_arc, not c.sweep) for c in arcs[::-1]]) < 0
