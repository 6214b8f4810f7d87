"""The micro-cantilever past its first failure (issue 36): the crack maps draw every particle, the
failed particles merge into their faces (fragment measures and gate), the crack's position and
peak load over the ladder, and 000's csph_bl beside csph."""
import numpy as np
import pytest

from studies.microcantilever.scene import MicroCantilever
from test_microcantilever_study import _lattice_out


def test_crack_map_draws_every_particle(monkeypatch, tmp_path):
    """The crack map (studies.microcantilever.cracked) draws the final particles on the deformed
    shape and its axes cover every one drawn: a failed particle that has left the body's
    reference box by 10 µm (a fragment) and one 3 µm below it are inside each panel's limits, and
    so is every intact particle. (The map took the reference box: those fell outside.)"""
    import matplotlib

    matplotlib.use("Agg")
    import xarray as xr

    from studies import figures
    from studies.microcantilever.figures import cracked

    figs = []
    monkeypatch.setattr(figures, "save", lambda fig, path: figs.append(fig) or path)
    dx = 1e-6
    ix, iy = np.meshgrid(np.arange(-5, 21), np.arange(-3, 3), indexing="ij")
    X = np.stack([ix.ravel(), iy.ravel()], 1) * dx + np.array([0.0, 0.5 * dx])
    n = len(X)
    x = X + np.stack([np.zeros(n), -1e-8 * np.clip(X[:, 0], 0, None) / dx], 1)
    failed = np.zeros(n, np.int8)
    far, low = n - 1, n // 2
    failed[[far, low]] = 1
    x[far] += np.array([10e-6, 4e-6])  # a fragment, far off the free end
    x[low, 1] -= 3e-6
    xs = np.stack([x, x])[:, None]  # (case, rule, particle, axis)
    ds = xr.Dataset(
        dict(particle_X=(("case", "rule", "particle", "axis"), np.stack([X, X])[:, None]),
             particle_x=(("case", "rule", "particle", "axis"), xs),
             particle_region=(("case", "rule", "particle"), np.zeros((2, 1, n), np.int64)),
             particle_failed=(("case", "rule", "particle"), np.stack([failed, failed])[:, None]),
             particle_resolution=(("case", "rule"), np.full((2, 1), 5))),
        coords=dict(case=["inter", "intra"], rule=["compression"]),
        attrs=dict(region_names="grain0", param_H=5e-6, plane="strain"))
    cracked(ds, tmp_path / "cracks.png")
    (fig,) = figs
    panels = [ax for ax in fig.axes if ax.collections]
    assert len(panels) == 2
    for ax in panels:
        (x0, x1), (y0, y1) = ax.get_xlim(), ax.get_ylim()
        um = x * 1e6
        assert np.all((um[:, 0] >= x0) & (um[:, 0] <= x1)), (x0, x1, um[:, 0].max())
        assert np.all((um[:, 1] >= y0) & (um[:, 1] <= y1)), (y0, y1, um[:, 1].min())


def test_fragment_measures():
    """fragment_measures: the largest speed of the failed particles and their kinetic energy
    Σ ½ ρ V |v|² over the released energy, by hand on three particles (two failed); NaN without
    velocities."""
    from studies.microcantilever.derive import fragment_measures

    sc = MicroCantilever(dim=2)
    out = dict(v=np.array([[3.0, 4.0], [0.0, 1.0], [9.0, 9.0]]), volume=np.array([2e-12, 1e-12, 1e-12]),
               failed_particles=np.array([True, True, False]), released_energy=np.array([0.0, 1e-6]))
    m = fragment_measures(out, sc)
    assert m["fragment_speed_max"] == pytest.approx(5.0)
    ke = 0.5 * sc.rho * (2e-12 * 25.0 + 1e-12 * 1.0)
    assert m["fragment_kinetic_share"] == pytest.approx(ke / 1e-6, rel=1e-12)
    assert np.isnan(fragment_measures({**out, "v": None}, sc)["fragment_speed_max"])
    # relative to the faces: the intact particles within 2.2 spacings (here the third, 1.5 spacings
    # from the first and 3.5 from the second); a loading-patch particle is not counted
    dx = 1e-6
    X = np.array([[0.0, 0.0], [5e-6, 0.0], [1.5e-6, 0.0]])
    m = fragment_measures({**out, "X": X}, sc, dx)
    rel = np.array([np.hypot(3.0 - 9.0, 4.0 - 9.0), np.hypot(0.0, 1.0)])  # v − v̄ (none near: 0)
    assert m["fragment_relative_speed_max"] == pytest.approx(rel.max())
    assert m["fragment_relative_kinetic_share"] == pytest.approx(
        0.5 * sc.rho * (2e-12 * rel[0] ** 2 + 1e-12 * rel[1] ** 2) / 1e-6, rel=1e-12)
    m = fragment_measures({**out, "X": X, "sets": {"patch": np.array([0])}}, sc, dx)
    assert m["fragment_speed_max"] == pytest.approx(1.0)


def test_crack_position_and_its_convergence_gates():
    """crack_position: the main crack's mean reference x and the region holding most of its
    particles, at the record of the cut; the gates of issue 36 item 3 on a made-up ladder: the
    position at the two finest within one spacing of the coarser (0.2 µm apart at H/Δx = 15, 20:
    0.6 of H/15) and the peak load converging at an observed order (values 200 − 100 (5/r)^p at
    p = 1: order 1), both failing when the finest moves (position 2 spacings off; the load's
    differences changing sign)."""
    import xarray as xr

    from studies.microcantilever.derive import crack_position
    from studies.microcantilever.gates import crack_convergence_gates

    dx = 0.5e-6
    out = _lattice_out([(4, j) for j in range(11)] + [(16, 10)], dx)
    out.update(region=np.where(np.arange(len(out["X"])) % 2 == 0, 1, 0),
               region_names=["grain0", "gb01"])
    x, reg = crack_position(out, dx)
    assert x == pytest.approx(4 * dx) and reg == "gb01"  # 6 of the 11 have an even index

    def ds_of(xs, peaks):
        res = [5, 10, 15, 20]
        shp = (1, 2, 1, 4)
        val = lambda a: np.broadcast_to(np.asarray(a, float), shp).copy()  # noqa: E731
        return xr.Dataset(dict(crack_x=(("solver", "case", "rule", "resolution"), val(xs)),
                               max_load=(("solver", "case", "rule", "resolution"), val(peaks)),
                               t_separated=(("solver", "case", "rule", "resolution"), val(1e-6)),
                               crack_region=(("solver", "case", "rule", "resolution"),
                                             np.full(shp, "gb01"))),
                          coords=dict(solver=["csph"], case=["inter", "intra"],
                                      rule=["compression"], resolution=res),
                          attrs=dict(param_H=5e-6))

    H = 5e-6
    peaks = [200 - 100 * (5 / r) for r in (5, 10, 15, 20)]
    g = crack_convergence_gates(ds_of([3e-6, 3.1e-6, 3.3e-6, 3.1e-6], peaks))
    assert len(g) == 4 and all(x.passed for x in g), [x.line() for x in g]
    assert g[0].observed == pytest.approx(0.2e-6 / (H / 15))
    assert g[1].observed == pytest.approx(1.0, rel=1e-6)
    bad = crack_convergence_gates(ds_of([3e-6, 3.1e-6, 3.3e-6, 3.3e-6 + 2 * H / 15],
                                        peaks[:3] + [peaks[2] - 1.0]))
    assert not any(x.passed for x in bad)


def _made_up_run(peak, n=6):
    """A made-up driver output: the load rises linearly to ``peak`` (N/m) at 2 µs, where the
    first particle fails, and falls to zero; n particles on a row, the first failed."""
    t = np.linspace(0.0, 4e-6, 401)
    F = np.where(t < 2e-6, peak * t / 2e-6, 0.0)
    W = 1e-9 * (t / t[-1])
    X = np.stack([np.arange(n) * 1e-6, np.zeros(n)], 1)
    failed = np.zeros(n, bool)
    failed[0] = True
    return dict(time=t, load=F, deflection_down=0.05 * t, failed=(t >= 2e-6).astype(float),
                external_work=W, kinetic_energy=0 * W, strain_energy=W, plastic_work=0 * W,
                released_energy=0 * W, status="ok", X=X, x=X, region=np.zeros(n, np.int64),
                region_names=["grain0"], failed_particles=failed, v=np.zeros((n, 2)),
                volume=np.full(n, 1e-12), n_particles=n)


def test_csph_bl_beside_csph(monkeypatch, tmp_path):
    """000's method (csph_bl) runs beside csph (issue 36, item 4): the dataset holds both solvers'
    runs on its ``solver`` coordinate (csph_bl under the default rule only), the report sets their
    peak loads side by side, the accuracy-against-cost rows list both, the crack map draws a row
    for each, and the gates stay csph's."""
    import matplotlib

    matplotlib.use("Agg")
    from studies import figures
    from studies.microcantilever.dataset import dataset
    from studies.microcantilever.figures import cracked
    from studies.microcantilever.gates import errors, gates
    from studies.microcantilever.report import comparison_notes

    sc = MicroCantilever(dim=2)
    outs = {("csph", c, rule, 5): _made_up_run(180.0) for c in ("inter", "intra")
            for rule in ("compression", "literal")}
    outs.update({("csph_bl", c, "compression", 5): _made_up_run(150.0) for c in ("inter", "intra")})
    ds = dataset(sc, outs, ["compression", "literal"], [5], solvers=("csph", "csph_bl"))
    assert list(ds.solver.values) == ["csph", "csph_bl"]
    assert float(ds.peak_load.sel(solver="csph_bl", case="inter", rule="compression",
                                  resolution=5)) == pytest.approx(150.0 * (1 - 1 / 200), rel=1e-9)
    assert str(ds.status.sel(solver="csph_bl", case="inter", rule="literal", resolution=5).values) \
        == "not run"
    (line, _) = comparison_notes(ds)
    assert "csph peak 179.1" in line and "csph_bl peak 149.2" in line, line
    assert sorted({r["solver"] for r in errors(ds)}) == ["csph (inter)", "csph (intra)",
                                                         "csph_bl (inter)", "csph_bl (intra)"]
    assert gates(ds) and not any("csph_bl" in g.name for g in gates(ds))
    assert ds.particle_x.dims[0] == "solver"
    figs = []
    monkeypatch.setattr(figures, "save", lambda fig, path: figs.append(fig) or path)
    cracked(ds, tmp_path / "cracks.png")
    titles = [ax.get_title() for ax in figs[0].axes if ax.collections]
    assert len(titles) == 6 and sum("csph_bl" in t for t in titles) == 2, titles


def test_run_makes_the_csph_bl_runs(monkeypatch):
    """study.run with csph_bl among the solvers makes its runs under the default rule beside
    csph's (the quick run: csph alone unless asked), on the same resolutions."""
    from studies.microcantilever import study

    seen = []

    def fake_tasks(tasks, scheduler, title):
        seen.extend(tasks)
        return [_made_up_run(150.0 if t.solver == "csph_bl" else 180.0) for t in tasks]

    monkeypatch.setattr(study, "run_tasks", fake_tasks)
    monkeypatch.setattr(study, "fem_ladder", lambda *a, **k: None)
    ds = study.run(quick=True)
    assert {t.solver for t in seen} == {"csph"} and list(ds.solver.values) == ["csph"]
    seen.clear()
    ds = study.run(quick=True, solvers=["csph", "csph_bl"])
    runs = sorted((t.solver, t.scene.case, t.scene.name.split("_")[-1], t.resolution) for t in seen)
    assert runs == [("csph", "inter", "compression", 5), ("csph", "intra", "compression", 5),
                    ("csph_bl", "inter", "compression", 5), ("csph_bl", "intra", "compression", 5)]
    assert list(ds.solver.values) == ["csph", "csph_bl"]


def test_fragment_gate():
    """Issue 36's bar, relative to the faces: a run whose failed particles carry 0.4 % of the
    released energy relative to the intact particles around them passes, one with 13.8 % (intra,
    2-D H/Δx = 5, before they merged into the faces) fails."""
    import xarray as xr

    from studies.microcantilever.gates import fragment_gates

    sel = dict(solver="csph", case="intra", rule="compression", resolution=5)
    for share, ok in ((0.004, True), (0.138, False)):
        var = (tuple(sel), np.full((1,) * 4, share))
        ds = xr.Dataset(dict(fragment_relative_kinetic_share=var),
                        coords={k: [v] for k, v in sel.items()})
        (g,) = fragment_gates(ds, "t", sel)
        assert g.passed is ok
