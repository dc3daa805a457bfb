"""Reading a cuts file: the scripted brush of ``tailor drape --cuts`` (units as in pattern files).

.. code-block:: json

    {"cuts": [
        {"time": 0.4, "points": [[0, -15, 75]], "radius": 5},
        {"time": 0.8, "points": [[10, -20, 45], [10, -20, 75]], "radius": 6, "separate": true}
    ]}

``time`` [s] counts from frame 0 (the dressed garment); ``points`` are in the body's frame in cm
(Z up, the body facing −Y), one point for a round hole or a polyline for a slit; ``radius`` [cm]
is the brush's; ``separate`` cuts the cloth apart along the polyline without removing any.
"""

from __future__ import annotations

import json
from pathlib import Path

from ..errors import PatternError
from ..tearing import Cut
from ._fields import Node

__all__ = ["read_cuts"]


def read_cuts(path) -> list[Cut]:
    """The cuts of a cuts file, in SI units; a bad file raises a one-line :class:`PatternError`."""
    path = Path(path)
    try:
        doc = json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise PatternError(f"{path}: no such cuts file") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise PatternError(f"{path}: cannot read: {exc}") from None
    except json.JSONDecodeError as exc:
        raise PatternError(f"{path.name}: line {exc.lineno} column {exc.colno}: malformed JSON: {exc.msg}") from None
    root = Node(doc, "", path.name)
    root.as_object({"cuts"})
    cuts = []
    for node in root.key("cuts").items():
        node.as_object({"time", "points", "radius", "separate"})
        time = node.key("time").as_number(minimum=0.0)
        points = node.key("points")
        points.as_list(min_length=1)
        pts = [tuple(0.01 * c for c in p.as_point(3)) for p in points.items()]
        radius = 0.01 * node.key("radius").as_number(positive=True)
        separate = node.key("separate", False).as_bool()
        if separate and len(pts) < 2:
            points.fail("a separating cut needs a polyline of at least two points")
        cuts.append(Cut(time, pts, radius, separate=separate))
    return cuts
