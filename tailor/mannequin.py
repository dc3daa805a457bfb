"""The parametric mannequin: a smooth, watertight human form from tape measurements.

The body is an implicit surface: a smooth union (polynomial smooth-min) of a lofted torso (an
elliptical cross-section at every height, interpolated through the measured bust, waist, hips…),
a neck and head, tapered capsules for upper arms, forearms, thighs and shins, and ellipsoids for
hands, calves and feet. Smooth union blends shoulders, armpits and crotch the way a dress form's
are blended. Marching cubes (scikit-image) turns the field into a watertight triangle mesh, a
few Taubin steps smooth it, and the torso is calibrated so its measured girths match the tape.

Every primitive belongs to a bone of a small skeleton; skinning weights come from the same
field (a vertex follows the primitives it lies on), so the walk cycle bends elbows and knees
smoothly. Metres, Z up, feet on z = 0, facing −Y, the body's left on +X.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, replace

import numpy as np

from .errors import BodyError
from .sections import horizontal_outlines
from .units import CM, DEG

__all__ = ["Measurements", "MEASUREMENT_PRESETS", "Mannequin", "make_mannequin", "walk_cycle", "BONES"]


POSE_ANGLES = {"arm_angle": (0.0, 80.0 * DEG), "arm_forward": (-45.0 * DEG, 45.0 * DEG), "leg_spread": (-5.0 * DEG, 30.0 * DEG)}
"""Ranges of the pose angles [rad]: arms below horizontal (0: T-pose), arms swung forward (+) or
back (−) from the frontal plane, each leg out from vertical (−: the legs pressed together)."""


@dataclass(frozen=True, slots=True)
class Measurements:
    """Tape measurements of a body [m], its pose angles and the shoulders' slope [rad].

    Heights are derived from lengths the way GarmentCode's body parameters are: the shoulder
    line sits ``head`` below the top of the head at the neck and falls ``shoulder_slope``
    (GarmentCode's ``shoulder_incl``) towards the shoulder tips; bust, waist, hips and crotch
    follow downwards.
    """

    height: float = 1.7199
    bust: float = 0.998407
    underbust: float = 0.862455
    waist: float = 0.843338
    hips: float = 1.03478
    thigh: float = 0.602039
    neck_width: float = 0.189328
    wrist: float = 0.165945
    shoulder_width: float = 0.364568
    arm_length: float = 0.539697
    arm_angle: float = 45.483 * DEG
    shoulder_slope: float = 21.6777 * DEG
    head: float = 0.263262
    shoulder_to_bust: float = 0.256947
    shoulder_to_waist: float = 0.368913
    waist_to_hips: float = 0.234837
    hips_to_crotch: float = 0.0881363
    arm_forward: float = 0.0
    leg_spread: float = 0.0

    def __post_init__(self):
        for k, v in asdict(self).items():
            if not (isinstance(v, (int, float)) and math.isfinite(v) and (v > 0 or k in POSE_ANGLES)):
                raise BodyError(f"measurement {k} must be a positive number, got {v!r}")
        for k, (lo, hi) in POSE_ANGLES.items():
            if not lo <= getattr(self, k) <= hi:
                raise BodyError(f"{k} must be between {lo / DEG:g} and {hi / DEG:g} degrees, got {getattr(self, k) / DEG:g}")
        if not 1.0 <= self.height <= 2.5:
            raise BodyError(f"height must be between 100 and 250 cm, got {self.height / CM:g} cm")
        if not self.waist < self.hips * 1.3 or not self.bust < self.height:
            raise BodyError("measurements are not those of a human body (waist, hips, bust)")

    # heights of the torso landmarks [m]
    @property
    def shoulder_z(self) -> float:
        return self.height - self.head

    @property
    def acromion_z(self) -> float:
        """Height of the shoulder tip: the shoulder line falls ``shoulder_slope`` from the neck outwards."""
        return self.shoulder_z - math.tan(self.shoulder_slope) * 0.5 * max(self.shoulder_width - self.neck_width, 0.0)

    @property
    def bust_z(self) -> float:
        return self.shoulder_z - self.shoulder_to_bust

    @property
    def waist_z(self) -> float:
        return self.shoulder_z - self.shoulder_to_waist

    @property
    def hips_z(self) -> float:
        return self.waist_z - self.waist_to_hips

    @property
    def crotch_z(self) -> float:
        return self.hips_z - self.hips_to_crotch

    @property
    def knee_z(self) -> float:
        return 0.285 * self.height

    @property
    def ankle_z(self) -> float:
        return 0.05 * self.height


MEASUREMENT_PRESETS = {
    "default": Measurements(),
    "woman": Measurements(),
    "man": Measurements(
        height=1.78, bust=1.00, underbust=0.93, waist=0.86, hips=0.99, thigh=0.56, neck_width=0.21,
        wrist=0.175, shoulder_width=0.44, arm_length=0.58, shoulder_slope=20.0 * DEG, head=0.27, shoulder_to_bust=0.22,
        shoulder_to_waist=0.40, waist_to_hips=0.20, hips_to_crotch=0.09,
    ),
}
"""Named bodies. ``default`` (= ``woman``) is GarmentCode's neutral body (its mean measurements)."""

BONES = (
    "pelvis", "abdomen", "chest", "neck", "head",
    "l_upper_arm", "l_forearm", "l_hand", "r_upper_arm", "r_forearm", "r_hand",
    "l_thigh", "l_shin", "l_foot", "r_thigh", "r_shin", "r_foot",
)
"""Bones of the skeleton, in skinning-weight column order."""


def _ellipse_axes(circumference: float, aspect: float):
    """Semi-axes (a, b = aspect·a) of an ellipse of the given perimeter (Ramanujan II)."""
    h = ((1 - aspect) / (1 + aspect)) ** 2
    factor = math.pi * (1 + aspect) * (1 + 3 * h / (10 + math.sqrt(4 - 3 * h)))
    a = circumference / factor
    return a, aspect * a


def _smin(a, b, k):
    """Polynomial smooth minimum (blends within k)."""
    h = np.clip(0.5 + 0.5 * (b - a) / k, 0.0, 1.0)
    return b + (a - b) * h - k * h * (1.0 - h)


def _round_cone(p, a, b, ra, rb):
    """Signed distance to a capsule from a (radius ra) to b (radius rb) (Quilez's round cone)."""
    ba = b - a
    l2 = float(ba @ ba)
    rr = ra - rb
    a2 = l2 - rr * rr
    il2 = 1.0 / l2
    pa = p - a
    y = pa @ ba
    z = y - l2
    xv = pa * l2 - np.outer(y, ba)
    x2 = np.einsum("ij,ij->i", xv, xv)
    y2 = y * y * l2
    z2 = z * z * l2
    k = math.copysign(1.0, rr) * rr * rr * x2
    d = np.where(
        np.sign(z) * a2 * z2 > k,
        np.sqrt(x2 + z2) * il2 - rb,
        np.where(np.sign(y) * a2 * y2 < k, np.sqrt(x2 + y2) * il2 - ra, (np.sqrt(x2 * a2 * il2) + y * rr) * il2 - ra),
    )
    return d


def _ellipsoid(p, c, r):
    """Approximate signed distance to an axis-aligned ellipsoid (Quilez's bound)."""
    q = (p - c) / r
    k0 = np.linalg.norm(q, axis=1)
    k1 = np.linalg.norm(q / r, axis=1)
    return k0 * (k0 - 1.0) / np.maximum(k1, 1e-12)


@dataclass(frozen=True)
class _Torso:
    z: np.ndarray  # ring heights
    a: np.ndarray  # half widths
    b: np.ndarray  # half depths
    y: np.ndarray  # centre offsets along y (+ = back)
    slope: float = 0.0  # fall of the top per unit |x| beyond the neck (tan of the shoulder slope)
    neck: float = 0.0  # half width of the level top at the neck

    def sdf(self, p):
        from scipy.interpolate import PchipInterpolator

        z = np.clip(p[:, 2], self.z[0], self.z[-1])
        a = PchipInterpolator(self.z, self.a)(z)
        b = PchipInterpolator(self.z, self.b)(z)
        cy = PchipInterpolator(self.z, self.y)(z)
        rho = np.sqrt((p[:, 0] / a) ** 2 + ((p[:, 1] - cy) / b) ** 2)
        side = (rho - 1.0) * np.minimum(a, b)
        top = self.z[-1] - self.slope * np.maximum(np.abs(p[:, 0]) - self.neck, 0.0)
        caps = np.maximum(self.z[0] - p[:, 2], p[:, 2] - top)
        return np.maximum(side, caps)


def _torso_rings(m: Measurements, scale=None) -> _Torso:
    s = np.ones(9) if scale is None else scale
    k = m.height / 1.72  # offsets drawn on a 172 cm body, scaled to this one (a child's rings stay in order)
    rows = [  # (z, circumference, depth/width, centre y)
        (m.crotch_z + 0.012 * k, 0.86 * m.hips, 0.80, 0.012),
        (m.hips_z, m.hips, 0.80, 0.015),
        (0.5 * (m.hips_z + m.waist_z), 0.5 * (m.hips + m.waist), 0.74, 0.008),
        (m.waist_z, m.waist, 0.72, 0.0),
        (0.5 * (m.waist_z + m.bust_z) + 0.01 * k, m.underbust, 0.74, -0.003),
        (m.bust_z, m.bust, 0.77, -0.007),
        (m.bust_z + 0.085 * k, 0.96 * m.bust, 0.68, 0.004),
        (m.shoulder_z - 0.035 * k, 0.95 * m.bust, 0.52, 0.012),
        (m.shoulder_z + 0.005 * k, 0.62 * m.bust, 0.55, 0.012),
    ]
    z, a, b, y = [], [], [], []
    for (zz, circ, aspect, cy), f in zip(rows, s):
        aa, bb = _ellipse_axes(circ * f, aspect)
        z.append(zz)
        a.append(aa)
        b.append(bb)
        y.append(cy)
    return _Torso(np.array(z), np.array(a), np.array(b), np.array(y), math.tan(m.shoulder_slope), 0.5 * m.neck_width)


def _skeleton(m: Measurements) -> dict:
    """Rest-pose joint positions [m] (A-pose)."""
    j = {}
    j["pelvis"] = np.array([0.0, 0.005, m.hips_z])
    j["abdomen"] = np.array([0.0, 0.0, m.waist_z])
    j["chest"] = np.array([0.0, 0.0, m.bust_z])
    j["neck"] = np.array([0.0, 0.012, m.shoulder_z - 0.01])
    j["head"] = np.array([0.0, 0.005, m.height - 0.105])
    down = m.arm_angle
    upper, fore = 0.54 * m.arm_length, 0.46 * m.arm_length
    for side, sx in (("l", 1.0), ("r", -1.0)):
        d = np.array([sx * math.cos(down), -math.sin(down) * math.sin(m.arm_forward), -math.sin(down) * math.cos(m.arm_forward)])
        sh = np.array([sx * (0.5 * m.shoulder_width - 0.035), 0.012, m.acromion_z - 0.04])
        j[f"{side}_shoulder"] = sh
        j[f"{side}_elbow"] = sh + upper * d
        j[f"{side}_wrist"] = sh + (upper + fore) * d
        wide = _scales(m)["hips"]  # legs stand apart as wide as the hips are
        hip = np.array([sx * 0.102 * wide, 0.005, m.crotch_z + 0.06])
        j[f"{side}_hip"] = hip
        spread = _rotation([0.0, 1.0, 0.0], -sx * m.leg_spread)  # the leg swings out about the hip
        j[f"{side}_knee"] = hip + spread @ (np.array([sx * 0.095 * wide, 0.0, m.knee_z]) - hip)
        j[f"{side}_ankle"] = hip + spread @ (np.array([sx * 0.098 * wide, 0.02, m.ankle_z]) - hip)
    return j


def _scales(m: Measurements) -> dict:
    """Sizes of this body over the default's: limbs, hands and feet drawn for the default scale with
    them (1 for the default body), so a child or a heavy body has limbs of its own proportions."""
    base = MEASUREMENT_PRESETS["default"]
    return {"height": m.height / base.height, "hips": m.hips / base.hips, "arm": m.bust / base.bust,
            "leg": m.thigh / base.thigh}


def _primitives(m: Measurements, torso: _Torso, j: dict):
    """(bone, sdf function, blend radius) of every body part."""
    thigh_r = m.thigh / (2 * math.pi)
    wrist_r = m.wrist / (2 * math.pi)
    neck_r = 0.31 * m.neck_width
    k = _scales(m)
    arm, leg, size = k["arm"], k["leg"], k["height"]
    prims = [
        ("chest", torso.sdf, 0.0),
        ("neck", lambda p: _round_cone(p, j["neck"] - [0, 0, 0.03], j["head"] - [0, 0, 0.06], neck_r, neck_r * 0.95), 0.02),
        ("head", lambda p: _ellipsoid(p, j["head"] - [0, 0.008, 0.0], np.array([0.078, 0.098, 0.115]) * m.height / 1.72), 0.02),
    ]
    for side, sx in (("l", 1.0), ("r", -1.0)):
        sh, el, wr = j[f"{side}_shoulder"], j[f"{side}_elbow"], j[f"{side}_wrist"]
        d = (wr - el) / np.linalg.norm(wr - el)
        hip, kn, an = j[f"{side}_hip"], j[f"{side}_knee"], j[f"{side}_ankle"]
        prims += [
            (f"{side}_upper_arm", lambda p, sh=sh, el=el: _round_cone(p, sh, el, 0.048 * arm, 0.037 * arm), 0.025),
            (f"{side}_forearm", lambda p, el=el, wr=wr: _round_cone(p, el, wr, 0.037 * arm, wrist_r), 0.01),
            (f"{side}_hand", lambda p, wr=wr, d=d: _ellipsoid(p, wr + 0.06 * size * d, np.array([0.045, 0.022, 0.05]) * size), 0.02),
            (f"{side}_thigh", lambda p, hip=hip, kn=kn: _round_cone(p, hip, kn, thigh_r * 0.97, 0.058 * leg), 0.035),
            (f"{side}_shin", lambda p, kn=kn, an=an: _round_cone(p, kn, an, 0.056 * leg, 0.034 * leg), 0.015),
            (f"{side}_shin", lambda p, kn=kn, an=an: _ellipsoid(p, 0.6 * kn + 0.4 * an + [0, 0.012, 0.03], np.array([0.055, 0.058, 0.11]) * leg), 0.03),
            (f"{side}_foot", lambda p, an=an: _ellipsoid(p, an + np.array([0.0, -0.065, 0.028]) * size - [0.0, 0.0, m.ankle_z],
                                                           np.array([0.045, 0.125, 0.042]) * size), 0.025),
        ]
    return prims


def _field(points, prims):
    """Smooth-union distance and each primitive's own distance, shapes (n,), (n, P).

    Each limb is blended along its own chain, the left and right limbs are joined by a hard
    union (so thighs and arms never melt into each other), and the limbs then blend into the
    trunk: smooth shoulders, armpits and crotch with a gap between the legs.
    """
    each = np.column_stack([f(points) for _, f, _ in prims])
    groups: dict = {}
    for k, (bone, _, blend) in enumerate(prims):
        key = bone.split("_", 1)[1] if bone[:2] in ("l_", "r_") else "trunk"
        group = "arm" if key in ("upper_arm", "forearm", "hand") else "leg" if key in ("thigh", "shin", "foot") else "trunk"
        chain = (group, bone[:1]) if group != "trunk" else ("trunk", "")
        d, k_join = groups.get(chain, (None, blend))
        groups[chain] = (each[:, k] if d is None else _smin(d, each[:, k], blend), k_join if d is not None else blend)
    d = groups[("trunk", "")][0]
    for group, blend in (("arm", 0.022), ("leg", 0.03)):
        limbs = np.minimum(groups[(group, "l")][0], groups[(group, "r")][0])
        d = _smin(d, limbs, blend)
    d = np.maximum(d, -points[:, 2])  # flat soles on the floor
    return d, each


@dataclass(frozen=True, eq=False)
class Mannequin:
    """A generated body in its rest (A-) pose.

    Attributes
    ----------
    vertices : (N, 3) [m]; faces : (F, 3) int
    joints : dict name → (3,) [m]
    weights : (N, len(BONES)) skinning weights, rows sum to 1
    measurements : Measurements
    """

    vertices: np.ndarray
    faces: np.ndarray
    joints: dict
    weights: np.ndarray
    measurements: Measurements


def _mesh(m: Measurements, torso, joints, resolution):
    from skimage.measure import marching_cubes

    prims = _primitives(m, torso, joints)
    reach = (m.arm_length + 0.12) * math.sin(m.arm_angle) * abs(math.sin(m.arm_forward))  # arms swung forward or back
    deep = max(1.0, max(m.hips, m.bust) / MEASUREMENT_PRESETS["default"].hips)  # room front and back for a heavy body
    lo = np.array([-(0.5 * m.shoulder_width + m.arm_length + 0.12), -0.22 * deep - reach, -0.02])
    hi = np.array([-lo[0], 0.2 * deep + reach, m.height + 0.02])
    shape = np.ceil((hi - lo) / resolution).astype(int) + 1
    axes = [lo[k] + resolution * np.arange(shape[k]) for k in range(3)]
    grid = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
    d, _ = _field(grid, prims)
    verts, faces, _, _ = marching_cubes(d.reshape(shape), level=0.0, spacing=(resolution,) * 3)
    verts = verts + lo
    return verts, faces.astype(np.intp), prims


def _largest_component(vertices, faces):
    import trimesh

    mesh = trimesh.Trimesh(vertices, faces, process=True)
    parts = mesh.split(only_watertight=False)
    best = max(parts, key=lambda p: len(p.faces))
    trimesh.smoothing.filter_taubin(best, iterations=10)
    return np.asarray(best.vertices), np.asarray(best.faces, dtype=np.intp)


def _girth(vertices, faces, z):
    """Convex-hull perimeter (a tape measure) of the torso's cross-section at height z [m]: the
    outline round the body's axis (the arms and hands are others)."""
    from shapely.geometry import Point

    polys = horizontal_outlines(vertices, faces, [z])[0]
    trunk = [p for p in polys if p.contains(Point(0.0, 0.0))]
    return trunk[0].convex_hull.length if trunk else 0.0


def make_mannequin(measurements: Measurements | None = None, *, resolution: float = 0.016, calibrate: int = 3) -> Mannequin:
    """Generate the mannequin for ``measurements`` (default: GarmentCode's neutral body).

    Parameters
    ----------
    resolution : float
        Marching-cubes grid step [m]; 0.016 gives ≈ 19k triangles.
    calibrate : int
        Rounds of rescaling the torso rings so bust, underbust, waist and hips girths match.
    """
    m = measurements or Measurements()
    joints = _skeleton(m)
    scale = np.ones(9)
    targets = {1: (m.hips_z, m.hips), 3: (m.waist_z, m.waist), 4: (0.5 * (m.waist_z + m.bust_z) + 0.01 * m.height / 1.72, m.underbust),
               5: (m.bust_z, m.bust)}
    for round_ in range(calibrate + 1):
        torso = _torso_rings(m, scale)
        verts, faces, prims = _mesh(m, torso, joints, resolution)
        verts, faces = _largest_component(verts, faces)
        if round_ == calibrate:
            break
        for ring, (z, target) in targets.items():
            g = _girth(verts, faces, z)
            if g > 0:
                scale[ring] *= target / g
        scale[0] = scale[1]
        scale[2] = 0.5 * (scale[1] + scale[3])
        scale[6] = scale[7] = scale[5]
    verts[:, 2] -= verts[:, 2].min()  # smoothing rounds the soles a hair below the floor
    _, each = _field(verts, prims)
    weights = _skin_weights(verts, each, prims, m)
    return Mannequin(verts, faces, joints, weights, m)


def _skin_weights(verts, each, prims, m):
    """Bone weights from the field: a vertex follows the primitives it lies on (softmax of −d)."""
    w = np.zeros((len(verts), len(BONES)))
    sharp = np.exp(-np.maximum(each, 0.0) / 0.012)
    for k, (bone, _, _) in enumerate(prims):
        if bone == "chest":  # split the torso by height into pelvis, abdomen, chest
            z = verts[:, 2]
            t_low = np.clip((z - m.hips_z) / max(m.waist_z - m.hips_z, 1e-6), 0, 1)
            t_high = np.clip((z - m.waist_z) / max(m.bust_z - m.waist_z, 1e-6), 0, 1)
            w[:, BONES.index("pelvis")] += sharp[:, k] * (1 - t_low)
            w[:, BONES.index("abdomen")] += sharp[:, k] * t_low * (1 - t_high)
            w[:, BONES.index("chest")] += sharp[:, k] * t_high
        else:
            w[:, BONES.index(bone)] += sharp[:, k]
    return w / np.maximum(w.sum(axis=1, keepdims=True), 1e-12)


def _rotation(axis, angle):
    axis = np.asarray(axis, float) / np.linalg.norm(axis)
    x, y, z = axis
    c, s = math.cos(angle), math.sin(angle)
    return np.array([
        [c + x * x * (1 - c), x * y * (1 - c) - z * s, x * z * (1 - c) + y * s],
        [y * x * (1 - c) + z * s, c + y * y * (1 - c), y * z * (1 - c) - x * s],
        [z * x * (1 - c) - y * s, z * y * (1 - c) + x * s, c + z * z * (1 - c)],
    ])


def _pose(j, phase):
    """Bone transforms (R, t) at walk phase in [0, 1): legs swing, knees bend, arms counter-swing."""
    w = 2 * math.pi * phase
    hip_l, hip_r = 0.38 * math.sin(w), -0.38 * math.sin(w)  # flexion [rad], + = leg forward
    knee_l = 0.55 * max(0.0, math.sin(w + 1.3)) + 0.08
    knee_r = 0.55 * max(0.0, math.sin(w + 1.3 + math.pi)) + 0.08
    arm_l, arm_r = -0.25 * math.sin(w), 0.25 * math.sin(w)
    twist = 0.06 * math.sin(w)  # pelvis/torso counter-rotation about z
    x_axis = np.array([1.0, 0.0, 0.0])
    out = {}

    def about(rot, pivot):
        return rot, pivot - rot @ pivot

    def chain(parent, rot, pivot):
        pr, pt = parent
        r2, t2 = about(rot, pivot)
        return pr @ r2, pr @ t2 + pt

    ident = (np.eye(3), np.zeros(3))
    pelvis = about(_rotation([0, 0, 1], twist), j["pelvis"])
    chest = about(_rotation([0, 0, 1], -1.5 * twist), j["chest"])
    out["pelvis"] = pelvis
    out["abdomen"] = about(_rotation([0, 0, 1], -0.3 * twist), j["abdomen"])
    out["chest"] = chest
    out["neck"] = chest
    out["head"] = chest
    for side, hip_a, knee_a, arm_a in (("l", hip_l, knee_l, arm_l), ("r", hip_r, knee_r, arm_r)):
        # leg forward = toward −Y: rotate about +x by −angle
        thigh = chain(pelvis, _rotation(x_axis, -hip_a), j[f"{side}_hip"])
        shin = chain(thigh, _rotation(x_axis, knee_a), j[f"{side}_knee"])
        foot = chain(shin, _rotation(x_axis, -0.5 * knee_a + 0.3 * hip_a), j[f"{side}_ankle"])
        out[f"{side}_thigh"], out[f"{side}_shin"], out[f"{side}_foot"] = thigh, shin, foot
        upper = chain(chest, _rotation(x_axis, -arm_a), j[f"{side}_shoulder"])
        fore = chain(upper, _rotation(x_axis, -0.25 - 0.2 * max(0.0, -arm_a)), j[f"{side}_elbow"])
        out[f"{side}_upper_arm"], out[f"{side}_forearm"], out[f"{side}_hand"] = upper, fore, fore
    del ident
    return out


def walk_cycle(mannequin: Mannequin, *, frames: int = 25, period: float = 1.0) -> np.ndarray:
    """Vertex positions of a walk in place, one cycle, shape (frames, N, 3) [m].

    Linear blend skinning of the rest mesh; each frame is lifted so the lowest point touches the
    floor (z = 0), so the feet never go below it.
    """
    v = mannequin.vertices
    out = np.empty((frames, len(v), 3))
    for f in range(frames):
        pose = _pose(mannequin.joints, (f / frames) % 1.0)
        acc = np.zeros_like(v)
        for b, bone in enumerate(BONES):
            wb = mannequin.weights[:, b]
            if not wb.any():
                continue
            rot, t = pose[bone]
            acc += wb[:, None] * (v @ rot.T + t)
        acc[:, 2] -= acc[:, 2].min()
        out[f] = acc
    return out


def with_measurements(base: Measurements, **cm_values) -> Measurements:
    """A copy of ``base`` with some measurements replaced, given in cm (angles in degrees)."""
    values = {k: (v * DEG if k in ("shoulder_slope", *POSE_ANGLES) else v * CM) for k, v in cm_values.items() if v is not None}
    return replace(base, **values)
