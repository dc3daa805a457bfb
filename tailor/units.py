"""Unit constants. SI inside tailor; files speak cm, g/m², % and degrees.

Conversion happens once, at the boundary (``tailor.io``), with these constants.
"""

import math

__all__ = ["CM", "MM", "DEG", "G_PER_M2", "PERCENT", "GRAVITY"]

CM = 1.0e-2
"""One centimetre in metres."""
MM = 1.0e-3
"""One millimetre in metres."""
DEG = math.pi / 180.0
"""One degree in radians."""
G_PER_M2 = 1.0e-3
"""One gram per square metre in kg/m²."""
PERCENT = 1.0e-2
"""One percent as a fraction."""
GRAVITY = 9.80665
"""Standard gravity [m/s²]; the world's gravity vector is (0, 0, -GRAVITY) (Z up)."""
