"""tailor: sewing patterns in, simulated garments out.

The public surface is exactly ``__all__``; everything else is an implementation detail.
"""

from .errors import (
    BodyError,
    FabricError,
    FitError,
    MeshingError,
    PatternError,
    SeamError,
    SimulationError,
    SimulationUnstable,
    TailorError,
)
from .fabric import PRESETS, Fabric, preset
from .io import pattern_from_dict, read_pattern
from .batch import Job, drape_many
from .body import Body
from .dress import DrapeOptions, DrapeReport, DrapeResult, drape
from .io.body_files import read_body
from .io.animation import Animation, read_run
from .io.draw import draw_pattern
from .io.export import FORMATS, export
from .io.garment import write_drape
from .io.preview import PreviewSettings, preview
from .measure import Landmark, find_landmarks, measure_body
from .mesh import GarmentMesh, discretise
from .model import Model, State, build_model
from .outfit import outfit
from .pattern import Pattern, validate_pattern
from .sim import simulate
from .sizing import check_loops, grade

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
    "Model",
    "State",
    "build_model",
    "simulate",
    "Body",
    "read_body",
    "Landmark",
    "find_landmarks",
    "measure_body",
    "check_loops",
    "grade",
    "FitError",
    "drape",
    "outfit",
    "DrapeResult",
    "DrapeOptions",
    "DrapeReport",
    "write_drape",
    "Animation",
    "read_run",
    "export",
    "FORMATS",
    "preview",
    "PreviewSettings",
    "draw_pattern",
    "Job",
    "drape_many",
]
