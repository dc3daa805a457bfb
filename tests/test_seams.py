"""Sewing (`tailor/seams.py`): merging conserves mass and momentum exactly (Carignan Eq. 17–18), and
stiff seam springs close a gap stably under the implicit solver."""

import numpy as np
import pytest

from conftest import sheet
from tailor.seams import Sewing, merge_state


def test_merging_conserves_linear_momentum_and_mass_exactly():
    rng = np.random.default_rng(4)
    n = 50
    x, v, m = rng.normal(size=(n, 3)), rng.normal(size=(n, 3)), rng.uniform(0.1, 2.0, n)
    sewing = Sewing(np.array([[0, 1], [1, 2], [10, 20], [30, 30]]))  # a chain, a pair, a self-pair
    assert len(sewing.pairs) == 3
    sewing.merged[:] = True
    weld = sewing.weld_map(n)
    assert weld[0] == weld[1] == weld[2] and weld[10] == weld[20] and len(np.unique(weld)) == n - 3
    xw, vw = merge_state(x, v, m, weld)
    mw = np.bincount(weld, m)
    assert mw.sum() == pytest.approx(m.sum(), rel=1e-15)
    assert np.allclose((mw[:, None] * vw).sum(axis=0), (m[:, None] * v).sum(axis=0), rtol=0, atol=1e-12)
    # Eq. 18: r_m = r1 + (r2 − r1)·m2/(m1 + m2) for a single pair
    assert np.allclose(xw[weld[10]], x[10] + (x[20] - x[10]) * m[20] / (m[10] + m[20]))


def test_stiff_pair_springs_close_a_gap_stably_under_the_implicit_solver():
    from tailor.forces import pair_forces
    from tailor.forces.jacobian import SparsePattern, force_jacobians
    from tailor.integrators import SolverSettings, make_integrator
    from tailor.forces import total_forces

    model, x0 = sheet(20, 10, 0.05, "cotton", vertical=False, gravity=(0, 0, 0))
    left = np.flatnonzero(x0[:, 0] < 1e-9)
    right = np.flatnonzero(x0[:, 0] > 0.2 - 1e-9)
    pairs = np.column_stack([left[np.argsort(x0[left, 1])], right[np.argsort(x0[right, 1])]])  # a tube's seam
    m = model.vertex_mass[pairs].mean(axis=1)
    stiff = model.with_pairs(pairs, 1e5 * m, 2.0 * np.sqrt(1e5) * m)  # ω·Δt ≈ 3: explicit would explode
    state = stiff.state(x0)
    f = pair_forces(stiff, state)
    assert np.abs(f.sum(axis=0)).max() < 1e-12  # internal: momentum conserved
    k_all = force_jacobians(stiff, state, SparsePattern(stiff))[0].toarray()
    k_cloth = force_jacobians(model, model.state(x0), SparsePattern(model))[0].toarray()
    dx = np.random.default_rng(0).normal(0, 1e-4, x0.shape)
    moved = stiff.state(x0 + dx)
    predicted = -((k_all - k_cloth) @ dx.reshape(-1)).reshape(-1, 3)
    assert np.allclose(pair_forces(stiff, moved) - f, predicted, atol=1e-9)  # linear springs: K is exact
    integ = make_integrator("implicit")
    integ.configure(SolverSettings(max_stretch_change=np.inf))  # as drape sews: the seams' pull stretches the seam triangles by design
    gaps = []
    for _ in range(30):
        state = integ.step(stiff, state, 0.01, total_forces).state
        gaps.append(np.linalg.norm(state.x[pairs[:, 0]] - state.x[pairs[:, 1]], axis=1).max())
    assert np.isfinite(state.x).all() and gaps[-1] < 0.01 * 0.2 and gaps[-1] <= gaps[0]


def test_only_the_pairs_sewing_now_pull_and_merge():
    # an outfit sews one garment at a time: the others' pairs neither pull nor merge until their turn
    from types import SimpleNamespace

    from tailor.model import State

    x = np.array([[0.0, 0, 0], [0.001, 0, 0], [1.0, 0, 0], [1.001, 0, 0]])
    sewing = Sewing(np.array([[0, 1], [2, 3], [2, 2]]), active=[True, False, True])
    assert sewing.active.tolist() == [True, False] and sewing.sewing_count == 1 and sewing.open_count == 2
    weld = np.arange(4)
    model = SimpleNamespace(vertex_mass=np.ones(4))
    f = sewing.forces(model, State(x + [[0, 0.01, 0]] * np.array([[0], [1], [0], [1]]), np.zeros((4, 3)), 0.0), weld,
                      np.zeros((4, 3)))
    assert np.abs(f[:2]).max() > 0 and not f[2:].any()
    assert sewing.open_pairs(weld).tolist() == [[0, 1]]
    assert sewing.close(x) == 1 and sewing.merged.tolist() == [True, False]  # pair 2–3 is as close, but waits
    sewing.sew_only([False, True])
    assert sewing.close(x) == 1 and sewing.open_count == 0


def test_a_pair_to_a_held_panel_is_stiffened_only_when_near():
    # a waistband held at the waist while sewing: a stiff spring to the skirt below would stretch
    # the band down to it; the gentle explicit pull brings the skirt near first
    x = np.array([[0.0, 0, 0], [0.0, 0, 0.05], [1.0, 0, 0], [1.0, 0, 0.05], [2.0, 0, 0], [2.0, 0, 0.01]])
    pairs = np.array([[0, 1], [2, 3], [4, 5]])
    sewing = Sewing(pairs)
    mass = np.ones(6)
    k, _ = sewing.near_stiffness(x, pairs, mass, near=0.08, rate=1.0)
    assert k.tolist() == [1.0, 1.0, 1.0]
    sewing.anchor([1, 3, 5])
    sewing.anchor([1, 2, 3, 5])  # the second call replaces the first: 2-3 now joins two held vertices
    k, _ = sewing.near_stiffness(x, pairs, mass, near=0.08, rate=1.0, weld=np.arange(6), anchored_near=0.02)
    assert k.tolist() == [0.0, 1.0, 1.0]  # far from a held panel; both held; near one
    # in welded numbering (0 and 1 merged): the pairs 2-3 and 4-5 as before
    weld = np.array([0, 0, 1, 2, 3, 4])
    k, _ = sewing.near_stiffness(x[[0, 2, 3, 4, 5]], np.array([[1, 2], [3, 4]]), np.ones(5), near=0.08, rate=1.0,
                                 weld=weld, anchored_near=0.02)
    assert k.tolist() == [1.0, 1.0]


def test_pairs_across_a_body_just_under_its_top_are_routed_from_the_start():
    # a ball of radius 0.1 as the shoulder: straps either side 3 cm under its top are blocked and
    # routed over it at once; a pair through its middle (10 cm deep) waits to be stuck; a pair
    # beside it is pulled straight
    def inside(p):
        return np.linalg.norm(p, axis=1) < 0.1

    x = np.array([[0.0, -0.2, 0.07], [0.0, 0.2, 0.07], [0.0, -0.2, 0.0], [0.0, 0.2, 0.0],
                  [0.3, -0.2, 0.0], [0.3, 0.2, 0.0]])
    sewing = Sewing(np.array([[0, 1], [2, 3], [4, 5]]))
    assert sewing.block(x, inside, over=0.05) == 1 and sewing.blocked.tolist() == [True, False, False]
    assert sewing.block(x, inside, over=0.02) == 0  # 3 cm under the top: beyond 2 cm
    sewing.merged[0] = True
    assert sewing.block(x, inside, over=0.05) == 0  # merged pairs are not routed

    from types import SimpleNamespace

    from tailor.model import State

    over = np.array([0.0, 0.0, 0.12])
    sewing = Sewing(np.array([[0, 1], [2, 3], [4, 5]]), max_acceleration=1e9)
    sewing.block(x, inside, over=0.05)
    sewing.route_around(lambda mid: (np.flatnonzero(inside(mid)), np.tile(over, (int(inside(mid).sum()), 1))),
                        beyond=0.04, stuck=False)
    f = sewing.forces(SimpleNamespace(vertex_mass=np.ones(6)), State(x, np.zeros((6, 3)), 0.0), np.arange(6),
                      np.zeros((6, 3)))
    assert f[0, 2] > 0 and f[1, 2] > 0  # the straps: up over the top
    assert f[2, 2] == 0 and f[2, 1] > 0  # the deep pair: straight, until it is stuck


def test_each_kept_pair_keeps_its_seam_when_self_pairs_are_dropped():
    # a dart's tip pairs with itself and is dropped: the pairs after it must still name their own
    # seam (the sewing time-out's message named a dart for the GarmentCode dress's open shoulder)
    sewing = Sewing(np.array([[0, 1], [2, 2], [3, 4], [5, 6]]), seam=[0, 0, 0, 1])
    assert sewing.seam.tolist() == [0, 0, 1]


def test_pairs_whose_midpoint_is_inside_the_body_meet_over_it():
    """Two strap ends in front of and behind a shoulder (here a ball round the origin) are drawn to
    the point over it that ``meeting`` gives, not straight at each other through it; a near pair,
    the implicit springs', still meets at its midpoint."""
    from types import SimpleNamespace

    from tailor.model import State

    x = np.array([[0.0, -0.2, 0.0], [0.0, 0.2, 0.0], [0.5, 0.0, 0.0], [0.52, 0.0, 0.0]])
    over = np.array([0.0, 0.0, 0.15])

    def meeting(mid):
        inside = np.flatnonzero(np.linalg.norm(mid, axis=1) < 0.1)
        return inside, np.tile(over, (len(inside), 1))

    sewing = Sewing(np.array([[0, 1], [2, 3]]), max_acceleration=1e9)
    sewing.route_around(meeting, beyond=0.04)
    model = SimpleNamespace(vertex_mass=np.ones(4))

    def pull():
        return sewing.forces(model, State(x, np.zeros((4, 3)), 0.0), np.arange(4), np.zeros((4, 3)))

    f = pull()
    assert np.allclose(f[0], -f[1]) and f[0, 1] > 0  # still closing: straight
    sewing.close(x)
    sewing.close(x)  # not closer than a frame ago: stuck
    assert sewing.stuck.all()
    f = pull()
    for end in (0, 1):
        assert np.allclose(f[end] / np.linalg.norm(f[end]), (over - x[end]) / np.linalg.norm(over - x[end]))
    assert np.allclose(f[2], -f[3]) and f[2, 0] > 0 and not f[2, 1:].any()
    sewing.route_around(None)
    f = pull()
    assert np.allclose(f[0], -f[1]) and f[0, 1] > 0 and not f[0, [0, 2]].any()  # straight through


def test_the_last_pairs_are_stitched_where_they_are_once_every_one_stops_closing():
    """Eq. 16's d widens to the stragglers' reach as soon as the few pairs left all stopped closing
    (caught round an arm), not only after ¾ of the sewing time-out; pairs still closing wait."""
    from tailor.dress.options import DrapeOptions, STRAGGLER_REACH
    from tailor.dress.phases import _widen_merging

    opts = DrapeOptions(resolution=0.02)
    x = np.array([[0.0, 0, 0], [0.03, 0, 0], [1.0, 0, 0], [1.02, 0, 0]])
    for closing in (True, False):
        s = Sewing(np.array([[0, 1], [2, 3]]), merge_distance=0.004)
        s.merged[1] = True
        s.close(x)
        y = x.copy()
        y[1, 0] = 0.02 if closing else 0.0299  # 3 → 2 cm, or stalled at 3 cm
        s.close(y)
        assert bool(s.stalled[0]) is not closing and not s.stalled[1]  # a merged pair never stalls
        _widen_merging(s, 0.5, opts)
        assert s.merge_distance == (0.004 if closing else pytest.approx(STRAGGLER_REACH * 0.02))
        assert s.close(y) == (0 if closing else 1)
