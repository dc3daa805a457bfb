"""Every example runs (TAILOR_QUICK=1, under a minute) and writes under out/ in the working directory."""

import os
import subprocess
import sys
from pathlib import Path

import pytest

EXAMPLES = sorted((Path(__file__).resolve().parents[1] / "examples").glob("*.py"))


@pytest.mark.parametrize("script", EXAMPLES, ids=lambda p: p.stem)
def test_example_runs_quickly(script, tmp_path):
    env = dict(os.environ, TAILOR_QUICK="1", MPLBACKEND="Agg")
    proc = subprocess.run([sys.executable, str(script)], cwd=tmp_path, env=env, capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr[-2000:]
    written = [p for p in (tmp_path / "out").rglob("*") if p.is_file()]
    assert written, "an example must write its output under out/"
    assert not [p for p in tmp_path.iterdir() if p.name != "out"], "nothing outside out/"
