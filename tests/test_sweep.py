"""Swept boxes cut in time (`tailor/collide/sweep.py`): a step searched in parts finds every pair that
comes near during it, from fewer candidates than the whole step's boxes."""

import numpy as np

from tailor.collide.grid import edge_edge_pairs, unique_edges, vertex_rings, vertex_triangle_pairs
from tailor.collide.sweep import part_boxes, sweep_parts, union_edge_edge, union_vertex_triangle
from tailor.scenes import grid as sheet


def _swinging_flap():
    """A 0.4 m sheet (2 cm edges) whose half beyond x = 0.2 swings 90° down about that line in one step."""
    mesh = sheet(0.4, 0.4, 21)
    faces = np.asarray(mesh.faces, np.int64)
    x0 = np.c_[mesh.uv, np.zeros(len(mesh.uv))]
    x1 = x0.copy()
    flap = x0[:, 0] > 0.2
    r = x0[flap, 0] - 0.2
    x1[flap, 0], x1[flap, 2] = 0.2, -r
    return faces, x0, x1


def _vt_keys(vertex, tri, f):
    return set((vertex * f + tri).tolist())


def _ee_keys(ee):
    return {tuple(sorted(((a, b), (c, d)))) for a, b, c, d in ee.tolist()}


def test_a_step_in_parts_finds_every_pair_near_at_any_time_from_fewer_candidates():
    faces, x0, x1 = _swinging_flap()
    n, f = len(x0), len(faces)
    ring, edges = vertex_rings(faces, n), unique_edges(faces, n)
    verts, tris, ids = np.arange(n), np.arange(f), np.arange(len(edges))
    radius, cell = 0.011, 0.04
    parts = sweep_parts(float(np.linalg.norm(x1 - x0, axis=1).max()), 0.02)
    assert parts == 4  # 28 cm of motion, 8 cm a part

    def search(lo, hi):
        v, t, near = vertex_triangle_pairs(verts, tris, faces, lo, hi, x1, radius, cell, ring, exact=False)
        return (v, t, near), edge_edge_pairs(ids, edges, lo, hi, radius, cell, ring)

    whole = search(np.minimum(x0, x1), np.maximum(x0, x1))
    found = [search(lo, hi) for lo, hi in part_boxes(x0, x1, parts)]
    vt = union_vertex_triangle([p[0] for p in found], f)
    ee, _ = union_edge_edge([p[1] for p in found], edges, n)
    assert len(vt[0]) == len(set(zip(*vt[:2]))) and len(ee) == len(_ee_keys(ee))  # each once
    assert _vt_keys(*vt[:2], f) <= _vt_keys(*whole[0][:2], f) and _ee_keys(ee) <= _ee_keys(whole[1][0])
    assert 2 * len(ee) < len(whole[1][0]) and 2 * len(vt[0]) < len(whole[0][0])
    for t in np.linspace(0.0, 1.0, 21):  # every pair near at some time of the step is found
        xt = (1.0 - t) * x0 + t * x1
        (v, tri, _), (e, _) = search(xt, xt)
        assert _vt_keys(v, tri, f) <= _vt_keys(*vt[:2], f) and _ee_keys(e) <= _ee_keys(ee)


def test_steps_shorter_than_the_parts_are_searched_whole():
    assert sweep_parts(0.066, 0.0166) == 1  # a 2 cm garment's fastest walking step (4.6 cm)
    assert sweep_parts(float("inf"), 0.02) == 1 and sweep_parts(0.1, 0.0) == 1
    assert sweep_parts(10.0, 0.001) == 8
