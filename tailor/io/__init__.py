"""File formats: the only place where files are read or written and units converted."""

from .atomic import atomic_write, write_text_atomic
from .pattern_json import pattern_from_dict, read_pattern

__all__ = ["atomic_write", "write_text_atomic", "pattern_from_dict", "read_pattern"]
