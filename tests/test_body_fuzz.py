"""Broken, strange and wrong body files: ``tailor body info`` answers in one line with exit 2 (or reads
them), never with a traceback. 40 seeded files in CI, all 200 with ``-m slow``."""

import numpy as np
import pytest

from tailor.cli import main
from tailor.corpus import mannequin_variants
from tailor.io.obj import write_obj

KINDS = ("truncated", "nan", "inf", "no-faces", "bad-index", "two-people", "cube", "plane", "sphere", "huge",
         "tiny", "garbage", "empty", "lying", "headless", "legless", "shuffled", "polygons", "garbage-ply",
         "garbage-stl")


@pytest.fixture(scope="module")
def small_body():
    body = mannequin_variants(["arms-20"], resolution=0.035, calibrate=1)[0]
    return body.vertices, body.faces


def _obj_text(v, f):
    rows = [f"v {a:.6g} {b:.6g} {c:.6g}" for a, b, c in v] + [f"f {a + 1} {b + 1} {c + 1}" for a, b, c in f]
    return "\n".join(rows) + "\n"


def _fuzzed(kind, rng, v, f, path):
    """Write one fuzzed body file of ``kind`` at ``path`` (suffix may change); returns the path."""
    import trimesh

    if kind == "truncated":
        text = _obj_text(v, f)
        path.write_text(text[: int(rng.integers(1, len(text)))])
    elif kind in ("nan", "inf"):
        w = v.copy()
        w[rng.choice(len(w), int(rng.integers(1, 5))), int(rng.integers(3))] = np.nan if kind == "nan" else np.inf
        path.write_text(_obj_text(w, f).replace("inf", "inf"))
    elif kind == "no-faces":
        path.write_text(_obj_text(v, f[:0]))
    elif kind == "bad-index":
        g = f.copy()
        g[rng.integers(len(g)), rng.integers(3)] = len(v) + int(rng.integers(1, 1000))
        path.write_text(_obj_text(v, g))
    elif kind == "two-people":
        shift = np.array([rng.uniform(0.8, 2.0), rng.uniform(-0.5, 0.5), 0.0])
        write_obj(path, np.vstack([v, v + shift]), np.vstack([f, f + len(v)]))
    elif kind in ("cube", "sphere", "plane"):
        size = 10.0 ** rng.uniform(-2, 3)
        mesh = {"cube": trimesh.creation.box([size] * 3), "sphere": trimesh.creation.icosphere(radius=size),
                "plane": trimesh.Trimesh([[0, 0, 0], [size, 0, 0], [size, size, 0], [0, size, 0]], [[0, 1, 2], [0, 2, 3]])}[kind]
        write_obj(path, mesh.vertices, mesh.faces)
    elif kind in ("huge", "tiny"):
        write_obj(path, v * (10.0 ** (rng.uniform(8, 30) if kind == "huge" else -rng.uniform(5, 12))), f)
    elif kind in ("garbage", "garbage-ply", "garbage-stl"):
        path = path.with_suffix({"garbage": ".obj", "garbage-ply": ".ply", "garbage-stl": ".stl"}[kind])
        head = {"garbage": b"", "garbage-ply": b"ply\nformat binary_little_endian 1.0\nelement vertex 5\n", "garbage-stl": b"solid x\n"}[kind]
        path.write_bytes(head + rng.bytes(int(rng.integers(0, 4000))))
    elif kind == "empty":
        path.write_text("")
    elif kind == "lying":
        write_obj(path, v[:, [2, 1, 0]] * [1.0, 1.0, 1.0], f)
    elif kind in ("headless", "legless"):
        z = v[f].mean(axis=1)[:, 2]
        cut = rng.uniform(0.7, 0.95) if kind == "headless" else rng.uniform(0.2, 0.5)
        keep = z < cut * v[:, 2].max() if kind == "headless" else z > cut * v[:, 2].max()
        write_obj(path, v, f[keep])
    elif kind == "shuffled":
        write_obj(path, v, rng.integers(0, len(v), f.shape))
    elif kind == "polygons":
        quads = np.column_stack([f, f[:, :1]])
        path.write_text("\n".join([f"v {a} {b} {c}" for a, b, c in v] + [f"f {a + 1} {b + 1} {c + 1} {d + 1} {a + 1}" for a, b, c, d in quads]))
    return path


CASES = [(KINDS[i % len(KINDS)], i) for i in range(200)]


def _check(tmp_path, capsys, small_body, kind, seed):
    rng = np.random.default_rng(seed)
    path = _fuzzed(kind, rng, *small_body, tmp_path / f"{kind}_{seed}.obj")
    capsys.readouterr()
    rc = main(["body", "info", str(path)])
    err = capsys.readouterr().err.strip()
    assert rc in (0, 2), (kind, seed, rc)
    if rc == 2:
        assert err.count("\n") == 0 and err.startswith("tailor: error:") and path.name in err, (kind, seed, err)
    return rc


@pytest.mark.parametrize("kind,seed", CASES[::5])
def test_fuzzed_body_files_give_one_line_errors(tmp_path, capsys, small_body, kind, seed):
    _check(tmp_path, capsys, small_body, kind, seed)


@pytest.mark.slow
@pytest.mark.parametrize("kind,seed", [c for i, c in enumerate(CASES) if i % 5])
def test_all_200_fuzzed_body_files_give_one_line_errors(tmp_path, capsys, small_body, kind, seed):
    _check(tmp_path, capsys, small_body, kind, seed)


@pytest.mark.parametrize("kind,seed", CASES[3::11])
def test_fuzzed_body_files_give_one_line_errors_to_drape(tmp_path, capsys, small_body, kind, seed):
    from conftest import PANELS

    path = _fuzzed(kind, np.random.default_rng(seed), *small_body, tmp_path / f"{kind}_{seed}.obj")
    capsys.readouterr()
    rc = main(["-q", "drape", str(PANELS / "skirt.json"), "--body", str(path), "--frames", "1", "--resolution", "12",
               "--quality", "draft", "--out", str(tmp_path / "run")])
    err = capsys.readouterr().err.strip()
    assert rc in (0, 2), (kind, seed, rc)
    if rc == 2:
        assert err.count("\n") == 0 and err.startswith("tailor: error:") and path.name in err, (kind, seed, err)
        assert not (tmp_path / "run").exists()  # nothing half-written
