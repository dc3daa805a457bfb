"""The bench's measurements: rest-space error, Pareto frontier, outputs, and the stability corners."""


import numpy as np
import pytest

from tailor import bench
from tailor.scenes import grid


def test_rest_error_compares_different_resolutions_through_the_rest_parametrisation():
    def surface(uv):  # a smooth drape-like shape
        return np.c_[uv, 0.1 * np.sin(3 * uv[:, 0]) * np.cos(2 * uv[:, 1])]

    fine, coarse = grid(1.0, 1.0, 41), grid(1.0, 1.0, 9)
    mean, worst = bench.rest_error(fine.uv, surface(fine.uv), coarse.uv, surface(coarse.uv))
    assert worst < 2e-3  # the same surface: only the fine mesh's interpolation error
    shifted = surface(coarse.uv) + [0.0, 0.0, 0.01]
    mean, worst = bench.rest_error(fine.uv, surface(fine.uv), coarse.uv, shifted)
    assert mean == pytest.approx(0.01, abs=2e-3)


def test_pareto_keeps_only_runs_nothing_beats_and_outputs_are_written(tmp_path):
    runs = [bench.Run("sphere", "implicit", 16, dt, 10.0, 1e-3, wall_s=w, error_mean_mm=e, error_max_mm=2 * e)
            for dt, w, e in ((0.04, 1.0, 10.0), (0.02, 2.0, 5.0), (0.01, 3.0, 6.0), (0.005, 4.0, 1.0))]
    runs.append(bench.Run("sphere", "symplectic", 16, 1e-3, 4.0, None, stable=False, note="simulation unstable"))
    front = bench.pareto(runs)
    assert [r.dt for r in front] == [0.04, 0.02, 0.005]  # 0.01 is slower and worse than 0.02
    paths = bench.write_results(runs, tmp_path)
    assert {p.name for p in paths} == {"results.csv", "results.md", "pareto_sphere.png"}
    assert all(p.stat().st_size > 0 for p in paths)
    assert "no: simulation unstable" in (tmp_path / "results.md").read_text()


@pytest.mark.parametrize("integrator", ["implicit", "symplectic"])
def test_stability_corners_finish_or_stop_with_the_unstable_error(integrator, tmp_path):
    axes = {"density_g_m2": (5.0, 10000.0), "stretch_pct": (0.1, 50.0), "bending": (0.0, 1000.0)}
    rows = bench.stability_map(integrators=(integrator,), axes=axes, size=0.3, duration=0.2)
    assert len(rows) == 6
    for _, axis, value, outcome, _, detail in rows:
        assert outcome in ("ok", "unstable"), (axis, value, detail)
        if outcome == "unstable":  # a clear message: where, the step, and what to try
            assert "simulation unstable at t =" in detail and "Δt =" in detail and "try" in detail
    paths = bench.write_stability(rows, tmp_path)
    assert all(p.exists() for p in paths)


def test_an_explicit_step_far_beyond_eq24_stops_with_the_unstable_error_not_nan():
    from tailor.errors import SimulationUnstable
    from tailor.scenes import two_corner_hang

    setup = two_corner_hang(8, duration=0.5)
    frames = []
    with pytest.raises(SimulationUnstable, match="try a smaller time step"):
        from tailor.scenes import run_scene
        run_scene(setup.model, setup.x0, duration=setup.duration, integrator="symplectic", dt=8 * setup.model.time_step,
                  self_collision="off", on_frame=lambda i, st: frames.append(st.x.copy()))
    assert all(np.isfinite(f).all() for f in frames)


def test_rest_error_matches_rest_points_panel_by_panel():
    # two panels share the same uv square but lie 5 cm apart: matched per panel, the error is zero
    g = grid(0.3, 0.3, 7)
    uv = np.r_[g.uv, g.uv]
    panel = np.r_[np.zeros(len(g.uv), int), np.ones(len(g.uv), int)]
    x = np.c_[uv, 0.05 * panel]
    fine = grid(0.3, 0.3, 13)
    ref_uv, ref_panel = np.r_[fine.uv, fine.uv], np.r_[np.zeros(len(fine.uv), int), np.ones(len(fine.uv), int)]
    ref_x = np.c_[ref_uv, 0.05 * ref_panel]
    assert bench.rest_error(ref_uv, ref_x, uv, x, ref_panel, panel)[1] < 1e-9
    assert bench.rest_error(ref_uv, ref_x, uv, x, ref_panel, 1 - panel)[0] == pytest.approx(0.05)


def test_peak_memory_counts_what_the_block_allocated():
    import sys

    import numpy as np

    from tailor.bench import PeakMemory

    with PeakMemory() as small:
        pass
    with PeakMemory() as big:
        a = np.ones(10_000_000)  # 80 MB, touched
        del a
    if not sys.platform.startswith("linux"):
        assert np.isnan(big.mb)
        return
    assert 70.0 < big.added < 200.0 and big.mb > big.added
    assert small.added < 10.0 and small.mb < big.mb


def test_a_savings_run_that_goes_unstable_is_recorded_not_fatal(monkeypatch):
    # the full bench lost ten minutes of sweep results when one savings run stopped
    import types

    from tailor import bench
    from tailor.errors import SimulationUnstable

    real = bench.sphere_drop

    def fake(n, fabric):
        setup = real(4, fabric=fabric)

        def run(dt, tolerance, self_collision):
            if self_collision == "auto":
                raise SimulationUnstable("simulation unstable at t = 0.24 s: stretched 4.09x")
            report = {"self_collision": {"active_steps": 1, "steps": 2, "max_active_vertices": 3, "query_s": 0.0}}
            return types.SimpleNamespace(report=report)

        setup.run = run
        return setup

    monkeypatch.setattr(bench, "sphere_drop", fake)
    seen = []
    rows = bench.savings(quick=True, progress=lambda i, total, item: seen.append(item[3]))
    assert len(rows) == 5 and seen.count("unstable") == 1
    auto = [r for r in rows if r[1] == "auto"][0]
    assert "stopped: simulation unstable" in auto[3]
