"""Model (fixed) and State (moving): the simulator's data, as struct-of-arrays numpy.

:func:`build_model` turns a discretised pattern and its fabric(s) into a :class:`Model` once
(:mod:`.build`); a :class:`State` holds positions, velocities and time (:mod:`.data`).
"""

from .build import build_model
from .data import AIR_DENSITY, ELASTIC_MODELS, Model, State

__all__ = ["Model", "State", "build_model", "ELASTIC_MODELS", "AIR_DENSITY"]
