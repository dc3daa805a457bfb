"""What a drape is asked to do (:class:`DrapeOptions`) and what each of its phases does (:class:`PhaseSettings`).

Every threshold of the dressing lives here, with the reason for its value.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..collide import SELF_COLLISION_MODES
from ..contact import ContactSettings
from ..errors import SimulationError
from ..fabric import Fabric, preset
from ..integrators import INTEGRATORS
from ..sim import DEFAULT_QUALITY, QUALITY
from ..tearing import Cut

__all__ = ["DrapeOptions", "PhaseSettings", "SEWING", "SETTLE_QUALITY", "SETTLE_STEP_PER_RESOLUTION", "SETTLE_RAMP", "settle_step", "SETTLING", "TRANSITION", "MOTION", "DRAPE_RESOLUTION", "FREE_SEW_STEP",
           "NEAR_SEAM", "ANCHORED_NEAR", "NEAR_RATE", "COMPRESSION", "TRANSITION_S", "TRANSITION_SPEED", "TRANSITION_KEYS_PER_S", "transition_seconds", "STRAGGLERS", "MIN_STRAGGLERS",
           "STRAGGLER_REACH", "BLOCKED_OVER", "WELD_BATCH", "REST_SPEED", "REST_FRAMES", "FREEZE_STRETCH", "FREEZE_RINGS", "SLEEP_REACH", "MOTION_MAX_STRETCH", "MOTION_STRETCH_GROWTH", "ROUTE_BEYOND", "ROUTE_AFTER",
           "TUCK_BELOW", "TUCK_GATHER_TIME", "TUCK_ROW"]

DRAPE_RESOLUTION = 0.02
"""Default garment mesh edge length [m] of :func:`~tailor.dress.drape` and ``tailor drape`` (2 cm)."""

NEAR_SEAM = 0.08
"""Seam pairs closer than this [m] are pulled by stiff implicit springs."""

ANCHORED_NEAR = 0.02
"""... those joining a panel held while sewing (a waistband at the waist) to a free one, closer than
this (:meth:`~tailor.seams.Sewing.anchor`): from farther, such springs stretched the held band
down to the free panel (docs/measurements.md, "Sixth day")."""

ROUTE_BEYOND = 0.04
"""Seam pairs farther apart than this [m] whose midpoint is inside the body meet at a point over it
(:meth:`~tailor.seams.Sewing.route_around`): a sleeveless dress's straps, placed flat in front of and
behind the shoulder, are drawn over it instead of into it (docs/measurements.md, "Seams round the
body")."""

BLOCKED_OVER = 0.1
"""Seam pairs whose straight way runs through the body at placement, their midpoint less than this
[m] under its top (a strap's ends either side of the shoulder), are routed over it from the start
(:meth:`~tailor.seams.Sewing.block`)."""

ROUTE_AFTER = 0.25
"""... once this fraction of the sewing time-out has passed: a garment that sews in that time (most
close within a second) is sewn by straight pulls alone; routed from the start, sleeves' underarm
pairs were drawn round the arm and through each other."""

NEAR_RATE = 80000.0
"""Their rate k [1/s²] (Eq. 15's k·η folded in): strong enough to stretch a waistband into place."""

COMPRESSION = 0.1
"""Fraction of the stretch stiffness resisting compression in garments (eased seams gather)."""

TRANSITION_SPEED = 1.0
"""Speed [m/s] of the body point that moves farthest while a body dressed in its rest pose moves into
the first frame of its motion: half a walk's fastest (a foot's 2 m/s), so the transition never
shortens the steps more than the motion does."""

TRANSITION_S = (0.2, 1.0)
"""Shortest and longest transition [s]: the shipped walk's 27 cm (a hand) takes 0.27 s."""

TRANSITION_KEYS_PER_S = 25.0
"""Key poses (collision hierarchies) per second of transition."""


def transition_seconds(distance: float) -> float:
    """How long a body whose farthest point must travel ``distance`` [m] takes into its motion."""
    lo, hi = TRANSITION_S
    return float(min(max(distance / TRANSITION_SPEED, lo), hi))

MOTION_MAX_STRETCH = 5.0
"""While the body moves, a triangle stretched further than this (or than ``MOTION_STRETCH_GROWTH``
times the dressed garment's worst) means the run has gone wrong; a hem kicked by a heel reaches 4."""

MOTION_STRETCH_GROWTH = 1.5
"""See ``MOTION_MAX_STRETCH``."""

REST_SPEED = 0.02
"""A settling garment is at rest once its vertices' root-mean-square speed (√(2·kinetic energy / mass))
is below this [m/s], under a millimetre a frame, for :data:`REST_FRAMES` frames in a row; settling
then ends early. A sewn T-shirt falls from 0.4 m/s to this in 0.7 s and creeps on at 0.5–1 cm/s for
seconds (sliding over the shoulders)."""

REST_FRAMES = 2
"""See ``REST_SPEED``."""

FREEZE_STRETCH = 1.3
"""An outfit's sewn inner garments are held still while an outer one sews, except round their
triangles stretched beyond this (principal stretch; :meth:`~tailor.dress.garment.Garment.sew_stage`)."""

FREEZE_RINGS = 2
"""Rings of triangles round those left free with them."""

SLEEP_REACH = 0.15
"""[m] Held inner garments' cloth farther than this from every vertex of the outer garment sewing over
them is taken out of the model for that stage (:meth:`~tailor.dress.garment.Garment.sleep_far`), and
all of it is back once the outer garment comes within ⅔ of this of any
(:meth:`~tailor.dress.garment.Garment.wake_near`)."""

WELD_BATCH = 0.2
"""Merged seam pairs are welded (the garment's model rebuilt: the model, the self-collider and a
crossing check) once this fraction of all pairs has merged since the last weld, when a frame merged
none (the welded pairs then zip their neighbours shut; held only by springs, the trousers' last
pairs waited for the stragglers' rule), or when no pair is left sewing. Until then each merged pair
is held by its stiff seam spring (:data:`NEAR_RATE`). Measured in docs/measurements.md."""

STRAGGLERS = 0.02
"""After ¾ of the sewing time-out, when at most this fraction of pairs (or :data:`MIN_STRAGGLERS`) is
still open, those closer than :data:`STRAGGLER_REACH` mesh resolutions are merged where they are: the
last few pairs caught on the body (an underarm corner behind the arm, a dart's mouth) are stitched
as a tailor would."""

MIN_STRAGGLERS = 3
"""See ``STRAGGLERS`` (GarmentCode's fitted dress at 4 cm held its last 3 of 116 pairs)."""

STRAGGLER_REACH = 4.0
"""See ``STRAGGLERS``."""


TUCK_BELOW = 0.02
"""A tuck gathers the inner garments' cloth lower than this [m] above the tucking band's top edge."""
TUCK_GATHER_TIME = 0.2
"""[s] of sewing over which a tuck's cloth is carried onto the body (at once, rows fold over each other)."""
TUCK_ROW = 0.02
"""[m] Height of the rows a tuck draws in, each onto the hull of the body its loop encloses."""


@dataclass(frozen=True, slots=True)
class PhaseSettings:
    """What one phase of a drape does.

    Attributes
    ----------
    name : str
    gravity : bool
        Off while sewing (GarmentCode's zero-gravity warm-up: panels do not sag off the body).
    contact : ContactSettings
        Friction on the body, held contacts, self-collision.
    tolerance : float or None
        CG tolerance of the implicit solve; None: the quality preset's.
    max_stretch_change : float
        Per-step stretch change beyond which an implicit step is halved.
    wind : bool
        Whether the wind blows.
    max_stretch : float or None
        The guard's stretch limit; None: ``MOTION_MAX_STRETCH`` or growth over the dressed garment.
    moving : bool
        Steps follow the near-body speed rule of the timeline (the body moves).
    quasi_static : bool
        Only the phase's end state matters, a static equilibrium (settling): it is stepped at
        :data:`SETTLE_QUALITY`'s step and tolerance in every preset. Backward Euler's fixed point,
        v = 0 where the forces balance, is the same at any step; smaller steps only damp the way
        there less (docs/measurements.md, eleventh day).
    """

    name: str
    gravity: bool
    contact: ContactSettings
    tolerance: float | None
    max_stretch_change: float
    wind: bool
    max_stretch: float | None
    moving: bool
    quasi_static: bool = False


SEWING = PhaseSettings(
    "sewing", gravity=False,
    # panels slide over the body into place without friction; seam edges must be free to meet (the
    # self-collision leaves the open seams and their neighbours free, but not the two sides'
    # neighbourhoods of one pair against each other, and keeps the rest apart)
    contact=ContactSettings(friction_scale=0.0, hold=False, self_collision=True, layers=False),
    # sewing is assembly at the same step in every preset, with stiff seam springs pulling panels
    # metres: a loose solve there blows up (docs/measurements.md)
    tolerance=QUALITY["final"].tolerance,
    # the seams' pull stretches the triangles at the seams far in a step by design (merged and
    # relaxed afterwards): halving those steps only slows the assembly down
    max_stretch_change=math.inf, wind=False,
    # a corner pulled three ways may stretch its triangles this far before merging
    max_stretch=10.0, moving=False)
FREE_SEW_STEP = 0.02
"""[s] The step a garment's sewing takes when it holds none of its heights (a T-shirt, a dress, and
so an outfit's stage sewing one over held trousers): its seams close in about as much simulated
time as at the plain 10 ms step, in half the steps (the pull's damping taken for the step,
:attr:`~tailor.seams.Sewing.step`).
A stage holding a band's heights keeps the plain step: the heights are put back after each step,
and within a longer one the seams drag the band's lower rows further (docs/measurements.md,
twenty-fourth day)."""
SETTLE_QUALITY = QUALITY["draft"]
"""The preset whose tolerance every preset settles at (``PhaseSettings.quasi_static``)."""
SETTLE_STEP_PER_RESOLUTION = 2.0
"""[s/m] Settling steps at this per metre of mesh, at most :data:`SETTLE_QUALITY`'s step (40 ms at
2 cm, twice draft's garment step), after :data:`SETTLE_RAMP`: settling is quasi-static, and its end
state is as far from ``final``'s as at draft's step on the shipped garments, in half the steps."""
SETTLE_RAMP = 0.2
"""[s] The first part of settling, stepped at :data:`SETTLE_QUALITY`'s garment step (20 ms at 2 cm;
the preset's own where that is longer): gravity comes on and the
sewn garment's first fall is settling's fastest motion. Outfits settled at 40 ms from the start
blew up there (a T-shirt tucked into trousers, a T-shirt over a dress at 2.1 cm: a triangle at the
waist or the armpit 16× in the first steps; docs/measurements.md, twenty-eighth day)."""


def settle_step(resolution: float) -> float:
    """The step [s] a garment meshed at ``resolution`` [m] settles at after :data:`SETTLE_RAMP`."""
    return min(SETTLE_QUALITY.step, SETTLE_STEP_PER_RESOLUTION * resolution)


SETTLING = PhaseSettings("settling", gravity=True, contact=ContactSettings(), tolerance=SETTLE_QUALITY.tolerance,
                         max_stretch_change=0.3, wind=True, max_stretch=SEWING.max_stretch, moving=False, quasi_static=True)
TRANSITION = PhaseSettings("transition", gravity=True, contact=ContactSettings(), tolerance=None, max_stretch_change=0.3,
                           wind=True, max_stretch=None, moving=True)
MOTION = PhaseSettings("motion", gravity=True, contact=ContactSettings(), tolerance=None, max_stretch_change=0.3,
                       wind=True, max_stretch=None, moving=True)


@dataclass(frozen=True)
class DrapeOptions:
    """The keyword arguments of :func:`~tailor.dress.drape`, validated once (one-line errors).

    See :func:`~tailor.dress.drape` for their meaning.
    """

    frames: int = 25
    fps: float = 25.0
    resolution: float = DRAPE_RESOLUTION
    integrator: str = "implicit"
    sew_timeout: float = 4.0
    settle: float = 1.0
    record_sewing: bool = False
    self_collision: str = "auto"
    quality: str = DEFAULT_QUALITY
    wind: object = None
    cuts: tuple = field(default=())
    tear: bool = False
    fabric: Fabric | None = None
    limb_walls: bool = True
    """Keep each leg's panels on their side of the plane between the legs (off: to see what that prevents)."""
    keep_frames: bool = True
    """Keep every frame in the result; off, frames only go to the caller (``on_frame``, ``sink``: a writer
    streaming them to disk), so a long animation takes no more memory than a short one."""

    def __post_init__(self):
        if isinstance(self.fabric, str):
            object.__setattr__(self, "fabric", preset(self.fabric))
        object.__setattr__(self, "cuts", tuple(sorted(self.cuts, key=lambda c: c.time))
                           if all(isinstance(c, Cut) for c in self.cuts) else self._fail("cuts", self.cuts,
                                                                                            "tailor.tearing.Cut objects"))
        self._check_numbers()
        for name, value, choices in (("self_collision", self.self_collision, SELF_COLLISION_MODES),
                                     ("quality", self.quality, tuple(QUALITY)), ("integrator", self.integrator, tuple(INTEGRATORS))):
            if value not in choices:
                self._fail(name, value, "one of " + ", ".join(choices))

    def _check_numbers(self) -> None:
        if not (isinstance(self.frames, (int, np.integer)) and self.frames >= 1):
            self._fail("frames", self.frames, "a whole number of at least 1")
        for name in ("fps", "resolution", "sew_timeout"):
            value = getattr(self, name)
            if not (isinstance(value, (int, float, np.number)) and math.isfinite(value) and value > 0):
                self._fail(name, value, "a positive number")
        if not (math.isfinite(self.settle) and self.settle >= 0):
            self._fail("settle", self.settle, "a number of seconds, 0 or more")

    @staticmethod
    def _fail(name, value, expected):
        raise SimulationError(f"drape option {name} must be {expected}, got {value!r}")
