"""The import layers of DESIGN.md hold: physics never imports io or cli; each library has one owner."""

import ast
from pathlib import Path

import pytest

PKG = Path(__file__).resolve().parents[1] / "tailor"

# module → layer; a module may import tailor modules of the same or a lower layer only
LAYERS = {
    "errors": 0, "units": 0, "landmarks": 0,
    "geometry": 1, "curves": 1, "topology": 1, "hanging": 1, "sections": 1,
    "pattern": 2, "fabric": 2, "body": 2, "orient": 2,
    "mesh": 3, "placement": 3, "retarget": 3, "limbwalls": 3, "mannequin": 3, "measure": 3, "arms": 3,
    "params": 4, "model": 4, "sizing": 4,
    "forces": 5, "collide": 5, "seams": 5, "outfit": 5,
    "integrators": 6, "contact": 6, "constraints": 6,
    "sim": 7, "scenes": 7, "dress": 7, "tearing": 7,
    "io": 8, "fit": 8, "lab": 8, "cli": 9, "__main__": 9, "__init__": 9, "bench": 9, "batch": 9, "validate": 9, "corpus": 9,
}
OWNERS = {"triangle": {"mesh"}, "fcl": {"collide"}, "meshio": {"io"}, "skimage": {"mannequin"}, "matplotlib": {"io"},
          "pxr": {"io"}, "PIL": {"io"}, "ezdxf": {"io"}, "tqdm": {"cli"}, "yaml": {"io"},
          "distributed": {"batch"}, "dask": {"batch"}}


def _module_key(path: Path) -> str:
    rel = path.relative_to(PKG).with_suffix("")
    return rel.parts[0]


def _imports(path: Path):
    tree = ast.parse(path.read_text())
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom):
            if node.level:  # relative: resolve against the package
                base = path.relative_to(PKG).parent.parts[: max(len(path.relative_to(PKG).parent.parts) - node.level + 1, 0)]
                target = (*base, *(node.module.split(".") if node.module else []))
                yield "tailor", target[0] if target else "__init__"
            elif node.module:
                yield node.module.split(".")[0], None
        elif isinstance(node, ast.Import):
            for alias in node.names:
                yield alias.name.split(".")[0], None


SOURCES = sorted(PKG.rglob("*.py"))


@pytest.mark.parametrize("path", SOURCES, ids=lambda p: str(p.relative_to(PKG)))
def test_layering(path):
    me = _module_key(path)
    assert me in LAYERS, f"{me} has no layer in tests/test_layers.py"
    for top, target in _imports(path):
        if top == "tailor" and target is not None and target != me:
            assert LAYERS[target] <= LAYERS[me], f"{me} (layer {LAYERS[me]}) imports {target} (layer {LAYERS[target]})"
        if top in OWNERS:
            assert me in OWNERS[top], f"{me} imports {top}, owned by {OWNERS[top]}"


@pytest.mark.parametrize("path", [p for p in SOURCES if _module_key(p) not in ("cli", "__main__")],
                         ids=lambda p: str(p.relative_to(PKG)))
def test_the_library_logs_and_never_prints(path):
    calls = [node.lineno for node in ast.walk(ast.parse(path.read_text()))
             if isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.func.id == "print"]
    assert not calls, f"print() at line(s) {calls}: use logging (log = logging.getLogger(__name__))"


MAX_FUNCTION_LINES = 80
MAX_MODULE_LINES = 500


@pytest.mark.parametrize("path", SOURCES, ids=lambda p: str(p.relative_to(PKG)))
def test_modules_and_functions_stay_readable(path):
    text = path.read_text()
    assert text.count("\n") <= MAX_MODULE_LINES, f"{path.name}: over {MAX_MODULE_LINES} lines; split it"
    long = [(n.name, n.end_lineno - n.lineno + 1) for n in ast.walk(ast.parse(text))
            if isinstance(n, (ast.FunctionDef, ast.AsyncFunctionDef)) and n.end_lineno - n.lineno + 1 > MAX_FUNCTION_LINES]
    assert not long, f"functions over {MAX_FUNCTION_LINES} lines: {long}"


@pytest.mark.parametrize("path", SOURCES, ids=lambda p: str(p.relative_to(PKG)))
def test_integrators_are_configured_through_their_interface(path):
    """No ``hasattr``/``getattr``/``setattr`` on an integrator: every one implements
    :class:`tailor.integrators.Integrator` (configure, reset, step, counters)."""
    bad = []
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.func.id in ("hasattr", "getattr", "setattr"):
            first = node.args[0] if node.args else None
            if isinstance(first, ast.Name) and "integ" in first.id.lower():
                bad.append(node.lineno)
    assert not bad, f"hasattr/getattr/setattr on an integrator at line(s) {bad}"


def test_every_integrator_implements_the_protocol():
    from tailor.integrators import INTEGRATORS, Counters, SolverSettings, StepResult
    from tailor.forces import total_forces
    from tailor.scenes import cloth_model, rectangle

    _, model = cloth_model([rectangle(0.1, 0.1)], "cotton", 0.05)
    state = model.state(model.rest_uv[:, [0, 1, 1]] * [1, 1, 0])
    for name, cls in INTEGRATORS.items():
        integ = cls()
        assert integ.name == name and isinstance(integ.counters, Counters)
        integ.configure(SolverSettings(tolerance=1e-6))
        integ.reset()
        result = integ.step(model, state, 1e-4, total_forces, contacts=None, predict=None)
        assert isinstance(result, StepResult) and result.state.t == pytest.approx(1e-4)
        assert integ.settings.tolerance == 1e-6 and integ.counters.steps == 1
