"""Previews and pattern drawings: pictures that show what they claim (colours per panel, the
body in grey, the garment moving between frames), and bad options refused in one line."""

from __future__ import annotations

import numpy as np
import pytest
from PIL import Image

from tailor.cli import main
from tailor.errors import TailorError
from tailor.io import read_pattern
from tailor.io.animation import BODY_COLOUR, panel_colour, read_run
from tailor.io.draw import draw_pattern, panel_layout
from tailor.io.preview import PreviewSettings, camera, preview

from conftest import PANELS


def test_camera_front_looks_along_plus_y_and_side_along_minus_x():
    right, up, view = camera(0.0, 0.0)
    np.testing.assert_allclose([right, up, view], [[1, 0, 0], [0, 0, 1], [0, 1, 0]], atol=1e-12)
    right, up, view = camera(np.pi / 2, 0.0)  # at the body's left (+X), looking back at it
    np.testing.assert_allclose(view, [-1, 0, 0], atol=1e-12)
    np.testing.assert_allclose(np.cross(right, up), -view, atol=1e-12)  # right-handed: view is into the screen


def _hue_share(image: Image.Image, rgb, tol=0.12) -> float:
    """Fraction of pixels whose colour is a shade of ``rgb`` (same chromaticity; not the white background)."""
    px = np.asarray(image.convert("RGB"), float) / 255.0
    s = px.sum(axis=2, keepdims=True)
    ok = (s[..., 0] > 0.15) & (px.min(axis=2) < 0.95)
    chroma = px / np.maximum(s, 1e-9)
    target = np.asarray(rgb) / np.sum(rgb)
    return float((ok & (np.abs(chroma - target).max(axis=2) < tol * target.max())).mean())


def test_preview_renders_panels_in_their_colours_over_a_grey_body_and_a_gif(walk_run, tmp_path):
    _, run = walk_run
    anim = read_run(run)
    files = preview(anim, tmp_path, settings=PreviewSettings(width=120, height=160))
    pngs = [f for f in files if f.suffix == ".png"]
    gif = [f for f in files if f.suffix == ".gif"]
    assert len(pngs) == anim.frame_count and len(gif) == 1
    first = Image.open(pngs[0])
    assert first.size == (120, 160)
    assert _hue_share(first, panel_colour(0)) > 0.02  # the skirt front, red
    assert _hue_share(first, BODY_COLOUR, tol=0.03) > 0.05  # the body, grey
    with Image.open(gif[0]) as g:
        assert g.n_frames == anim.frame_count
        assert g.info["duration"] == 40  # 25 fps
    # the body walks: the last frame differs from the first
    a, b = (np.asarray(Image.open(p).convert("L"), float) for p in (pngs[0], pngs[-1]))
    assert np.abs(a - b).mean() > 1.0


def test_preview_options_and_cli(walk_run, tmp_path, capsys):
    _, run = walk_run
    with pytest.raises(TailorError):
        PreviewSettings(width=4)
    assert main(["preview", str(run), "--out", str(tmp_path / "p"), "--size", "80x100", "--every", "2", "--no-gif"]) == 0
    assert sorted(f.name for f in (tmp_path / "p").iterdir()) == ["frame_0000.png", "frame_0002.png"]
    assert main(["preview", str(run), "--size", "big"]) == 2
    assert "--size" in capsys.readouterr().err


def test_layout_keeps_panels_apart():
    pattern = read_pattern(PANELS / "tshirt.json")
    from shapely.geometry import Polygon

    from tailor.curves import loop_polyline

    polys = [Polygon(loop_polyline([e.curve for e in p.edges]) + o) for p, o in zip(pattern.panels, panel_layout(pattern))]
    for i in range(len(polys)):
        for j in range(i + 1, len(polys)):
            assert polys[i].distance(polys[j]) > 0.05


@pytest.mark.parametrize("suffix", ["png", "svg"])
def test_draw_pattern_writes_png_and_svg_with_every_seam_number(tmp_path, suffix):
    pattern = read_pattern(PANELS / "tshirt.json")
    out = tmp_path / f"tshirt.{suffix}"
    draw_pattern(pattern, out, mesh_resolution=0.05 if suffix == "png" else None)
    if suffix == "svg":
        text = out.read_text()
        assert text.lstrip().startswith("<?xml") and "</svg>" in text
        for name in (p.name for p in pattern.panels):
            assert name in text  # matplotlib keeps each text as a comment beside its glyphs
    else:
        image = Image.open(out)
        assert image.size[0] > 400 and _hue_share(image, panel_colour(1), tol=0.2) > 0.01


def test_cli_draw_refuses_other_formats(tmp_path, capsys):
    assert main(["draw", str(PANELS / "skirt.json"), "--out", str(tmp_path / "x.jpg")]) == 2
    assert ".png or .svg" in capsys.readouterr().err
    assert not (tmp_path / "x.jpg").exists()
