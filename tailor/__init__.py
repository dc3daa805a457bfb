"""tailor: sewing patterns in, simulated garments out.

The public surface is exactly ``__all__``; everything else is an implementation detail.
"""

from .errors import (
    BodyError,
    FabricError,
    MeshingError,
    PatternError,
    SeamError,
    SimulationError,
    SimulationUnstable,
    TailorError,
)
from .fabric import PRESETS, Fabric, preset
from .io import pattern_from_dict, read_pattern
from .mesh import GarmentMesh, discretise
from .pattern import Pattern, validate_pattern

__version__ = "0.1.0"

__all__ = [
    "TailorError",
    "PatternError",
    "SeamError",
    "FabricError",
    "MeshingError",
    "BodyError",
    "SimulationError",
    "SimulationUnstable",
    "Fabric",
    "PRESETS",
    "preset",
    "Pattern",
    "validate_pattern",
    "read_pattern",
    "pattern_from_dict",
    "GarmentMesh",
    "discretise",
]
