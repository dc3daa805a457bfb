"""The one exception family of tailor.

Every error a user can cause (a bad file, a bad number, an unstable run) is a
:class:`TailorError`; the command line turns it into one line and exit status 2.
"""

__all__ = [
    "TailorError",
    "PatternError",
    "SeamError",
    "FitError",
    "FabricError",
    "MeshingError",
    "BodyError",
    "SimulationError",
    "SimulationUnstable",
]


class TailorError(Exception):
    """Root of every error tailor raises on purpose."""


class PatternError(TailorError, ValueError):
    """A pattern file or document is malformed or inconsistent; the message names file and field."""


class SeamError(PatternError):
    """A seam references missing edges, sews an edge twice, or joins edges of incompatible length."""


class FitError(PatternError):
    """A pattern that cannot close round the body it is to dress (a loop shorter than the girth it goes round)."""


class FabricError(TailorError, ValueError):
    """Fabric numbers are missing, out of range, or name an unknown preset."""


class MeshingError(TailorError):
    """A panel could not be triangulated."""


class BodyError(TailorError, ValueError):
    """A body mesh or motion cannot be used (no faces, NaN, differing topology, ...)."""


class SimulationError(TailorError):
    """A simulation could not continue."""


class SimulationUnstable(SimulationError):
    """The integration diverged (NaN, inf, or unphysical strain/velocity); names time, step and a remedy."""
