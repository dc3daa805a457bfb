"""Wind: a smooth, time-varying Perlin-noise velocity field (Walker §3.8, made spatial).

Walker blows his flag with a Perlin-noise force applied evenly to every particle. Here the
noise is a *velocity field* of the air, varying smoothly in space and time, and the force comes
from :func:`tailor.forces.external.air_forces`, per triangle along its normal — so a flag
flaps, a sail fills, and cloth edge-on to the wind feels almost nothing.

    wind(p, t) = U·d̂ + U·τ·(n₁, n₂, n₃)(p/L + c·t·d̂/L, t/T)

with U the mean speed [m/s], d̂ the direction, τ the turbulence intensity, L the gust size [m],
and nᵢ three independent Perlin noises in [−1, 1] advected with the mean flow.

Examples
--------
>>> import numpy as np
>>> w = Wind(speed=5.0, direction=(1, 0, 0), turbulence=0.0)
>>> w(np.zeros((2, 3)), 0.0).tolist()
[[5.0, 0.0, 0.0], [5.0, 0.0, 0.0]]
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

__all__ = ["Wind", "perlin"]


def _fade(t):
    return t * t * t * (t * (t * 6.0 - 15.0) + 10.0)


def perlin(points, permutation) -> np.ndarray:
    """Classic 4D Perlin gradient noise at ``points`` (n, 4), roughly in [−1, 1], shape (n,).

    ``permutation`` is a shuffled ``arange(256)``; lattice gradients are the 32 vectors of
    4D gradient noise (two zero components, two ±1).
    """
    p = np.asarray(points, dtype=float)
    cell = np.floor(p).astype(np.int64)
    frac = p - cell
    perm = np.concatenate([permutation, permutation])
    fade = _fade(frac)
    total = np.zeros(len(p))
    for corner in range(16):
        offset = np.array([(corner >> k) & 1 for k in range(4)])
        c = (cell + offset) & 255
        h = perm[perm[perm[perm[c[:, 0]] + c[:, 1]] + c[:, 2]] + c[:, 3]] & 31
        d = frac - offset
        # gradient: choose two axes (6 pairs) and signs from the hash
        pair = h % 6
        a_axis = np.array([0, 0, 0, 1, 1, 2])[pair]
        b_axis = np.array([1, 2, 3, 2, 3, 3])[pair]
        sa = np.where(h & 8, -1.0, 1.0)
        sb = np.where(h & 16, -1.0, 1.0)
        rows = np.arange(len(p))
        dot = sa * d[rows, a_axis] + sb * d[rows, b_axis]
        weight = np.prod(np.where(offset == 1, fade, 1.0 - fade), axis=1)
        total += weight * dot
    return total


@dataclass(frozen=True)
class Wind:
    """A turbulent wind field; call it as ``wind(points (n, 3), t) -> (n, 3)`` [m/s].

    Attributes
    ----------
    speed : float
        Mean wind speed U [m/s] (a breeze 3, a strong wind 12, a gale 20).
    direction : tuple of 3 floats
        Direction of the mean flow (normalised).
    turbulence : float
        Gust intensity τ: fluctuations of ±τ·U.
    gust_size : float
        Spatial scale L of the gusts [m].
    gust_time : float
        Time scale T over which the pattern changes [s].
    seed : int
        Seed of the noise permutation (same seed, same wind).
    ramp : float
        Seconds over which the wind rises linearly from calm to full strength (0: full from the start).
    """

    speed: float = 5.0
    direction: tuple = (1.0, 0.0, 0.0)
    turbulence: float = 0.3
    gust_size: float = 0.5
    gust_time: float = 0.7
    seed: int = 0
    ramp: float = 0.0
    _perms: tuple = field(default=(), init=False, repr=False, compare=False)

    def __post_init__(self):
        rng = np.random.default_rng(self.seed)
        object.__setattr__(self, "_perms", tuple(rng.permutation(256) for _ in range(3)))

    def strength(self, t: float) -> float:
        """Fraction of full strength at time ``t`` (the ramp)."""
        return 1.0 if self.ramp <= 0.0 else min(1.0, max(0.0, t / self.ramp))

    def __call__(self, points, t: float) -> np.ndarray:
        d = np.asarray(self.direction, float)
        d = d / np.linalg.norm(d)
        mean = self.speed * d
        pts = np.asarray(points, float)
        a = self.strength(t)
        if self.turbulence == 0.0 or self.speed == 0.0:
            return np.tile(a * mean, (len(pts), 1))
        advected = (pts - mean * t) / self.gust_size
        q = np.column_stack([advected, np.full(len(pts), t / self.gust_time)])
        noise = np.column_stack([perlin(q + 17.0 * k, perm) for k, perm in enumerate(self._perms)])
        return a * (mean + self.speed * self.turbulence * noise)
