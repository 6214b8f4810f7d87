"""The fracture-mode competition study (issue 36, item 2: ``workbench run microcantilever_mode``):
its quick run passes its gates, each gate fails on a regression and on a NaN, the transition and
its convergence gate against hand-computed crossings, and the pad that keeps the loading patch on
the beam."""
import math

import numpy as np
import pytest
import xarray as xr

import studies
from studies.microcantilever import mode
from studies.microcantilever.padded import PaddedCantilever


@pytest.fixture(scope="module")
def quick():
    """The quick sweep (2 seeds, 3 ratios, H/Δx = 5, 2-D): 6 runs of csph."""
    return mode.run(quick=True)


def test_registered_as_its_own_study():
    assert studies.get("microcantilever_mode") is mode
    assert mode.SCENE is PaddedCantilever


def test_quick_run_passes_its_gates(quick):
    assert dict(quick.sizes) == {"resolution": 1, "ratio": 3, "seed": 2}
    assert (quick.status.values == "ok").all(), quick.status.values
    gates = mode.gates(quick)
    assert len(gates) == mode.N_GATES[True], [g.name for g in gates]
    for g in gates:
        assert g.passed, g.line()
        assert g.reference, g.name


def test_every_quick_gate_fails_a_regression_and_a_nan(quick):
    """Each gate, fed its regression (Gate.regressed: the other outcome of an outcome gate), fails;
    a NaN share of one run at either limit ratio fails the gates that read it (never drops
    them)."""
    for g in mode.gates(quick):
        assert not g.regressed(3.0).passed, g.line()
    for q in (quick.ratio.values[0], quick.ratio.values[-1]):
        bad = quick.copy(deep=True)
        bad["share_gb"].loc[dict(ratio=q, seed=quick.seed.values[0])] = np.nan
        gates = mode.gates(mode.derive(bad))
        assert len(gates) == mode.N_GATES[True]
        failed = {g.name for g in gates if not g.passed}
        assert any(f"mode at rho={q:g}" in n for n in failed), failed
        assert any("crosses 50 %" in n for n in failed), failed
        assert any("monotone" in n for n in failed), failed


def test_transition_against_hand_interpolation():
    """Linear in log ρ: shares 0.2 at ρ = 1 and 0.8 at ρ = 4 cross 0.5 at ρ = 2 exactly; no
    crossing (already above at the first ratio, never reaching it, a NaN) is NaN."""
    assert mode.transition([1, 4, 10], [0.2, 0.8, 1.0]) == pytest.approx(2.0, rel=1e-12)
    assert mode.transition([1, 2, 4], [0.0, 0.25, 1.0]) == pytest.approx(2 * 2 ** (1 / 3), rel=1e-12)
    for share in ([0.6, 0.9, 1.0], [0.1, 0.2, 0.3], [0.1, np.nan, 1.0]):
        assert math.isnan(mode.transition([1, 2, 4], share))


def _synthetic(transitions, ratios=mode.RATIOS, seeds=(1, 2, 3, 4, 5)):
    """A dataset whose share at each resolution is linear in log ρ, 0.5 at that resolution's
    transition and rising 0.4 per decade (clipped to [0, 1]: between 1 and 10 it is not), the
    same for every seed (no scatter): the interpolation is exact."""
    q = np.log(np.asarray(ratios, float))
    share = np.stack([np.clip(0.5 + 0.4 * (q - math.log(t)) / math.log(10.0), 0.0, 1.0)
                      for t in transitions])
    share = np.repeat(share[:, :, None], len(seeds), axis=2)
    ds = xr.Dataset({"share_gb": (("resolution", "ratio", "seed"), share)},
                    coords={"resolution": [5, 10][:len(transitions)], "ratio": list(ratios),
                            "seed": list(seeds)})
    return mode.derive(ds)


def test_convergence_gate_is_one_sweep_step():
    """The transition moving by half a step of the sweep passes, by 1.5 steps (three times)
    fails; the bootstrap interval of seeds without scatter is the transition itself."""
    step = 3.0 / 2.0  # the sweep between 2 and 3
    a = 2.4
    ok = _synthetic([a, a * step ** 0.5])
    g = mode.convergence_gate(ok)
    assert g.passed and g.observed == pytest.approx(0.5, rel=1e-9), g.line()
    assert not g.regressed(3.0).passed
    lo, hi = a / step ** 0.75, a * step ** 0.75  # in (1.5, 2) and (3, 4)
    bad = mode.convergence_gate(_synthetic([lo, hi]))
    assert not bad.passed, bad.line()
    assert bad.observed == pytest.approx(math.log(hi / lo) / math.log(4 / 3), rel=1e-9)
    assert float(ok.transition_lo[0]) == pytest.approx(float(ok.transition[0]))
    nan = ok.copy(deep=True)
    nan["share_gb"][1, 0, 0] = np.nan
    assert not mode.convergence_gate(mode.derive(nan)).passed


def test_monotone_gate_allows_the_seeds_scatter_only():
    """A fall of the mean share smaller than two standard errors of the seeds' scatter passes; a
    fall of a share without scatter fails."""
    drop, _ = mode.monotone_drop([0.1, 0.6, 0.5, 1.0], [0.0, 0.3, 0.3, 0.0], 5)
    assert drop < 0  # 0.1 fall within 2·√(0.09 + 0.09)/√5 = 0.38
    drop, k = mode.monotone_drop([0.1, 0.6, 0.5, 1.0], [0.0, 0.0, 0.0, 0.0], 5)
    assert drop == pytest.approx(0.1) and k == 1


def test_the_pad_does_not_fail_and_only_the_pad():
    """The padded scene's extra regions (pad_*) never fail (ε_L = ∞), lie within ``pad`` of the
    loading patch, take the law of the region they cover, and ``pad`` = 0 is the plain scene."""
    sc = mode.mode_scene(PaddedCantilever(), 2.0, 3)
    dx = sc.H / 5
    model = sc.model(dx)
    plain = {r.name: r for r in PaddedCantilever(pad=0.0).model(dx).regions}
    pads = [r for r in model.regions if r.name.startswith("pad_")]
    assert pads and {r.name[4:] for r in pads} <= set(plain)
    a, b = sc.patch_edges(dx)
    for r in pads:
        base = next(x for x in model.regions if x.name == r.name[4:])
        assert math.isinf(r.material.eps_L) and r.material.E == base.material.E
        lo, hi = np.asarray(r.shape.bounds()[0]), np.asarray(r.shape.bounds()[1])
        assert lo[0] >= a - sc.pad - 1e-12 and hi[0] <= b + sc.pad + 1e-12
    x = np.array([[0.5 * (a + b), sc.H / 2 - 0.5 * sc.pad], [0.5 * (a + b), 0.0]])
    inside = np.any([r.shape.contains(x) for r in pads], axis=0)
    assert inside.tolist() == [True, False]


def _failed_near_patch(sc, out, dx):
    """The failed particles within ``sc.pad`` (1 µm) of the loading patch, and all failed, (x, y)."""
    a, b = sc.patch_edges(dx)
    X = np.asarray(out["X"])[np.asarray(out["failed_particles"], bool)]
    near = (X[:, 0] >= a - 1e-6 - 1e-12) & (X[:, 0] <= b + 1e-6 + 1e-12) & \
        (X[:, 1] >= sc.H / 2 - 1e-6 - 1e-12)
    return X[near], X


def test_without_the_pad_the_patch_tears_off_and_with_it_the_beam_cracks():
    """Why the study loads through a pad (2-D, H/Δx = 5): without it (pad = 0; seed 3, ρ = 2)
    most failed particles lie under the rigid patch's ends and the 'cut' comes before 1.2 µs; with
    it (seed 1, ρ = 1) no particle fails there and the crack crosses the beam at its root, the
    cut after 1 µs. About 6 s."""
    from studies.common import run_solver

    dx = PaddedCantilever().H / 5
    plain = mode.mode_scene(PaddedCantilever(pad=0.0), 2.0, 3)
    out = run_solver("csph", plain, 5, crack="visibility")
    near, every = _failed_near_patch(plain, out, dx)
    assert out["status"] == "ok" and len(near) > len(every) / 2, every
    assert out["t_separated"] < 1.2e-6
    padded = mode.mode_scene(PaddedCantilever(), 1.0, 1)
    out = run_solver("csph", padded, 5, crack="visibility")
    near, every = _failed_near_patch(padded, out, dx)
    assert out["status"] == "ok" and len(near) == 0, near
    root = every[every[:, 0] <= 2e-6 + 1e-12]
    assert np.ptp(root[:, 1]) >= padded.H * 0.6, every  # across most of the height at the root
    assert out["t_separated"] > 1.0e-6
