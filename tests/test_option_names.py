"""Two small mismatches of issue 41: a scene method named ``material`` and sph's viscous work."""
import dataclasses

from workbench.materials import Material
from workbench.results import provenance
from workbench.scenes.crack_band import MortarBar


@dataclasses.dataclass(frozen=True)
class WithMethod(MortarBar):
    def material(self, dx):  # a method of that name, as a user's scene may have
        return self.mortar(dx)


@dataclasses.dataclass(frozen=True)
class WithMaterial(MortarBar):
    @property
    def material(self):
        return Material.svk(E=2e11, nu=0.3, rho=7850.0)


def test_a_scene_method_named_material_does_not_break_the_provenance():
    """The result writer's provenance describes a scene's ``material`` only when it is a Material
    (it called ``describe`` on a bound method and crashed after the runs)."""
    attrs = provenance("study", WithMethod())
    assert attrs["scene"] == "mortar_bar" and not any(k.startswith("material") for k in attrs)
    attrs = provenance("study", WithMaterial())
    assert attrs["material_law"] == "svk" and attrs["material_E"] == 2e11


def test_sph_reports_its_viscous_work_under_the_option_name():
    """sph's option ``viscous_work=True`` is reported as ``viscous_work`` (not
    ``viscous_dissipation``), beside ``plastic_work``."""
    from sph.classic import Classic
    from sph.particles import discretise

    sc = MortarBar()
    ps = discretise(sc.model(sc.B / 4), 4)
    out = Classic(ps, stress="hyperelastic", viscous_work=True).dissipated()
    assert "viscous_work" in out and "viscous_dissipation" not in out
    assert {"plastic_work", "released_energy"} <= set(out)
