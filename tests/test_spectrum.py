"""sph.spectrum: the highest eigenfrequency ω_max of each method's linearised discrete system and
its critical time step Δt_crit = 2/ω_max, checked against a dense eigensolve of the assembled
tangent (csph, hpm) and against the explicit loops themselves (every method: stable just below
Δt_crit, exponential blow-up just above it)."""
import dataclasses

import numpy as np
import pytest
import scipy.linalg

from sph import driver
from sph.driver import Run, method_entry, model_at
from sph.particles import discretise
from sph.driver import scene_time_steps
from sph.spectrum import critical_time_step, max_frequency
from workbench.scenes import Plate
from workbench.scenes.params import SceneError

RES = 4  # the plate at H/Δx = 4: 600 free DOFs, a dense eigensolve takes ~0.1 s
SHORT = Plate(periods=0.1)  # ~0.1 plate period: hundreds of steps, enough for a blow-up to show


def _body(method, scene=SHORT, res=RES, lattice=None, **options):
    mod, defaults = method_entry(method)
    model, _ = model_at(scene, res)
    ps = discretise(model, res, lattice)
    body = mod.build(ps, **{**defaults, **options})
    return body, Run(model, ps, body).fixed


@pytest.mark.parametrize("method", ["csph", "hpm"])
def test_max_frequency_matches_the_dense_eigensolve(method):
    """ω_max of the matrix-free Lanczos on the central difference of the force equals the largest
    generalised eigenvalue of (K, M) with K the assembled tangent of the gradient form
    (sph.total_lagrangian.tangent_matrix) and M the lumped masses, on the free DOFs. Tolerance
    1e-5: ARPACK is asked for 1e-6 on ω², the central difference's truncation is O(ε²) ~ 1e-12 and
    its round-off ~1e-8 at the perturbation strain 1e-6."""
    body, fixed = _body(method)
    tlb = body.gradient_form()
    _, A = tlb.evaluate(body.X.copy(), tangent=True)
    K = tlb.tangent(A).toarray()
    free = ~fixed.ravel()
    m = np.repeat(body.m, body.dim)[free]
    w2 = scipy.linalg.eigh(K[np.ix_(free, free)], np.diag(m), eigvals_only=True)
    w_ref = np.sqrt(w2.max())
    w = max_frequency(body, fixed)
    assert w == pytest.approx(w_ref, rel=1e-5)
    assert critical_time_step(body, fixed) == pytest.approx(2.0 / w_ref, rel=1e-5)


def _run(method, factor, scene=SHORT, reference="spectrum", **options):
    d = dataclasses.replace(scene.model().drive, dt_factor=factor, dt_reference=reference)
    return driver.solve(method, scene, RES, drive=d, **options)


# Every method on the plate: stable at 0.9 Δt_crit, blown up (exponential energy growth) at
# 1.1 Δt_crit — the critical step of eq. (1) is the integration's to within ±10 %. Classic SPH
# without its artificial viscosity (the linearisation leaves the viscosity out: it damps, and a
# velocity force taken explicitly lowers the critical step — with α = β = 1 the plate blows up at
# 0.9 Δt_crit and is stable at 0.7, see test_stability.py).
CASES = [("csph", {}), ("hpm", {}), ("sph", {"lattice": "cell", "alpha": 0.0, "beta": 0.0})]


@pytest.mark.parametrize("method,options", CASES, ids=[c[0] for c in CASES])
def test_critical_step_is_where_the_explicit_loop_blows_up(method, options):
    below = _run(method, 0.9, **options)
    assert below["status"] == "ok", below["status"]
    above = _run(method, 1.1, **options)
    assert above["criterion"] in ("energy", "non-finite"), above["status"]


def test_dt_reference_spectrum_rescues_consistent_csph_on_a_cell_lattice():
    """Integration-consistent csph on a cell lattice: the correction extrapolates half a spacing
    beyond the outermost particles and ω_max rises far above the CFL estimate (Δt_crit ≈ 0.11
    Δx/c_p on this plate), so the run blows up at the CFL step and is stable at 0.9 Δt_crit."""
    opts = dict(lattice="cell", integration="consistent")
    steps = scene_time_steps("csph", SHORT, RES, **opts)
    assert steps["dt_crit"] < 0.5 * steps["dt_cfl"]
    assert _run("csph", 1.0, reference="cfl", **opts)["criterion"] in ("energy", "non-finite")
    ok = _run("csph", 0.9, **opts)
    assert ok["status"] == "ok", ok["status"]
    assert ok["dt"] == pytest.approx(0.9 * steps["dt_crit"], rel=1e-6)


def test_dt_reference_is_validated():
    d = dataclasses.replace(SHORT.model().drive, dt_reference="courant")
    with pytest.raises(SceneError, match="dt_reference"):
        driver.solve("hpm", SHORT, RES, drive=d)
