"""AAMA / ASTM DXF pattern files written with ezdxf, in several exporters' dialects, for the tests."""

import numpy as np

GORE = np.array([[-21.0, 0.0], [21.0, 0.0], [11.0, 60.0], [-11.0, 60.0]])  # cm, counter-clockwise
HEM_SAG = 1.5  # the hem curves down this much [cm] in its middle


def gore_outline(points=7):
    """(outline, corner flags): the gore with its curved hem sampled at ``points`` points."""
    t = np.linspace(0.0, 1.0, points)[1:-1]
    hem = np.column_stack([-21.0 + 42.0 * t, -HEM_SAG * np.sin(np.pi * t)])
    outline = np.vstack([GORE[:1], hem, GORE[1:]])
    corners = np.zeros(len(outline), bool)
    corners[[0, len(hem) + 1, len(hem) + 2, len(hem) + 3]] = True
    return outline, corners


def side_point(outline, start, end, from_top):
    """The point ``from_top`` cm down the straight side from vertex ``start`` (top) towards ``end``."""
    a, b = outline[start], outline[end]
    return a + (b - a) * from_top / np.linalg.norm(b - a)


# which side carries which seam: notches [cm from the waist] on the left (−x) and right (+x) sides
FOUR_GORES = {"Front Left": ([20.0], [35.0]), "Front Right": ([35.0], [20.0]),
              "Back Left": ([35.0], [20.0, 21.0]), "Back Right": ([20.0, 21.0], [35.0])}


def write_aama(path, pieces=FOUR_GORES, *, scale=10.0, units_text="METRIC", lwpolyline=True, notch_points=False,
               quantity=None, sizes=(None,), insunits=None, turn_points=True, mirror_text=None):
    """Write a skirt of gores as an AAMA DXF: one block per piece (and size), inserted in model space.
    ``scale`` file units per cm (10: millimetres)."""
    import ezdxf

    doc = ezdxf.new("R2000" if lwpolyline else "R12")
    if insunits is not None:
        doc.header["$INSUNITS"] = insunits
    msp = doc.modelspace()
    if units_text:
        msp.add_text(f"Units: {units_text}", dxfattribs={"layer": "1"})
    outline, corners = gore_outline()
    k = 0
    for size in sizes:
        grow = 1.0 if size in (None, "M") else 1.05
        for name, (left, right) in pieces.items():
            pts = outline * [grow, 1.0] * scale
            block = doc.blocks.new(f"P{k}")
            if lwpolyline:
                block.add_lwpolyline([tuple(p) for p in pts], close=True, dxfattribs={"layer": "1"})
            else:
                block.add_polyline2d([tuple(p) for p in pts], close=True, dxfattribs={"layer": "1"})
            for p, c in zip(pts, corners):
                if turn_points or not c:
                    block.add_point(tuple(p), dxfattribs={"layer": "2" if c else "3"})
            block.add_line((0, 10 * scale), (0, 50 * scale), dxfattribs={"layer": "7"})
            n = len(pts)
            marks = [side_point(pts / scale, n - 1, 0, d) for d in left] + [side_point(pts / scale, n - 2, n - 3, d) for d in right]
            for m in marks:
                m = m * scale
                if notch_points:
                    block.add_point(tuple(m), dxfattribs={"layer": "4"})
                else:
                    inward = np.array([1.0 if m[0] < 0 else -1.0, 0.0]) * 0.5 * scale
                    block.add_line(tuple(m), tuple(m + inward), dxfattribs={"layer": "4"})
            block.add_circle((0, 30 * scale), 0.2 * scale, dxfattribs={"layer": "13"})
            block.add_text(f"Piece Name: {name}", dxfattribs={"layer": "15"})
            block.add_text(f"Quantity: {quantity or 1}", dxfattribs={"layer": "15"})
            if mirror_text:
                block.add_text(f"Mirror: {mirror_text}", dxfattribs={"layer": "15"})
            block.add_text("Category: Skirt", dxfattribs={"layer": "15"})
            if size:
                block.add_text(f"Size: {size}", dxfattribs={"layer": "15"})
            msp.add_blockref(f"P{k}", (k * 60 * scale, 0))
            k += 1
    doc.saveas(path)
    return path
