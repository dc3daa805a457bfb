"""Frames streamed to disk as the simulation hands them over (DrapeWriter, keep_frames=False)."""

import json
import tracemalloc
import weakref

import numpy as np
import pytest

from conftest import PANELS
from tailor.dress import DrapeFrame, drape
from tailor.errors import TailorError
from tailor.io import read_pattern
from tailor.io.animation import read_loads
from tailor.io.body_files import read_body
from tailor.io.garment import DrapeWriter, write_drape

RUN = dict(frames=3, resolution=0.06, quality="draft")  # as conftest's walk_run


def _frames(result):
    """The kept result's frames as a sink receives them."""
    for k, x in enumerate(result.frames):
        mesh, weld = result.topology_at(k)
        yield DrapeFrame(k, x, result.body_frames[k], result.contact_forces[k], result.attachment_forces[k], mesh, weld)


def test_a_streamed_drape_writes_the_files_a_kept_one_does(walk_run, tmp_path):
    kept, folder = walk_run
    body = read_body("mannequin-walk")
    with DrapeWriter(tmp_path / "streamed", kept.pattern, body_faces=body.faces) as writer:
        result = drape(read_pattern(PANELS / "skirt.json"), body, sink=writer, keep_frames=False, **RUN)
        out = writer.finish(result.report)
    assert result.frames == [] and result.body_frames == [] and result.contact_forces == []
    names = sorted(p.name for p in folder.iterdir())
    assert names == sorted(p.name for p in out.iterdir())
    for name in names:
        if name.endswith((".obj", ".mtl")):
            assert (out / name).read_text() == (folder / name).read_text(), name
    n = kept.report.welded_vertices
    for a, b in zip(read_loads(out, 3, n), read_loads(folder, 3, n)):
        assert np.array_equal(a, b)
    mine, theirs = (json.loads((f / "report.json").read_text()) for f in (out, folder))
    assert mine["frames_written"] == theirs["frames_written"] == 3
    assert mine["crossings_per_frame"] == theirs["crossings_per_frame"]
    assert mine["max_penetration_m_per_frame"] == theirs["max_penetration_m_per_frame"]


def test_memory_does_not_grow_with_the_frames_when_none_are_kept():
    """The traced memory as each walking frame leaves: it grows by a frame's arrays per frame when
    frames are kept (the garment's and the body's positions, the loads), not when they only stream
    out; and no frame's arrays outlive the next frame then."""
    pattern, body = read_pattern(PANELS / "skirt.json"), read_body("mannequin-walk")

    def growth(keep: bool) -> float:
        current, alive = [], []

        def sink(frame):
            current.append(tracemalloc.get_traced_memory()[0])
            alive.append(weakref.ref(frame.x))
            if not keep and frame.index >= 2:
                assert alive[-3]() is None, f"frame {frame.index - 2}'s positions are still held"

        tracemalloc.start()
        try:
            drape(pattern, body, frames=24, resolution=0.08, keep_frames=keep, sink=sink)
        finally:
            tracemalloc.stop()
        # bytes a frame, fitted over the last 16 frames (the body's broad phase fills its caches before)
        return float(np.polyfit(np.arange(16), current[-16:], 1)[0])

    kept, streamed = growth(True), growth(False)
    assert kept >= 24 * len(body.frames[0])  # at least the body's positions are kept each frame
    assert streamed < 0.25 * kept


def test_a_writer_shows_nothing_until_finished_and_nothing_after_a_failure(walk_run, tmp_path):
    result, _ = walk_run
    out = tmp_path / "run"
    with pytest.raises(RuntimeError, match="stopped"), DrapeWriter(out, result.pattern) as writer:
        for frame in _frames(result):
            writer(frame)
            assert not out.exists()
        raise RuntimeError("simulation stopped")
    assert list(tmp_path.iterdir()) == []  # no folder, no temporary one
    with DrapeWriter(out, result.pattern) as writer:
        frames = list(_frames(result))
        with pytest.raises(ValueError, match="frame 1 given where frame 0 was due"):
            writer(frames[1])
        for frame in frames:
            writer(frame)
        writer.finish(result.report)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run"]
    assert json.loads((out / "report.json").read_text())["frames_written"] == 3
    with pytest.raises(TailorError, match="already exists"):
        DrapeWriter(out, result.pattern)


def test_write_drape_refuses_a_result_without_frames(walk_run, tmp_path):
    result, _ = walk_run
    from dataclasses import replace

    with pytest.raises(TailorError, match="keep_frames=False"):
        write_drape(replace(result, frames=[], body_frames=[]), tmp_path / "empty")
    assert list(tmp_path.iterdir()) == []
