"""The body over time during a drape: its pose, velocity and collider frame at any instant, and the
step its motion allows.

A moving body with a neutral pose (:attr:`~tailor.body.Body.rest`, as the shipped walk has) is
dressed in that pose and then moves into its first frame at :data:`~.options.TRANSITION_SPEED`
(along key poses :data:`~.options.TRANSITION_KEYS_PER_S` a second), so panels are never placed round a
leg in mid-stride. Each step while the body moves carries no body point that can reach the cloth
within the frame further relative to the cloth nearest it than the body collider's sure radius (where
every body triangle near a vertex is its candidate: half the contact margin by default; the feet do not
shorten a T-shirt's steps, nor the legs those of trousers swinging with them).
"""

from __future__ import annotations

import math

import numpy as np
from scipy.spatial import cKDTree

from ..collide.bounds import axis_bounds
from .options import SETTLE_RAMP, TRANSITION_KEYS_PER_S, transition_seconds

__all__ = ["Timeline", "NearBodySpeed"]


class NearBodySpeed:
    """The largest speed [m/s] of the body vertices that can reach the cloth within a span, relative
    to the cloth nearest them.

    Per body vertex, its velocity over each interval of the motion (looping, as :meth:`Body.at`) and,
    with a rest ``pose``, its speed over the transition. A body vertex can touch the cloth within
    ``duration`` only if it is nearer than the contact margin plus how far both can travel meanwhile
    (the cloth at up to twice its fastest vertex's speed plus 1 m/s) plus the longest body edge (a
    triangle reaches that far from its corners); the others do not limit the step. While the body
    moves, what limits a step is how fast each such body vertex moves relative to the cloth vertex
    nearest it, at any interval of the span: trousers' legs swing with the legs, and only a hem the
    knee kicks, or cloth left behind, meets the body at its own speed.
    """

    def __init__(self, body, pose, margin: float, transition_s: float = 1.0):
        # transition_s [s]: how long the body takes from ``pose`` into its first frame (unused without a pose)
        f = np.asarray(body.frames, dtype=np.float64)
        self.frames = f
        self.speeds = np.linalg.norm(np.roll(f, -1, axis=0) - f, axis=2) * body.fps if len(f) > 1 else None
        self.ease = None if pose is None else np.linalg.norm(f[0] - pose, axis=1) / transition_s
        faces = np.asarray(body.faces)
        self.edge = float(np.linalg.norm(f[0][faces] - f[0][np.roll(faces, 1, axis=1)], axis=2).max())
        self.fps, self.margin = body.fps, margin

    def __call__(self, x, v, body_x, duration: float, span) -> float:
        """``span`` is (start, end) in the motion's time [s], or None during the transition."""
        intervals = None
        if span is None:
            speed = self.ease
        elif self.speeds is None:
            return 0.0
        else:
            k0 = int(math.floor(span[0] * self.fps + 1e-9))
            k1 = max(k0 + 1, int(math.ceil(span[1] * self.fps - 1e-9)))
            intervals = np.arange(k0, k1) % len(self.speeds)
            speed = self.speeds[intervals].max(axis=0)
        if speed is None or not len(x):
            return 0.0
        cloth = float(np.sqrt((v * v).sum(axis=1).max())) if len(v) else 0.0
        reach = self.margin + (float(speed.max()) + 2.0 * cloth + 1.0) * duration + self.edge
        # only the body vertices within the cloth's box grown by the reach can be within reach of it
        lo, hi = axis_bounds(x)
        box = np.flatnonzero(((body_x >= lo - reach) & (body_x <= hi + reach)).all(axis=1))
        d, nearest = cKDTree(x).query(body_x[box], distance_upper_bound=reach)
        hit = np.isfinite(d)
        near, nearest = box[hit], nearest[hit]
        if not len(near):
            return 0.0
        if intervals is None:
            return float(speed[near].max())
        return max(float(np.linalg.norm(self._velocity(k, near) - v[nearest], axis=1).max()) for k in intervals)

    def _velocity(self, k: int, ids) -> np.ndarray:
        """(len(ids), 3) velocity [m/s] of body vertices ``ids`` over the motion's interval ``k`` (the
        last one loops to frame 0)."""
        f = self.frames
        return (f[(k + 1) % len(f), ids] - f[k, ids]) * self.fps


class Timeline:
    """Where the body is at any time of a drape, and the largest step its motion allows.

    Parameters
    ----------
    body : Body
    still_step : float or None
        The implicit step [s] while the body is still (None: explicit integrators keep Eq. 24's).
    settle_step : float or None
        The implicit step [s] of a quasi-static phase (settling: only its end state matters) once
        its first :data:`~.options.SETTLE_RAMP` s are over; default ``still_step``.
    ramp_step : float or None
        The step [s] of those first seconds; default ``still_step``.
    """

    def __init__(self, body, still_step: float | None, *, settle_step: float | None = None,
                 ramp_step: float | None = None):
        self.body = body
        self.moving = body.frame_count > 1
        has_rest = self.moving and body.rest is not None
        self.pose = body.rest if has_rest else body.frames[0]
        # seconds from the rest pose into the motion's first frame (0: no transition)
        self.transition_s = transition_seconds(float(np.linalg.norm(body.frames[0] - self.pose, axis=1).max())) if has_rest else 0.0
        self.keys = max(1, int(round(TRANSITION_KEYS_PER_S * self.transition_s))) if has_rest else 0
        self.settle_start = None  # [s] of the drape's clock, set when gravity comes on
        self.transition_start = None  # [s] of the drape's clock, set when the body starts to move
        self.motion_start = None
        self.still_step = still_step
        self.settle_step = still_step if settle_step is None else settle_step
        self.ramp_step = still_step if ramp_step is None else ramp_step
        self.steps_used: list = []
        self._near = None
        self.margin = 0.0
        self.travel = 0.0  # [m] how far a step may carry a body point relative to the cloth (follow_collider)
        self.max_speed = self._max_speed()

    @property
    def collider_frames(self) -> np.ndarray:
        """The body frames the collider needs: the dressing pose, the transition's key poses, the motion."""
        if not self.keys:
            return self.body.frames
        steps = np.arange(1, self.keys + 1)[:, None, None] / self.keys
        pose = self.pose
        return np.concatenate([pose[None], pose + steps * (self.body.frames[0] - pose), self.body.frames])

    def start_settling(self, t: float) -> None:
        """Settling (gravity on) starts at ``t`` [s]: :meth:`settling_step` ramps from there."""
        self.settle_start = t

    def settling_step(self, t: float) -> float | None:
        """The quasi-static step [s] at time ``t`` of settling: ``ramp_step`` for its first
        :data:`~.options.SETTLE_RAMP` s, ``settle_step`` after."""
        if self.settle_start is None or t - self.settle_start < SETTLE_RAMP - 1e-9:
            return self.ramp_step
        return self.settle_step

    def start_transition(self, t: float) -> None:
        """The body starts to move (into its motion's first frame, if it has a rest pose) at ``t`` [s]."""
        self.transition_start = t

    def start_motion(self, t: float) -> None:
        """Frame 0 of the motion is at ``t`` [s]."""
        self.motion_start = t

    def follow_collider(self, margin: float, travel: float) -> None:
        """The body collider's ``margin`` [m] and how far [m] a step may carry the body through the
        cloth (its :attr:`~tailor.collide.body.BodyCollider.sure` radius): the step rule of a moving
        body uses them."""
        self.margin, self.travel = margin, travel
        if self.moving:
            self._near = NearBodySpeed(self.body, self.pose if self.keys else None, margin, self.transition_s)

    def at(self, t: float):
        """Body positions, velocities and collider frame at time ``t`` of the drape."""
        ease, start, body = self.transition_start, self.motion_start, self.body
        if ease is None or (start is None and not self.keys):
            return self.pose, np.zeros_like(self.pose), 0
        if start is None:  # transition: rest pose → first frame at constant speed
            a = min(max((t - ease) / self.transition_s, 0.0), 1.0)
            return (self.pose + a * (body.frames[0] - self.pose), (body.frames[0] - self.pose) / self.transition_s,
                    1 + min(self.keys - 1, int(a * self.keys)))
        if not self.moving:
            return self.pose, np.zeros_like(self.pose), 0
        tb = max(0.0, t - start)
        bx, bv = body.at(tb)
        return bx, bv, (1 + self.keys if self.keys else 0) + int(round(tb * body.fps)) % body.frame_count

    def _max_speed(self) -> float:
        """The body's fastest vertex speed [m/s] over the motion and the transition (0: still)."""
        if not self.moving:
            return 0.0
        speed = float(np.abs(np.diff(self.body.frames, axis=0)).max() * self.body.fps)
        if self.keys:
            speed = max(speed, float(np.abs(self.body.frames[0] - self.pose).max()) / self.transition_s)
        return speed

    @property
    def motion_step(self) -> float | None:
        """The step no body point anywhere can travel more than :attr:`travel` in (None: explicit)."""
        if self.still_step is None or self.max_speed <= 0:
            return self.still_step
        return min(self.still_step, self.travel / self.max_speed)

    def moving_step(self, state, duration: float) -> float | None:
        """The step for the next ``duration`` s while the body moves: only body points near the cloth
        count (a swinging hand far from a T-shirt does not shorten its steps), by their speed relative
        to the cloth nearest them (:class:`NearBodySpeed`). The transition into the motion's first
        frame is, like settling, quasi-static (only its end, the dressed frame 0, is kept): its steps
        are the settling step's, shortened by the same near-body rule."""
        if self.still_step is None:
            return None
        if self._near is None or self.max_speed <= 0:
            return self.motion_step
        bx = self.at(state.t)[0]
        start = self.motion_start
        span = None if start is None else (state.t - start, state.t - start + duration)
        longest = self.still_step if span is not None else max(self.still_step, self.settle_step)
        fastest = self._near(state.x, state.v, bx, duration, span)
        dt = min(longest, self.travel / fastest) if fastest > 0 else longest
        if span is not None:  # the motion's steps, as the report gives them
            self.steps_used.append(dt)
        return dt
