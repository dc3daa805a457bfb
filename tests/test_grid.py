"""The compiled grid broad phase (`tailor/collide/grid.py`): exactly the pairs a brute-force check finds, each once."""

import numpy as np
import pytest
from scipy.spatial import cKDTree

from tailor.collide.closest import closest_barycentric
from tailor.collide.grid import MAX_CELLS, Grid, bin_boxes, edge_edge_pairs, vertex_triangle_pairs


def _soup(rng, n=300, faces=400, spread=0.3):
    x = rng.uniform(0.0, spread, (n, 3))
    f = np.array([rng.choice(n, 3, replace=False) for _ in range(faces)])
    lo = x - rng.uniform(0.0, 0.02, (n, 3))  # boxes round each vertex (its motion over a step)
    hi = x + rng.uniform(0.0, 0.02, (n, 3))
    return x, f, lo, hi


def _gap(lo_a, hi_a, lo_b, hi_b):
    return np.linalg.norm(np.maximum(0.0, np.maximum(lo_b - hi_a, lo_a - hi_b)))


def _ring(n, faces):
    e = faces[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2)
    keys = np.unique(np.concatenate([e[:, 0] * n + e[:, 1], e[:, 1] * n + e[:, 0], np.arange(n) * (n + 1)]))
    return np.searchsorted(keys // n, np.arange(n + 1)).astype(np.int64), (keys % n).astype(np.int64), set(keys.tolist())


@pytest.mark.parametrize("exact, cell", [(False, 0.03), (True, 0.03), (False, 0.2), (False, 0.004)])
def test_vertex_triangle_pairs_are_exactly_the_brute_force_ones(exact, cell):
    rng = np.random.default_rng(3)
    x, faces, lo, hi = _soup(rng)
    if exact:
        lo = hi = x
    verts, tris, radius = np.arange(0, 300, 2), np.arange(0, 400, 3), 0.025
    *ring, keys = _ring(len(x), faces)
    v, t, near = vertex_triangle_pairs(verts, tris, faces, lo, hi, x, radius, cell, ring, exact=exact)
    want = set()
    for p in verts:
        for k in tris:
            f = faces[k]
            if p in f or _gap(lo[p], hi[p], lo[f].min(0), hi[f].max(0)) > radius:
                continue
            if exact and np.linalg.norm(x[p] - np.dot(closest_barycentric(x[p], *x[f]), x[f])) > radius:
                continue
            want.add((p, k))
    got = list(zip(v.tolist(), t.tolist()))
    assert len(got) == len(set(got)) and set(got) == want and len(want) > 50
    assert np.array_equal(near, [any(p * len(x) + q in keys for q in faces[k]) for p, k in got])


@pytest.mark.parametrize("cell", [0.03, 0.5, 0.004])
def test_edge_edge_pairs_are_exactly_the_brute_force_ones_each_once(cell):
    rng = np.random.default_rng(4)
    x, faces, lo, hi = _soup(rng, faces=200)
    edges = np.unique(np.sort(faces[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1), axis=0)
    ids, radius = np.arange(0, len(edges), 2), 0.02
    *ring, keys = _ring(len(x), faces)
    pairs, near = edge_edge_pairs(ids, edges, lo, hi, radius, cell, ring)
    want = set()
    for i, a in enumerate(ids):
        for b in ids[i + 1:]:
            ea, eb = edges[a], edges[b]
            if set(ea) & set(eb):
                continue
            if _gap(lo[ea].min(0), hi[ea].max(0), lo[eb].min(0), hi[eb].max(0)) <= radius:
                want.add(frozenset([tuple(ea), tuple(eb)]))
    got = [frozenset([tuple(p[:2]), tuple(p[2:])]) for p in pairs.tolist()]
    assert len(got) == len(set(got)) and set(got) == want and len(want) > 50
    assert np.array_equal(near, [any(p * len(x) + q in keys for p in r[:2] for q in r[2:]) for r in pairs.tolist()])


@pytest.mark.parametrize("cell", [0.03, 0.004])
def test_edge_edge_pairs_of_dirty_edges_are_the_brute_force_ones_touching_them_each_once(cell):
    """A partial query: only the pairs with at least one dirty edge, each once, none among clean ones."""
    rng = np.random.default_rng(5)
    x, faces, lo, hi = _soup(rng, faces=200)
    edges = np.unique(np.sort(faces[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1), axis=0)
    ids, radius = np.arange(len(edges)), 0.02
    dirty = rng.random(len(ids)) < 0.2
    ring = _ring(len(x), faces)[:2]
    pairs, _ = edge_edge_pairs(ids, edges, lo, hi, radius, cell, ring, dirty=dirty)
    want = set()
    for i in range(len(ids)):
        for j in range(i + 1, len(ids)):
            ea, eb = edges[ids[i]], edges[ids[j]]
            if not (dirty[i] or dirty[j]) or set(ea) & set(eb):
                continue
            if _gap(lo[ea].min(0), hi[ea].max(0), lo[eb].min(0), hi[eb].max(0)) <= radius:
                want.add(frozenset([tuple(ea), tuple(eb)]))
    got = [frozenset([tuple(p[:2]), tuple(p[2:])]) for p in pairs.tolist()]
    assert len(got) == len(set(got)) and set(got) == want and len(want) > 20


def test_a_grid_over_a_vast_extent_keeps_to_its_cell_budget():
    grid = Grid(np.zeros((1, 3)), np.full((1, 3), 100.0), 1e-3)
    assert np.prod(grid.dims) <= 1.05 * MAX_CELLS  # one cell more per axis at most


def test_overlapping_boxes_are_the_pairs_brute_force_finds():
    from tailor.collide.grid import overlapping_boxes

    rng = np.random.default_rng(5)
    lo = rng.uniform(0, 1, (300, 3))
    hi = lo + rng.uniform(0, 0.15, (300, 3))
    i, j = overlapping_boxes(lo, hi)
    meet = np.all((lo[:, None] <= hi[None]) & (lo[None] <= hi[:, None]), axis=2)
    expected = {(a, b) for a, b in zip(*np.nonzero(np.triu(meet, 1)))}
    assert set(zip(i.tolist(), j.tolist())) == expected and len(i) == len(expected) and np.all(i < j)


def test_binned_boxes_hold_exactly_the_boxes_meeting_each_cell_in_order():
    rng = np.random.default_rng(7)
    lo = rng.uniform(0.0, 1.0, (500, 3))
    hi = lo + rng.uniform(0.0, 0.3, (500, 3))
    grid = Grid(lo, hi, 0.17)
    ptr, items = bin_boxes(lo, hi, grid.origin, grid.cell, grid.dims)
    first = np.clip(np.floor((lo - grid.origin) / grid.cell).astype(int), 0, grid.dims - 1)
    last = np.clip(np.floor((hi - grid.origin) / grid.cell).astype(int), 0, grid.dims - 1)
    assert len(ptr) == np.prod(grid.dims) + 1
    for key in range(np.prod(grid.dims)):
        a, b, c = key % grid.dims[0], (key // grid.dims[0]) % grid.dims[1], key // (grid.dims[0] * grid.dims[1])
        cell = np.array([a, b, c])
        expected = np.flatnonzero(np.all((first <= cell) & (cell <= last), axis=1))
        assert np.array_equal(items[ptr[key]:ptr[key + 1]], expected)


def test_edge_pairs_found_in_one_pass_are_the_two_pass_ones_in_order_where_some_chunks_overflow():
    """Each chunk of queries writes into room for a few pairs a query; a chunk that overflows (a dense
    crumple) is written again in full. The pairs, and their order, are those of counting first."""
    from tailor.collide.grid import _GUESS_CHUNK, _GUESS_PAIRS, _ee_pairs, _ee_pairs_guessed
    from tailor.collide.patch_pairs import NO_PATCH_PAIRS

    rng = np.random.default_rng(6)
    n = 4 * _GUESS_CHUNK
    start = rng.uniform(0.0, 0.25, (n, 3))
    start[:_GUESS_CHUNK] = rng.uniform(0.0, 0.03, (_GUESS_CHUNK, 3))  # the first chunk's edges crumpled together
    x = np.stack([start, start + rng.normal(0.0, 0.01, (n, 3))], axis=1).reshape(-1, 3)
    edges = np.arange(2 * n).reshape(-1, 2)
    lo, hi = np.minimum(x[0::2], x[1::2]), np.maximum(x[0::2], x[1::2])
    dirty = rng.random(n) < 0.8
    grid = Grid(lo - 0.02, hi + 0.02, 0.02)
    ring = (np.zeros(2 * n + 1, np.int64), np.zeros(0, np.int64))
    args = (np.arange(n), edges, lo, hi, np.flatnonzero(dirty).astype(np.int64), dirty, grid.origin, grid.cell, grid.dims, 0.02,
            np.zeros(n), *ring, NO_PATCH_PAIRS)
    (want, want_near), (got, got_near) = _ee_pairs(*args), _ee_pairs_guessed(*args, _GUESS_PAIRS)
    first = np.isin(want[:, 0] // 2, np.arange(_GUESS_CHUNK)).sum()
    assert first > _GUESS_CHUNK * _GUESS_PAIRS and len(want) - first > 100  # one chunk overflowed, the others did not
    assert np.array_equal(got, want) and np.array_equal(got_near, want_near)


def test_vertex_triangle_pairs_overflowing_their_room_are_searched_again_in_vertex_order():
    """Vertices are searched in chunks, each writing into room for a few triangles a vertex; a chunk in
    a crumple overflows and is searched again in full. Every pair a brute-force check finds, once,
    grouped by vertex in the order the vertices were given."""
    from tailor.collide.grid import _GUESS_CHUNK, _GUESS_TRIANGLES

    rng = np.random.default_rng(7)
    n = 3 * _GUESS_CHUNK
    x = rng.uniform(0.0, 0.2, (n, 3))
    x[:_GUESS_CHUNK] = rng.uniform(0.0, 0.04, (_GUESS_CHUNK, 3))  # the first chunk crumpled together
    faces = cKDTree(x).query(x, k=3)[1]  # each vertex with its two nearest: small triangles
    verts = np.r_[rng.permutation(_GUESS_CHUNK), _GUESS_CHUNK + rng.permutation(n - _GUESS_CHUNK)]  # the crumple first
    tris, radius = np.arange(len(faces)), 0.02
    ring = (np.zeros(n + 1, np.int64), np.zeros(0, np.int64))
    v, t, _ = vertex_triangle_pairs(verts, tris, faces, x, x, x, radius, 0.02, ring, exact=False)
    t_lo, t_hi = x[faces].min(axis=1), x[faces].max(axis=1)
    gap = np.linalg.norm(np.maximum(0.0, np.maximum(t_lo[None] - x[verts, None], x[verts, None] - t_hi[None])), axis=2)
    want = (gap <= radius) & ~(faces[None] == verts[:, None, None]).any(axis=2)
    per_chunk = want.sum(axis=1).reshape(3, -1).sum(axis=1)
    assert per_chunk[0] > _GUESS_CHUNK * _GUESS_TRIANGLES and 100 < per_chunk[1:].max() < _GUESS_CHUNK * _GUESS_TRIANGLES
    rank = np.empty(n, np.int64)
    rank[verts] = np.arange(n)
    assert np.all(np.diff(rank[v]) >= 0)  # grouped by vertex, in the given order
    got = set(zip(v.tolist(), t.tolist()))
    assert len(got) == len(v) and got == {(verts[i], k) for i, k in zip(*np.nonzero(want))}


def test_a_learning_room_finds_every_pair_and_sizes_the_next_search_by_this_ones_density():
    """A search repeated step after step makes room per query from what the last one found
    (:class:`PairRoom`): a room far too small finds the same pairs in the same order (its chunks
    searched again), and the next room is twice the pairs per query found plus the slack, within
    its bounds."""
    from tailor.collide.grid import ROOM_LEAST, ROOM_SLACK, PairRoom

    rng = np.random.default_rng(11)
    x, f, lo, hi = _soup(rng, n=600, faces=900, spread=0.12)
    edges = np.unique(np.sort(f[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1), axis=0)
    ring = _ring(len(x), f)[:2]
    want, want_near = edge_edge_pairs(np.arange(len(edges)), edges, lo, hi, 0.01, 0.02, ring)
    room = PairRoom()
    room.per = 1  # every chunk overflows
    got, got_near = edge_edge_pairs(np.arange(len(edges)), edges, lo, hi, 0.01, 0.02, ring, room=room)
    assert np.array_equal(got, want) and np.array_equal(got_near, want_near)
    assert len(want) > 16 * len(edges)  # dense enough to set the room above its floor
    assert room.per == min(room.most, max(ROOM_LEAST, 2 * len(want) // len(edges) + ROOM_SLACK)) > ROOM_LEAST
    v0, t0, _ = vertex_triangle_pairs(np.arange(len(x)), np.arange(len(f)), f, lo, hi, x, 0.01, 0.02, ring, exact=False)
    small = PairRoom(most=20)
    v1, t1, _ = vertex_triangle_pairs(np.arange(len(x)), np.arange(len(f)), f, lo, hi, x, 0.01, 0.02, ring, exact=False, room=small)
    assert np.array_equal(v0, v1) and np.array_equal(t0, t1) and small.per <= 20


def test_searches_filtered_by_patch_pairs_find_what_the_patches_filter_keeps_of_the_unfiltered_ones():
    """The searches test the patch rule before writing a pair out (:mod:`tailor.collide.patch_pairs`):
    on a crumpled sheet they return, in order, exactly the unfiltered pairs that ``Regions`` allows,
    plus every pair with a free vertex at each end (a kept seam's, checked by the caller)."""
    from tailor.collide.grid import unique_edges, vertex_rings
    from tailor.collide.regions import Regions
    from tailor.scenes import grid as sheet

    mesh = sheet(0.4, 0.4, 21)
    faces = np.asarray(mesh.faces, np.int64)
    rng = np.random.default_rng(11)
    x = np.c_[mesh.uv, np.zeros(len(mesh.uv))]
    x[:, 2] = 0.01 * np.sin(12.0 * x[:, 1]) + rng.normal(0.0, 0.0005, len(x))  # a gentle wave
    x[:, 0] = np.where(x[:, 0] > 0.3, 0.6 - x[:, 0], x[:, 0])  # a strip folded back over itself along x = 0.3
    x[mesh.uv[:, 0] > 0.3, 2] += 0.008
    regions = Regions(faces, np.zeros(len(faces), np.int64), x, 0.05)
    pairs = regions.touching(x, None, 0.006)[1]
    edges = unique_edges(faces, len(x))
    free = np.zeros(len(x), bool)
    free[rng.choice(len(x), 60, replace=False)] = True
    ring = vertex_rings(faces, len(x))
    filt = regions.patch_pairs(pairs, regions.edge_patches(edges), free).arrays()
    verts, every = np.arange(len(x)), np.arange(len(faces))  # the flat part too: its pairs are filtered out
    v0, t0, _ = vertex_triangle_pairs(verts, every, faces, x, x, x, 0.025, 0.04, ring, exact=True)
    v1, t1, _ = vertex_triangle_pairs(verts, every, faces, x, x, x, 0.025, 0.04, ring, exact=True, patch_pairs=filt)
    allowed = regions.allowed_vertex_triangle(pairs, v0, t0)
    keep = allowed | (free[v0] & free[faces[t0]].any(axis=1))
    assert allowed.sum() < keep.sum() < len(keep)  # the flat part's pairs filtered out, the free ones let through
    assert np.array_equal(v1, v0[keep]) and np.array_equal(t1, t0[keep])
    ids = np.arange(len(edges))
    e0, _ = edge_edge_pairs(ids, edges, x, x, 0.025, 0.04, ring)
    e1, _ = edge_edge_pairs(ids, edges, x, x, 0.025, 0.04, ring, patch_pairs=filt)
    allowed = regions.allowed_edge_edge(pairs, e0)
    keep = allowed | (free[e0[:, :2]].any(axis=1) & free[e0[:, 2:]].any(axis=1))
    assert allowed.sum() < keep.sum() < len(keep) and np.array_equal(e1, e0[keep])


def test_pairs_with_padded_ends_are_those_within_the_radius_plus_both_pads_as_brute_force_finds():
    """Each vertex's pad (its own reach beyond the radius: half the self-contact margin for a vertex
    that may drift, none for one held still) widens the search pair by pair: a vertex–triangle pair
    within the radius plus the vertex's pad plus the largest of the triangle's corners', an edge pair
    within the radius plus both edges' largest; pairs of two unpadded elements only within the radius."""
    rng = np.random.default_rng(12)
    x, f, lo, hi = _soup(rng, n=500, faces=700, spread=0.12)
    pad = np.where(rng.random(len(x)) < 0.5, 0.0, 0.006)
    ring = _ring(len(x), f)[:2]
    radius = 0.004

    def gap(a_lo, a_hi, b_lo, b_hi):
        return np.linalg.norm(np.maximum(0.0, np.maximum(b_lo[None] - a_hi[:, None], a_lo[:, None] - b_hi[None])), axis=2)

    v, t, _ = vertex_triangle_pairs(np.arange(len(x)), np.arange(len(f)), f, lo, hi, x, radius, 0.02, ring, exact=False, pad=pad)
    reach = radius + pad[:, None] + pad[f].max(axis=1)[None]
    want = (gap(lo, hi, lo[f].min(axis=1), hi[f].max(axis=1)) <= reach) & ~(f[None] == np.arange(len(x))[:, None, None]).any(axis=2)
    assert set(zip(v.tolist(), t.tolist())) == set(zip(*np.nonzero(want)))
    assert want.sum() > len(x)  # enough pairs for the test to mean something
    edges = np.unique(np.sort(f[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1), axis=0)
    got, _ = edge_edge_pairs(np.arange(len(edges)), edges, lo, hi, radius, 0.02, ring, pad=pad)
    e_lo, e_hi, e_pad = lo[edges].min(axis=1), hi[edges].max(axis=1), pad[edges].max(axis=1)
    close = gap(e_lo, e_hi, e_lo, e_hi) <= radius + e_pad[:, None] + e_pad[None]
    shared = (edges[:, None, :, None] == edges[None, :, None, :]).any(axis=(2, 3))
    i, j = np.nonzero(np.triu(close & ~shared, 1))
    key = {tuple(sorted((tuple(edges[a]), tuple(edges[b])))) for a, b in zip(i, j)}
    assert {tuple(sorted((tuple(r[:2]), tuple(r[2:])))) for r in got.tolist()} == key
    assert len(got) > len(edge_edge_pairs(np.arange(len(edges)), edges, lo, hi, radius, 0.02, ring)[0])


def test_compiled_bounds_are_numpys_for_points_and_triangles_and_nan_reaches_them():
    from tailor.collide.bounds import axis_bounds, triangle_bounds

    rng = np.random.default_rng(5)
    x, f, _, _ = _soup(rng)
    lo, hi = axis_bounds(x)
    assert np.array_equal(lo, x.min(axis=0)) and np.array_equal(hi, x.max(axis=0))
    t_lo, t_hi = triangle_bounds(x, f, 2)
    assert np.array_equal(t_lo, x[f][:, :, :2].min(axis=1)) and np.array_equal(t_hi, x[f][:, :, :2].max(axis=1))
    x[17, 1] = np.nan
    assert np.isnan(axis_bounds(x)[0]).all() and np.isnan(axis_bounds(x)[1]).all()
    with pytest.raises(ValueError):
        axis_bounds(np.zeros((0, 3)))


def test_each_patchs_normal_cone_is_its_faces_mean_normal_and_widest_angle_from_it():
    """:meth:`Regions._cones` against the definition on a folded sheet: the mean of a patch's
    area-weighted normals, and the largest angle between it and a face's normal (a flat patch 0,
    the patches along the fold near 180°)."""
    from tailor.collide.regions import Regions
    from tailor.scenes import grid as sheet

    mesh = sheet(0.4, 0.4, 21)
    faces = np.asarray(mesh.faces, np.int64)
    x = np.c_[mesh.uv, np.zeros(len(mesh.uv))]
    x[:, 0] = np.where(x[:, 0] > 0.3, 0.6 - x[:, 0], x[:, 0])  # folded back over itself along x = 0.3
    x[mesh.uv[:, 0] > 0.3, 2] += 0.008
    regions = Regions(faces, np.zeros(len(faces), np.int64), x, 0.05)
    mean, spread = regions._cones(x)
    n = np.cross(x[faces[:, 1]] - x[faces[:, 0]], x[faces[:, 2]] - x[faces[:, 0]])
    for p in range(regions.count):
        mine = n[regions.face_patch == p]
        m = mine.sum(axis=0) / np.linalg.norm(mine.sum(axis=0))
        cos = (mine / np.linalg.norm(mine, axis=1)[:, None]) @ m
        assert np.allclose(mean[p], m, atol=1e-12)
        assert spread[p] == pytest.approx(np.arccos(np.clip(cos.min(), -1.0, 1.0)), abs=1e-6)
    assert spread.min() < 1e-6 and spread.max() > 0.9 * np.pi  # flat patches, and ones holding the fold
