"""Shared fixtures: small pattern documents built in code, and the GarmentCode reference folder."""

from __future__ import annotations

import copy
import os
from pathlib import Path

import pytest

if "PYTEST_XDIST_WORKER_COUNT" in os.environ:
    # one numba thread per test worker when the workers fill the cores (as `tailor batch` does); set
    # before anything imports numba. Passive waiting: GNU OpenMP's spinning threads would steal the
    # other worker's core.
    _threads = max(1, (os.cpu_count() or 1) // int(os.environ["PYTEST_XDIST_WORKER_COUNT"]))
    os.environ.setdefault("NUMBA_NUM_THREADS", str(_threads))
    os.environ.setdefault("OMP_WAIT_POLICY", "PASSIVE")

ROOT = Path(__file__).resolve().parents[1]
PANELS = ROOT / "panels"
GARMENTCODE = ROOT.parent / "shared" / "garmentcode"


def rect_panel(w: float, h: float, **extra) -> dict:
    """A w × h cm rectangle panel, counter-clockwise from the origin."""
    panel = {
        "vertices": [[0, 0], [w, 0], [w, h], [0, h]],
        "edges": [{"endpoints": [i, (i + 1) % 4]} for i in range(4)],
    }
    panel.update(extra)
    return panel


def doc_with(panels: dict, stitches=None, **top) -> dict:
    """A pattern document around ``panels``."""
    doc = {"pattern": {"panels": copy.deepcopy(panels), "stitches": stitches or []}, "properties": {"units_in_meter": 100}}
    doc.update(top)
    return doc


def gc_skirt_doc(waist_cm: float = 110.0) -> dict:
    """A straight skirt on a waistband written as GarmentCode writes patterns: flat panels placed by
    translations (Y up, facing +Z, cm; the back panels wound the other way), the band's free top edge
    labelled ``lower_interface``, no attachments; the band at the waist, the skirt 5 cm below it."""
    def rect(w, h, at, back=False, top_label=None):
        v = [[0, 0], [0, h], [w, h], [w, 0]] if back else [[0, 0], [w, 0], [w, h], [0, h]]
        edges = [{"endpoints": [i, (i + 1) % 4]} for i in range(4)]
        if top_label:
            edges[1 if back else 2]["label"] = top_label
        return {"vertices": v, "edges": edges, "translation": at, "rotation": [0, 0, 0]}

    band_y, skirt_y = waist_cm - 5.5, waist_cm - 56.0
    panels = {"wb_front": rect(46, 5, [-23, band_y, 20], top_label="lower_interface"),
              "wb_back": rect(40, 5, [-20, band_y, -15], back=True, top_label="lower_interface"),
              "skirt_front": rect(58, 45, [-29, skirt_y, 25]),
              "skirt_back": rect(50, 45, [-25, skirt_y, -20], back=True)}
    stitches = [[{"panel": "wb_front", "edge": 3}, {"panel": "wb_back", "edge": 0}],
                [{"panel": "wb_front", "edge": 1}, {"panel": "wb_back", "edge": 2}],
                [{"panel": "skirt_front", "edge": 3}, {"panel": "skirt_back", "edge": 0}],
                [{"panel": "skirt_front", "edge": 1}, {"panel": "skirt_back", "edge": 2}],
                [{"panel": "wb_front", "edge": 0}, {"panel": "skirt_front", "edge": 2}],
                [{"panel": "wb_back", "edge": 3}, {"panel": "skirt_back", "edge": 1}]]
    return doc_with(panels, stitches)


@pytest.fixture
def square_doc():
    """One 20 × 20 cm panel."""
    return doc_with({"sq": rect_panel(20, 20)})


@pytest.fixture
def tube_doc():
    """One 30 × 20 cm panel whose left and right edges are sewn into a tube."""
    return doc_with({"tube": rect_panel(30, 20)}, [[{"panel": "tube", "edge": 1}, {"panel": "tube", "edge": 3}]])


@pytest.fixture
def two_panel_doc():
    """Front and back 30 × 40 cm panels sewn at both sides."""
    return doc_with(
        {"front": rect_panel(30, 40), "back": rect_panel(30, 40)},
        [
            [{"panel": "front", "edge": 1}, {"panel": "back", "edge": 3}],
            [{"panel": "front", "edge": 3}, {"panel": "back", "edge": 1}],
        ],
    )


@pytest.fixture(scope="session")
def mannequin():
    """tailor's own default body, as shipped in bodies/."""
    from tailor.io.body_files import read_body

    return read_body("mannequin")


@pytest.fixture
def garmentcode_dir():
    """``../shared/garmentcode`` (reference patterns, not in the repository); skip when absent."""
    if not GARMENTCODE.is_dir():
        pytest.skip("GarmentCode reference patterns not available")
    return GARMENTCODE


def sheet(width_cm: float, height_cm: float, resolution_m: float, fabric="cotton", *, vertical=True, grain=90, **model_kwargs):
    """A rectangular cloth: (model, rest positions). Vertical sheets span x (width) and z (height)."""
    import numpy as np

    from tailor.fabric import Fabric, preset
    from tailor.io import pattern_from_dict
    from tailor.mesh import discretise
    from tailor.model import build_model

    doc = doc_with({"sheet": rect_panel(width_cm, height_cm, grain=grain)})
    mesh = discretise(pattern_from_dict(doc), resolution_m)
    fab = fabric if isinstance(fabric, Fabric) else preset(fabric)
    model = build_model(mesh, fab, **model_kwargs)
    uv = model.rest_uv
    if vertical:
        x0 = np.column_stack([uv[:, 0], np.zeros(len(uv)), uv[:, 1]])
    else:
        x0 = np.column_stack([uv, np.zeros(len(uv))])
    return model, x0


def assert_minus_gradient(potential, forces, model, state, *, wrt="x", eps=1e-7, samples=6, seed=0):
    """Check ``forces(model, state) == −∂potential/∂(state.<wrt>)`` by central differences."""
    import numpy as np
    import pytest

    rng = np.random.default_rng(seed)
    f = forces(model, state)
    for i in rng.choice(model.vertex_count, samples, replace=False):
        for k in range(3):
            up, dn = state.copy(), state.copy()
            getattr(up, wrt)[i, k] += eps
            getattr(dn, wrt)[i, k] -= eps
            numeric = -(potential(model, up) - potential(model, dn)) / (2 * eps)
            assert f[i, k] == pytest.approx(numeric, rel=1e-5, abs=1e-8 * np.abs(f).max())


@pytest.fixture(scope="session")
def walk_run(tmp_path_factory):
    """A small skirt drape on the walking mannequin, written with its body: (DrapeResult, run folder)."""
    from tailor.dress import drape
    from tailor.io import read_pattern
    from tailor.io.body_files import read_body
    from tailor.io.garment import write_drape

    result = drape(read_pattern(PANELS / "skirt.json"), read_body("mannequin-walk"), frames=3, resolution=0.06,
                   quality="draft")
    return result, write_drape(result, tmp_path_factory.mktemp("runs") / "skirt", with_body=True)
