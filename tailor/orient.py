"""Which way a human mesh stands: its parts, up axis, units, trunk centre and facing.

Every detection reads the body's shape, never where the file put its origin:

* **parts**: duplicate vertices are welded (STL and UV-split OBJ), then the mesh is split into
  connected parts (a mesh whose median edge is a tenth of its size is no surface: refused). Parts under 2 % of the largest's area (eyes, teeth, lashes, tongue, buttons)
  are dropped; a second part of the largest's size beside it (not overlapping) is a second person.
* **up**: the major principal axis of the surface's area (a standing body is tallest; a T-pose's
  arm span puts only the thin arms far out, so even when it is as wide as tall the spread along
  it is half that along the body), snapped to a file axis within 10°; its sign puts the wide end
  (the feet, toe to heel) down and the narrow one (the crown of the head) up.
* **units**: the height that makes a standing human (0.8–2.5 m) in m, dm, cm or mm.
* **trunk centre**: the area centroid of the trunk's outlines between 50 % and 70 % of the
  height (the trunk is the largest outline there; hands and fingers are small beside it).
* **facing**: the trunk is wider than deep, so the front–back axis is the minor axis of those
  outlines; the feet say which way along it (toes stick out forward from the ankles).
"""

from __future__ import annotations

import numpy as np

from .errors import BodyError
from .geometry import connected_components, face_areas
from .sections import horizontal_outlines, second_moments

__all__ = ["weld", "body_parts", "up_rotation", "detect_units", "trunk_frame", "foot_offsets", "forward", "UNITS", "AXES"]

UNITS = {"m": 1.0, "dm": 0.1, "cm": 0.01, "mm": 0.001}
"""Length units a body file may be in, to metres."""

AXES = {"x": 0, "y": 1, "z": 2}
"""Axis names for ``up`` and ``facing``."""

STANDING = (0.8, 2.5)
"""Heights [m] of the standing humans units are detected for (a small child to a very tall adult)."""

SNAP = np.cos(np.radians(10.0))
"""A detected direction within 10° of a file axis is taken to be that axis."""


def weld(frames, faces):
    """Merge vertices at the same place in the first frame; returns (frames, faces)."""
    first = frames[0]
    scale = max(float(np.ptp(first, axis=0).max()), 1e-12)
    key = np.round(first / (scale * 1e-9)).astype(np.int64)
    _, keep, inverse = np.unique(key, axis=0, return_index=True, return_inverse=True)
    if len(keep) == len(first):
        return frames, faces
    order = np.argsort(keep)  # keep the file's vertex order
    rank = np.empty_like(order)
    rank[order] = np.arange(len(order))
    return frames[:, keep[order]], rank[inverse.ravel()][faces]


def _part_boxes(vertices, label, count):
    lo = np.full((count, 3), np.inf)
    hi = np.full((count, 3), -np.inf)
    np.minimum.at(lo, label, vertices)
    np.maximum.at(hi, label, vertices)
    return lo, hi


def body_parts(frames, faces, source="body"):
    """Keep the body's parts: (frames, faces, how many small parts were dropped).

    Raises
    ------
    BodyError
        Two or more parts the size of a person side by side.
    """
    faces = faces[(faces[:, 0] != faces[:, 1]) & (faces[:, 1] != faces[:, 2]) & (faces[:, 0] != faces[:, 2])]
    if not len(faces):
        raise BodyError(f"{source}: every face is degenerate (repeats a vertex)")
    x = frames[0]
    label = connected_components(len(x), faces)
    count = int(label.max()) + 1
    tri = x[faces]
    area = face_areas(x, faces)
    part_area = np.bincount(label[faces[:, 0]], weights=area, minlength=count)
    main = int(np.argmax(part_area))
    if part_area[main] <= 0:
        raise BodyError(f"{source}: the mesh has no area (every face is flat to a line)")
    edges = np.linalg.norm(tri - np.roll(tri, 1, axis=1), axis=2)
    size = float(np.ptp(x, axis=0).max())
    if len(faces) >= 100 and np.median(edges) > 0.1 * size:  # a body's triangles are small beside it
        raise BodyError(f"{source}: the faces do not make a surface (the median edge is {np.median(edges) / size:.0%} of the "
                        "body's size): are the face indices scrambled?")
    lo, hi = _part_boxes(x, label, count)
    big = np.flatnonzero(part_area >= 0.3 * part_area[main])
    apart = [p for p in big if p != main and (np.any(lo[p] > hi[main]) or np.any(hi[p] < lo[main]))]
    if apart:
        raise BodyError(f"{source}: {len(apart) + 1} separate bodies side by side (parts of a person's size that do not "
                        "touch); give one body a file")
    keep_part = part_area >= 0.02 * part_area[main]
    faces = faces[keep_part[label[faces[:, 0]]]]
    used = np.unique(faces)
    remap = np.full(len(x), -1)
    remap[used] = np.arange(len(used))
    dropped = int(np.count_nonzero(~keep_part & (part_area > 0)))
    return frames[:, used], remap[faces], dropped


def _minimal_rotation(u) -> np.ndarray:
    """The rotation taking unit ``u`` to +Z about their common normal (180° about x for −Z)."""
    z = np.array([0.0, 0.0, 1.0])
    c = float(u @ z)
    if c < -1.0 + 1e-12:
        return np.diag([1.0, -1.0, -1.0])
    k = np.cross(u, z)
    kx = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    return np.eye(3) + kx + kx @ kx / (1.0 + c)


def _snap(u):
    """``u`` snapped to the nearest signed axis when within 10° of it; (unit vector, name or None)."""
    u = u / np.linalg.norm(u)
    k = int(np.argmax(np.abs(u)))
    if abs(u[k]) >= SNAP:
        out = np.zeros(len(u))
        out[k] = np.sign(u[k])
        return out, ("-" if u[k] < 0 else "+") + "xyz"[k]
    return u, None


def _end_spread(x, up):
    """Horizontal spread (box area) of the lowest and highest 3 % of the body along ``up``."""
    s = x @ up
    lo, hi = s.min(), s.max()
    band = 0.03 * (hi - lo)
    out = []
    for sel in (s < lo + band, s > hi - band):
        p = x[sel] - np.outer(s[sel], up)
        out.append(float(np.prod(np.sort(np.ptp(p, axis=0))[1:])) if len(p) > 2 else 0.0)
    return out


def up_rotation(vertices, faces, up="auto", source="body"):
    """(rotation taking the body's up to +Z, how up was found in file terms)."""
    if up != "auto":
        name = up.lstrip("+-")
        if name not in AXES:
            raise BodyError(f"{source}: up must be auto or an axis like y or -z, got {up!r}")
        u = np.zeros(3)
        u[AXES[name]] = -1.0 if up.startswith("-") else 1.0
        return _minimal_rotation(u), up.lstrip("+")
    area = face_areas(vertices, faces)
    centre = vertices[faces].mean(axis=1)
    mean = (area[:, None] * centre).sum(axis=0) / area.sum()
    d = centre - mean
    cov = (area[:, None, None] * d[:, :, None] * d[:, None, :]).sum(axis=0)
    u = np.linalg.eigh(cov)[1][:, -1]
    u, name = _snap(u)
    feet, head = _end_spread(vertices, u)
    if head > feet:
        u, name = -u, (None if name is None else ("+" if name[0] == "-" else "-") + name[1])
    label = name.lstrip("+") if name else "(" + ", ".join(f"{c:.3f}" for c in u) + ")"
    return _minimal_rotation(u), label


def detect_units(height: float, units="auto", source="body"):
    """(scale to metres, unit name) for a body ``height`` units tall."""
    if units not in ("auto", *UNITS):
        raise BodyError(f"{source}: units must be auto, {', '.join(UNITS)}, got {units!r}")
    fits = [name for name, s in UNITS.items() if STANDING[0] <= height * s <= STANDING[1]]
    if units == "auto":
        if not fits:
            raise BodyError(
                f"{source}: cannot tell the units: the body is {height:g} units tall, which is no standing human "
                f"in m, dm, cm or mm; pass the units explicitly"
            )
        return UNITS[fits[0]], fits[0]
    metres = height * UNITS[units]
    if not 0.3 <= metres <= 3.0:
        hint = f"; its size suggests {fits[0]}" if fits else ""
        raise BodyError(f"{source}: in {units} the body would be {metres * 100:.3g} cm tall, no standing human{hint}")
    return UNITS[units], units


def trunk_frame(vertices, faces):
    """(centre (2,), minor axis (2,), aspect) of the trunk between 50 % and 70 % of the height.

    ``vertices`` stand on z = 0, Z up. The minor axis is the front–back direction (sign unknown);
    aspect is depth over width (near 1: a round trunk tells no direction).
    """
    h = float(vertices[:, 2].max())
    cuts = horizontal_outlines(vertices, faces, np.linspace(0.5, 0.7, 9) * h)
    trunks = [c[0] for c in cuts if c]
    if not trunks:
        raise BodyError("no trunk found between 50 % and 70 % of the height: is this a standing human?")
    areas = np.array([t.area for t in trunks])
    cents = np.array([t.centroid.coords[0] for t in trunks])
    centre = (areas[:, None] * cents).sum(axis=0) / areas.sum()
    moments = sum(a * (second_moments(t) + np.outer(c - centre, c - centre)) for a, t, c in zip(areas, trunks, cents))
    w, vec = np.linalg.eigh(moments)
    return centre, vec[:, 0], float(np.sqrt(max(w[0], 0.0) / max(w[1], 1e-300)))


def foot_offsets(vertices, lateral, centre):
    """Horizontal offsets from each planted foot's ankle to the foot's centre (toes pull it forward).

    ``lateral`` is the body's left–right axis and ``centre`` its trunk centre (2D): the floor slab
    is split into the two feet on either side of the centre.
    """
    z = vertices[:, 2]
    h = np.ptp(z)
    low_sel = z < z.min() + 0.03 * h
    ankle_sel = (z > z.min() + 0.05 * h) & (z < z.min() + 0.08 * h)
    out = []
    for side in (1.0, -1.0):
        low = vertices[low_sel][:, :2]
        low = low[side * ((low - centre) @ lateral) > 0]
        ankles = vertices[ankle_sel][:, :2]
        ankles = ankles[side * ((ankles - centre) @ lateral) > 0]
        if len(low) < 3 or len(ankles) < 3:
            continue
        foot = low.mean(axis=0)
        near = ankles[np.linalg.norm(ankles - foot, axis=1) < 0.08 * h]
        if len(near) >= 3:
            out.append(foot - near.mean(axis=0))
    return out


def forward(frames, faces):
    """Horizontal unit vector (3,) the body faces, and its trunk centre (2,) in the first frame.

    ``frames`` stand on z = 0, Z up. The minor axis of the trunk gives the line; the feet of every
    frame (a lifted foot is not in the floor slab) give the sign. With neither, the body is taken to
    face −Y, the convention of Z-up files (and of Y-up files facing +Z).
    """
    centre, minor, aspect = trunk_frame(frames[0], faces)
    lateral = np.array([minor[1], -minor[0]])
    offsets = [o for x in frames for o in foot_offsets(x, lateral, centre + (x[:, :2].mean(axis=0) - frames[0][:, :2].mean(axis=0)))]
    toes = np.mean(offsets, axis=0) if offsets else np.zeros(2)
    h = float(np.ptp(frames[0][:, 2]))
    if aspect > 0.92:  # a round trunk: the feet alone say where the body faces
        line = toes if np.linalg.norm(toes) > 0.005 * h else np.array([0.0, -1.0])
    else:
        line = minor
    along = float(toes @ line)
    if abs(along) < 0.005 * h:
        along = -line[1] if abs(line[1]) > 1e-9 else 1.0  # no clear feet: the one nearer −Y
    d = np.sign(along) * line / np.linalg.norm(line)
    out, _ = _snap(np.array([d[0], d[1], 0.0]))
    return out, centre
