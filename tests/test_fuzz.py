"""Property-based: random and mutated documents make the loader raise PatternError, never anything else."""

import copy
import json

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from conftest import PANELS
from tailor.errors import PatternError
from tailor.io import pattern_from_dict

SEEDS = [json.loads(p.read_text()) for p in sorted(PANELS.glob("*.json"))]

json_leaf = st.one_of(
    st.none(),
    st.booleans(),
    st.integers(-10, 200),
    st.floats(allow_nan=True, allow_infinity=True),
    st.floats(-1e3, 1e3),
    st.text(max_size=8),
)
json_value = st.recursive(
    json_leaf,
    lambda inner: st.one_of(st.lists(inner, max_size=4), st.dictionaries(st.text(max_size=8), inner, max_size=4)),
    max_leaves=12,
)


def loads_or_pattern_error(doc):
    try:
        pattern_from_dict(doc, source="fuzz.json")
    except PatternError as exc:
        assert str(exc).startswith("fuzz.json: ") and "\n" not in str(exc)


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(json_value)
def test_random_documents(doc):
    loads_or_pattern_error(doc)


def _paths(node, prefix=()):
    yield prefix
    if isinstance(node, dict):
        for k, v in node.items():
            yield from _paths(v, prefix + (k,))
    elif isinstance(node, list):
        for i, v in enumerate(node):
            yield from _paths(v, prefix + (i,))


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.sampled_from(range(len(SEEDS))), st.data())
def test_mutated_shipped_patterns(seed, data):
    doc = copy.deepcopy(SEEDS[seed])
    for _ in range(data.draw(st.integers(1, 3))):
        paths = [p for p in _paths(doc) if p]
        path = data.draw(st.sampled_from(paths))
        parent = doc
        for k in path[:-1]:
            parent = parent[k]
        action = data.draw(st.sampled_from(["replace", "delete", "perturb"]))
        if action == "delete":
            del parent[path[-1]]
        elif action == "perturb" and isinstance(parent[path[-1]], (int, float)) and not isinstance(parent[path[-1]], bool):
            parent[path[-1]] = parent[path[-1]] * data.draw(st.sampled_from([-1, 0, 0.5, 2, 1e6, 1e-9]))
        else:
            parent[path[-1]] = data.draw(json_value)
    loads_or_pattern_error(doc)
