"""One notion of a failed particle for every law (workbench.materials.failure, issue 41 item 3) and
particles that start failed (Region(failed=True), from item 2): the failure observables, the
connectivity and separation check, csph's crack rule and the field output read it with the mortar
and the brittle law as with J2."""
import dataclasses

import numpy as np
import pytest

from workbench.materials import Material, MaterialTable, evaluate
from workbench.materials import failure
from workbench.scenes import model as M
from workbench.scenes.crack_band import MortarBar
from workbench.scenes.params import SceneError

J2 = Material.j2_linear(E=200e9, nu=0.3, sigma_y0=400e6, H=1e9, eps_L=0.1)
MORTAR = Material.mortar(E=11.9e9, nu=0.2, f_t=1.61e6, f_c=16.1e6, eps_release=0.017)
BRITTLE = Material.brittle(E=200e9, nu=0.3, f_t=1e9, G_c=2e4, band=0.002)
TABLE = MaterialTable((Material.svk(1e9, 0.3), J2, MORTAR, BRITTLE))


def test_failed_and_set_failed_for_every_law():
    """Virgin points of every law are intact; set_failed makes the J2, mortar and brittle points
    failed (damage 1), and an elastic law cannot fail (one line naming the law)."""
    mat_id = np.array([0, 1, 2, 3, 1, 2, 3])
    h = TABLE.initial_history(mat_id)
    assert not failure.failed(TABLE, mat_id, h).any()
    mask = np.array([False, True, True, True, False, False, False])
    failure.set_failed(TABLE, mat_id, h, mask)
    assert failure.failed(TABLE, mat_id, h).tolist() == mask.tolist()
    assert failure.damage(TABLE, mat_id, h).tolist() == mask.astype(float).tolist()
    with pytest.raises(ValueError, match="^failed: a 'svk' material cannot fail"):
        failure.set_failed(TABLE, mat_id, h, mat_id == 0)
    # J2 without a damage limit does not fail under load, but a point set failed is failed
    j2_inf = MaterialTable((Material.j2_linear(200e9, 0.3, 400e6, 1e9),))
    assert not failure.can_fail(j2_inf) and failure.can_fail(TABLE)
    h = j2_inf.initial_history(np.zeros(2, np.int64))
    failure.set_failed(j2_inf, np.zeros(2, np.int64), h, np.array([True, False]))
    assert failure.failed(j2_inf, np.zeros(2, np.int64), h).tolist() == [True, False]


def test_a_failed_point_carries_no_tension():
    """The state set_failed leaves is the law's failed state: under uniaxial tension (Green–Lagrange
    E_xx = 1e-3) no stress, where the intact point carries E·1e-3-order stress."""
    mat_id = np.array([1, 2, 3])
    F = np.tile(np.eye(3), (3, 1, 1))
    F[:, 0, 0] = np.sqrt(1 + 2e-3)
    h = TABLE.initial_history(mat_id)
    intact = evaluate(TABLE, F, h, mat_id=mat_id)["stress"][:, 0, 0]
    failure.set_failed(TABLE, mat_id, h, np.ones(3, bool))
    broken = evaluate(TABLE, F, h, mat_id=mat_id)["stress"][:, 0, 0]
    assert np.all(np.abs(intact) > 1e5)
    assert np.abs(broken).max() <= 1e-12 * np.abs(intact).min()


def test_field_output_damage_for_the_mortar_and_the_brittle_law():
    from workbench.fields import particle_point_data

    mat_id = np.array([2, 3, 2])
    h = TABLE.initial_history(mat_id)
    failure.set_failed(TABLE, mat_id, h, np.array([True, True, False]))
    X = np.zeros((3, 2))
    out = particle_point_data(TABLE, X, X, X, F=np.tile(np.eye(3), (3, 1, 1)), history=h,
                              mat_id=mat_id)
    assert out["damage"].tolist() == [1.0, 1.0, 0.0]


@dataclasses.dataclass(frozen=True)
class Observed:
    """A MortarBar (either law) with a FailedFraction observable and the drive's separation check
    between its two ends; ``failed_middle``: the weak section starts failed."""

    bar: MortarBar
    failed_middle: bool = False
    name: str = "observed_bar"

    def model(self, spacing=None):
        mdl = self.bar.model(spacing)
        regions = tuple(dataclasses.replace(r, failed=True) if (self.failed_middle and r.name == "weak")
                        else r for r in mdl.regions)
        drive = dataclasses.replace(mdl.drive, separate=("left", "right"), after=0.0)
        return dataclasses.replace(mdl, regions=regions, drive=drive,
                                   observables=mdl.observables + (M.FailedFraction("failed"),))

    def summarise(self, out):
        return {}


@pytest.mark.parametrize("law", ["mortar", "brittle"])
def test_a_softening_crack_fails_particles_cuts_the_body_and_stops_the_run(law):
    """The bar (5 mm, csph with nodal integration and its default crack rule) pulled apart: the
    failed fraction becomes positive, the failed particles lie in the crack's columns, the
    connectivity finds the two halves apart and ``separate`` stops the run before its end."""
    from sph import driver

    sc = Observed(MortarBar(law=law))
    out = driver.solve("csph", sc, 4, integration="nodal")
    assert out["status"] == "ok"
    assert out["failed"][0] == 0.0 and out["failed"][-1] > 0.0
    failed = out["failed_particles"]
    assert failed.any()
    x0 = sc.bar.weak_section(sc.bar.B / 4)
    assert np.all(np.abs(out["X"][failed, 0] - (x0 + 0.5 * sc.bar.B / 4)) < sc.bar.B / 4)
    assert out["criterion"] == "separated" and out["time"][-1] < sc.bar.duration(sc.bar.B / 4)
    comp = out["component"]
    left, right = out["sets"]["left"], out["sets"]["right"]
    assert len(set(comp[left])) == 1 and len(set(comp[right])) == 1
    assert comp[left[0]] != comp[right[0]]


@pytest.mark.parametrize("law", ["mortar", "brittle"])
def test_initially_failed_region_starts_failed_and_cut(law):
    """Region(failed=True) across the bar: its particles are failed at t = 0 (FailedFraction, and
    the final failed_particles), csph's crack rule has cut the body from the start, so the run stops
    at the first record the check sees (the first after t = 0); classic SPH reads the same failed
    set."""
    from sph import driver

    sc = Observed(MortarBar(law=law), failed_middle=True)
    out = driver.solve("csph", sc, 4, integration="nodal")
    weak = np.asarray(out["region"]) == out["region_names"].index("weak")
    assert out["failed"][0] == pytest.approx(weak.sum() / weak.size)
    assert out["failed_particles"][weak].all() and not out["failed_particles"][~weak].any()
    assert out["criterion"] == "separated" and out["t_separated"] == out["time"][1]
    out = driver.solve("sph", dataclasses.replace(sc, bar=dataclasses.replace(sc.bar, opening=0.2)),
                       4, stress="hyperelastic")
    assert out["failed"][0] == pytest.approx(weak.sum() / weak.size)


def test_a_failed_region_needs_a_law_that_can_fail():
    sc = MortarBar()
    mdl = sc.model()
    regions = tuple(dataclasses.replace(r, failed=True) if r.name == "grip_left" else r
                    for r in mdl.regions)
    with pytest.raises(SceneError, match="^region 'grip_left': failed=True needs a material that "
                                         "can fail"):
        dataclasses.replace(mdl, regions=regions)


def test_fem_starts_the_failed_region_failed():
    """The FEM reads the same scene item: the elements of the failed region start failed at every
    point (fem_reference.observe.failed_elements), the others intact."""
    from fem_reference.model import build
    from fem_reference.observe import failed_elements

    for law in ("mortar", "brittle"):
        sc = Observed(MortarBar(law=law), failed_middle=True)
        fm = build(sc, 4, element="q4")
        weak = fm.region == fm.model.regions.index(fm.model.region("weak"))
        failed = failed_elements(fm.problem, fm.problem.initial_state())
        assert weak.any() and np.array_equal(failed, weak), law


def test_hpm_stored_energy_reads_the_history():
    """hpm's stored energy of a law with a history is Σ V ψ(F, h) at the committed history (it
    evaluated every law as virgin, reading history columns it did not have): on the brittle bar
    (ν = 0) under a uniform stretch E_xx = e, failing every brittle particle removes exactly
    Σ_brittle V ½ E e² (the grips stay elastic); hpm's gradient is exact for a linear field."""
    from sph.hpm import HPM
    from sph.particles import discretise

    sc = MortarBar(law="brittle")
    ps = discretise(sc.model(sc.B / 4), 4)
    body = HPM(ps)
    stretch = 1e-4  # F_xx = 1 + stretch, below the cracking strain f_t/E = 1.35e-4
    body.x[:, 0] = ps.X[:, 0] * (1 + stretch)
    e = stretch + 0.5 * stretch ** 2
    brittle = np.array([m.law == "brittle" for m in ps.table.materials])[ps.mat_id]
    intact = body.stored_energy()
    assert intact == pytest.approx(ps.V.sum() * 0.5 * sc.E * e * e, rel=1e-9)
    failure.set_failed(ps.table, ps.mat_id, body.st.h, brittle)
    assert intact - body.stored_energy() == pytest.approx(ps.V[brittle].sum() * 0.5 * sc.E * e * e,
                                                          rel=1e-9)
    assert set(body.dissipated()) >= {"released_energy"}
