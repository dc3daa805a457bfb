"""Same inputs, same bits: results do not depend on the number of threads (a batch worker pinned
to one core gives exactly what a two-core laptop gives)."""

from __future__ import annotations

import os
import subprocess
import sys

import numpy as np

SCRIPT = """
import sys, numpy as np
from tailor.scenes import sphere_drop
from tailor.forces.kernels import _tasks
setup = sphere_drop(80, duration=0.2)
assert _tasks(setup.model.face_count) > 1  # the threaded force path is taken
frames = setup.run(integrator="implicit", dt=0.02).frames
np.save(sys.argv[1], np.stack(frames))
"""


def test_a_scene_gives_the_same_bits_on_one_and_two_threads(tmp_path):
    out = {}
    for threads in (1, 2):
        env = {**os.environ, "NUMBA_NUM_THREADS": str(threads)}
        path = tmp_path / f"t{threads}.npy"
        subprocess.run([sys.executable, "-c", SCRIPT, str(path)], check=True, env=env, timeout=300)
        out[threads] = np.load(path)
    assert out[1].shape == out[2].shape and np.isfinite(out[1]).all()
    assert np.abs(out[1][-1] - out[1][0]).max() > 0.05  # it fell: the comparison is not of two rest states
    np.testing.assert_array_equal(out[1], out[2])
