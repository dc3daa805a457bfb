"""Horizontal sections of meshes: rings chained from the cut edges, checked against trimesh's."""

import numpy as np
import pytest
import trimesh

from tailor.sections import cut_outlines, horizontal_outlines


def _trimesh_areas(mesh, z):
    sec = mesh.section(plane_origin=[0.0, 0.0, z], plane_normal=[0.0, 0.0, 1.0])
    return sorted(p.area for p in sec.to_2D(to_2D=np.eye(4))[0].polygons_full) if sec is not None else []


@pytest.mark.parametrize("heights", [np.linspace(-0.95, 0.95, 9), [0.3, -0.2, 0.0]])
def test_the_sections_of_a_sphere_are_trimesh_s(heights):
    mesh = trimesh.creation.icosphere(subdivisions=3)
    ours = horizontal_outlines(mesh.vertices, mesh.faces, heights)
    for z, polys in zip(heights, ours):
        assert len(polys) == 1
        assert polys[0].area == pytest.approx(_trimesh_areas(mesh, z)[0], rel=1e-9)
        assert polys[0].area == pytest.approx(np.pi * (1 - z * z), rel=0.08)


def test_a_cut_through_vertices_and_two_parts_and_a_hole():
    legs = trimesh.util.concatenate([trimesh.creation.cylinder(0.1, 1.0, sections=16).apply_translation([x, 0, 0.5])
                                     for x in (-0.3, 0.3)])
    z_of_a_ring = float(np.unique(np.round(legs.vertices[:, 2], 9))[0])  # the cylinders' bottom rim
    cuts = horizontal_outlines(legs.vertices, legs.faces, [0.5, z_of_a_ring + 1e-12, 0.0])
    assert [len(c) for c in cuts[:2]] == [2, 2]
    assert [p.area for p in cuts[0]] == pytest.approx([8 * 0.1 ** 2 * np.sin(2 * np.pi / 16)] * 2, rel=1e-9)
    whole = trimesh.creation.icosphere(subdivisions=3, radius=0.15)  # edges of 2 cm
    holed = whole.copy()
    holed.update_faces(np.linalg.norm(holed.triangles_center - [0.15, 0.0, 0.0], axis=1) > 0.02)
    assert len(holed.faces) < len(whole.faces)
    (poly,) = horizontal_outlines(holed.vertices, holed.faces, [0.0])[0]  # closed across the hole
    assert poly.area == pytest.approx(horizontal_outlines(whole.vertices, whole.faces, [0.0])[0][0].area, rel=0.03)


def test_an_oblique_cut_is_the_horizontal_cut_turned():
    mesh = trimesh.creation.capsule(height=1.0, radius=0.2, count=[16, 16])
    turn = trimesh.transformations.rotation_matrix(0.7, [1.0, 0.0, 0.0])
    turned = mesh.copy().apply_transform(turn)
    axis = turn[:3, :3] @ [0.0, 0.0, 1.0]
    (a,) = horizontal_outlines(mesh.vertices, mesh.faces, [0.1])[0]
    (b,) = cut_outlines(turned, 0.1 * axis, axis)
    assert b.area == pytest.approx(a.area, rel=1e-9)
