"""Typed access to a parsed JSON document that knows where it is, for one-line errors.

``Node(doc, source="skirt.json").key("pattern").key("panels")`` walks the document; any
``as_*`` check that fails raises ``PatternError("skirt.json: pattern.panels: ...")``.
"""

from __future__ import annotations

import difflib
import json
import math
import re

from ..errors import PatternError

__all__ = ["Node"]

_PLAIN = re.compile(r"[A-Za-z0-9_\-]{1,64}")


def _kind(value) -> str:
    if value is None:
        return "null"
    if isinstance(value, bool):
        return "a boolean"
    if isinstance(value, (int, float)):
        return "a number"
    if isinstance(value, str):
        return "a string"
    if isinstance(value, list):
        return "a list"
    if isinstance(value, dict):
        return "an object"
    return type(value).__name__


class Node:
    """A value inside a document together with its path (``pattern.panels.front.edges[2]``)."""

    __slots__ = ("value", "path", "source", "error")

    def __init__(self, value, path: str = "", source: str = "<pattern>", error=PatternError):
        self.value = value
        self.path = path
        self.source = source
        self.error = error

    # -- navigation -----------------------------------------------------------------------
    def fail(self, message: str):
        """Raise the one-line error for this field."""
        where = f"{self.path}: " if self.path else ""
        raise self.error(f"{self.source}: {where}{message}")

    def _child(self, value, suffix: str, *, index: bool = False) -> "Node":
        if not index and not _PLAIN.fullmatch(suffix):
            suffix, index = f"[{json.dumps(suffix)}]", True  # odd keys are quoted, never raw
        if index:
            path = f"{self.path}{suffix}"
        else:
            path = f"{self.path}.{suffix}" if self.path else suffix
        return Node(value, path, self.source, self.error)

    def has(self, key: str) -> bool:
        """Whether this object has ``key``."""
        return isinstance(self.value, dict) and key in self.value

    def key(self, key: str, default=..., *, required: bool = True) -> "Node | None":
        """The child ``key``; missing → error, or ``Node(default)`` when a default is given."""
        obj = self.as_object()
        if key in obj:
            return self._child(obj[key], key)
        if default is not ...:
            return self._child(default, key)
        if not required:
            return None
        self.fail(f"missing field {key!r}")

    def items(self) -> list["Node"]:
        """Children of a list."""
        return [self._child(v, f"[{i}]", index=True) for i, v in enumerate(self.as_list())]

    def entries(self) -> list[tuple[str, "Node"]]:
        """(key, child) pairs of an object."""
        return [(k, self._child(v, str(k))) for k, v in self.as_object().items()]

    # -- checks ---------------------------------------------------------------------------
    def as_object(self, allowed=None) -> dict:
        """The value as a dict; with ``allowed``, unknown keys are an error with a did-you-mean."""
        if not isinstance(self.value, dict):
            self.fail(f"expected an object, got {_kind(self.value)}")
        if allowed is not None:
            for k in self.value:
                if k not in allowed:
                    close = difflib.get_close_matches(str(k), sorted(allowed), n=1)
                    hint = f" (did you mean {close[0]!r}?)" if close else ""
                    self._child(None, str(k)).fail(
                        f"unknown field {str(k)!r}{hint}; allowed: {', '.join(sorted(allowed))}"
                    )
        return self.value

    def as_list(self, length: int | None = None, min_length: int | None = None) -> list:
        """The value as a list of a given or minimum length."""
        if not isinstance(self.value, list):
            self.fail(f"expected a list, got {_kind(self.value)}")
        n = len(self.value)
        if length is not None and n != length:
            self.fail(f"expected {length} items, got {n}")
        if min_length is not None and n < min_length:
            self.fail(f"expected at least {min_length} items, got {n}")
        return self.value

    def as_number(self, *, minimum=None, positive: bool = False, maximum=None) -> float:
        """The value as a finite float within bounds."""
        v = self.value
        if isinstance(v, bool) or not isinstance(v, (int, float)):
            self.fail(f"expected a number, got {_kind(v)}")
        v = float(v)
        if not math.isfinite(v):
            self.fail(f"expected a finite number, got {v}")
        if positive and v <= 0:
            self.fail(f"must be positive, got {v:g}")
        if minimum is not None and v < minimum:
            self.fail(f"must be >= {minimum:g}, got {v:g}")
        if maximum is not None and v > maximum:
            self.fail(f"must be <= {maximum:g}, got {v:g}")
        return v

    def as_int(self, *, minimum: int | None = None, below: int | None = None, what: str = "index") -> int:
        """The value as an integer (``3.0`` accepted), ``minimum <= v < below``."""
        v = self.value
        if isinstance(v, bool) or not isinstance(v, (int, float)) or (isinstance(v, float) and not v.is_integer()):
            self.fail(f"expected an integer {what}, got {v!r}")
        v = int(v)
        if minimum is not None and v < minimum:
            self.fail(f"{what} {v} must be >= {minimum}")
        if below is not None and v >= below:
            self.fail(f"{what} {v} does not exist (there are {below})")
        return v

    def as_str(self, choices=None) -> str:
        """The value as a string, optionally one of ``choices`` (with a did-you-mean)."""
        if not isinstance(self.value, str):
            self.fail(f"expected a string, got {_kind(self.value)}")
        if choices is not None and self.value not in choices:
            close = difflib.get_close_matches(self.value, list(choices), n=1)
            hint = f" (did you mean {close[0]!r}?)" if close else ""
            self.fail(f"unknown value {self.value!r}{hint}; choose one of {', '.join(choices)}")
        return self.value

    def as_bool(self) -> bool:
        """The value as a boolean (0/1 accepted, as GarmentCode writes arc flags)."""
        v = self.value
        if isinstance(v, bool):
            return v
        if isinstance(v, (int, float)) and v in (0, 1):
            return bool(v)
        self.fail(f"expected true/false or 0/1, got {v!r}")

    def as_point(self, dim: int = 2) -> tuple[float, ...]:
        """The value as a list of ``dim`` finite numbers."""
        return tuple(n.as_number() for n in (self.as_list(length=dim) and self.items()))
