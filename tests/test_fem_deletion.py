"""Element deletion for fracture (Problem(..., deletion=True)): a bar in uniaxial tension with one
weaker element loses all of its load when that element fails and is deleted.

The bar: 5 × 1 × 1 elements, 5 mm × 1 mm × 1 mm, Table 1 steel (J2, Swift hardening); the middle
element has the damage limit ε_L = 0.05, the others ε_L = ∞. Rollers on X = 0, Y = 0, Z = 0, the
end X = L moved axially to the log strain ε (displacement control), lateral faces free: uniaxial
stress. Every element has the same stress–strain curve until the weak one reaches D = ε_p/ε_L = 1,
so the state is homogeneous and the axial reaction is exactly the uniaxial curve,
R = τ(ε) e^{−ε} A₀ (the nominal stress: τ the Kirchhoff stress, workbench.analytic.uniaxial_curve),
up to the failure strain ε_f = ε_L + C (ε_L + ε0)^n / E. Past it the weak element carries no stress
(000 eq. 36), the others unload elastically to zero and R = 0 exactly; the weak element is deleted
at the step where it fails.
"""
import numpy as np
import pytest

from fem_reference.assembly import Discretisation
from fem_reference.boundary import Constraints
from fem_reference.mesh import box
from fem_reference.static import Problem, load_path
from workbench import analytic
from workbench.materials import HIST_DAMAGE, TABLE1_STEEL, MaterialTable

LB, W, N_EL = 5e-3, 1e-3, 5
EPS_L = 0.05
WEAK = TABLE1_STEEL.replace(eps_L=EPS_L)
EPS_F = EPS_L + WEAK.C * (EPS_L + WEAK.eps0) ** WEAK.n / WEAK.E
# Before failure: the FEM reproduces the homogeneous state (a patch test) to the Newton tolerance
# (1e-10 relative residual; measured ≤ 1.4e-12). After: a zero load to the same tolerance relative
# to the force scale of the step (the pre-failure reaction; measured ≤ 2.3e-9).
TOL_CURVE = 1e-9
TOL_ZERO = 1e-8


def bar(order, deletion="any"):
    disc = Discretisation(box((0, 0, 0), (LB, W, W), (N_EL, 1, 1)), order=order)
    xc = disc.centroids()[:, 0]
    mat_id = ((xc > 2 * LB / N_EL) & (xc < 3 * LB / N_EL)).astype(np.int64)  # the middle one
    bc = Constraints(disc)
    for k in range(3):
        bc.roller(lambda x, k=k: x[k] < 1e-12, k)
    end = bc.prescribe(lambda x: x[0] > LB - 1e-12, 0, lambda eps: LB * np.expm1(eps))
    bc.apply()
    problem = Problem(disc, MaterialTable((TABLE1_STEEL, WEAK)), None, bc.values,
                      lambda lam: np.zeros(disc.N), mat_id=mat_id, deletion=deletion)
    return problem, end


@pytest.mark.parametrize("order,rule", [(1, "any"), (2, "any"), (2, "all")],
                         ids=["hex8", "hex27", "hex27-all"])
def test_weak_element_fails_and_the_bar_unloads(order, rule):
    problem, end = bar(order, rule)
    disc = problem.disc
    eps = np.array([0.002, 0.01, 0.03, 0.05, EPS_F - 1e-4, EPS_F + 1e-4, EPS_F + 0.01,
                    EPS_F + 0.03])
    R = []

    def measure(k, lam, state):
        R.append(problem.evaluate(state.u, state, tangent=False)["f_int"][end].sum())

    mass0 = problem.mass().sum() / 3
    recs, state = load_path(problem, eps, max_increment=0.01, rtol=1e-10, callback=measure)
    assert all(r["status"] == "ok" for r in recs), [r["status"] for r in recs]
    R = np.array(R)
    before = eps < EPS_F
    ref = analytic.uniaxial_curve(TABLE1_STEEL, eps[before])["nominal"] * W * W
    assert np.abs(R[before] / ref - 1).max() < TOL_CURVE, R[before] / ref - 1
    assert np.abs(R[~before]).max() < TOL_ZERO * ref[-1], R[~before] / ref[-1]
    # the weak element, and only it, was deleted at the step that crossed ε_f
    assert [r["deleted"].tolist() for r in recs] == [[]] * 5 + [[2]] + [[]] * 2
    assert disc.active.tolist() == [True, True, False, True, True]
    assert np.all(state.history[2 * disc.nqp:3 * disc.nqp, HIST_DAMAGE] >= 1)
    # no mass from it any more: 4/5 of the bar's
    assert problem.mass().sum() / 3 == pytest.approx(0.8 * mass0, rel=1e-12)
    # the 27-node element leaves its centre and free-face nodes without an element: held
    assert len(problem.held) == (0 if order == 1 else 3 * 7)


@pytest.mark.parametrize("rule,deleted", [("any", [1, 3]), ("all", [3])])
def test_deletion_criterion(rule, deleted):
    """'any': an element goes when one of its points has D ≥ 1; 'all': when every one has."""
    problem, _ = bar(1, rule)
    disc = problem.disc
    state = problem.initial_state()
    D = state.history[:, HIST_DAMAGE].reshape(disc.nel, disc.nqp)
    D[1, 0] = 1.0  # element 1: one point
    D[3, :] = 1.5  # element 3: all points
    D[4, 0] = 0.999  # element 4: not yet
    state.history[:, HIST_DAMAGE] = D.ravel()
    assert problem.delete_failed(state).tolist() == deleted
    assert (~disc.active).nonzero()[0].tolist() == deleted
    # deletion off: nothing happens
    off, _ = bar(1, deletion=False)
    assert len(off.delete_failed(state)) == 0 and off.disc.active.all()


def test_damage_is_read_at_j2_points_only():
    """History column HIST_DAMAGE is the damage D of the J2 law only (the mortar law of 003 keeps a
    component of its damage tensor there): with that column set to 1 everywhere, the J2 elements
    count as failed and carry no stress, the mortar elements do not; a table without a J2 law
    refuses deletion."""
    from fem_reference.observe import failed_elements
    from workbench.materials import MORTAR_003

    disc = Discretisation(box((0, 0, 0), (2 * W, W, W), (2, 1, 1)), order=1)
    mat_id = np.array([0, 1], np.int64)  # element 0 J2, element 1 mortar
    problem = Problem(disc, MaterialTable((TABLE1_STEEL, MORTAR_003)), None, np.zeros(0),
                      lambda lam: np.zeros(disc.N), mat_id=mat_id, deletion="any")
    state = problem.initial_state()
    state.history[:, HIST_DAMAGE] = 1.0
    assert np.array_equal(problem.live_points(state).reshape(2, -1).all(axis=1), [False, True])
    assert np.array_equal(failed_elements(problem, state), [True, False])
    assert np.array_equal(problem.delete_failed(state), [0])
    with pytest.raises(ValueError, match="deletion"):
        Problem(disc, MaterialTable((MORTAR_003,)), None, np.zeros(0),
                lambda lam: np.zeros(disc.N), deletion="any")


def test_a_body_that_fails_everywhere_carries_nothing_and_does_not_crash():
    """The SS curve's block with damage (ε_L = 0.05) fails at every point at once under its
    homogeneous stretch: the FEM's path goes on (status ok, not 'error: cannot reshape …'), the
    force is zero from the first load value past failure, and until then it is the damage-free
    block's — failure where the damage-free block's plastic strain passes ε_L."""
    from fem_reference import solve_model
    from workbench.scenes import SSCurve

    free = solve_model(SSCurve(), 2)
    out = solve_model(SSCurve(eps_L=0.05), 2)
    assert all(str(s).startswith("ok") for s in np.atleast_1d(out["status"])), out["status"]
    k = int(np.argmax(np.asarray(free["eps_p"]) >= 0.05))  # the first value past ε_L
    assert 0 < k < len(free["eps_p"]) - 1
    np.testing.assert_allclose(out["reaction"][:k], free["reaction"][:k], rtol=1e-9)
    np.testing.assert_array_equal(out["reaction"][k:], 0.0)
