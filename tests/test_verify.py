"""`workbench verify --quick`, the main job, end to end: exit status, report, datasets per the
contract, accuracy-versus-cost figures."""
import pytest
import xarray as xr

import studies


@pytest.fixture(scope="module")
def verified(quick_verify):
    return quick_verify


def test_verify_quick_passes_its_gates(verified):
    """Exit status 0, no failed gate, and every gate the studies declare evaluated: each study's
    N_GATES of --quick plus its count gate (a gate that vanished — a missing or NaN run left out —
    would pass 'no FAIL' and fail this)."""
    out, proc = verified
    assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-3000:]
    md = (out / "report.md").read_text()
    assert "FAIL" not in md
    n = sum(studies.get(s).N_GATES[True] + 1 for s in studies.HEADLINE)
    assert f"{n}/{n} gates passed" in md, md[:400]
    for s in studies.HEADLINE:
        declared = studies.get(s).N_GATES[True]
        assert f"PASS  {s}: gates evaluated against the {declared} the study declares" in md, s
    assert (out / "report.html").read_text().startswith("<!doctype html>")


@pytest.mark.parametrize("study", studies.HEADLINE)
def test_datasets_follow_the_contract(verified, study):
    out, _ = verified
    with xr.open_dataset(out / f"{study}.nc") as ds:
        assert "solver" in ds.coords
        if study == "stability":
            # stability.nc: every particle method over the four scenes of the contract
            assert set(ds.solver.values) >= {"csph", "hpm", "sph"}
            assert set(ds.scene.values) >= {"ring", "slab", "rings", "plate"}
            assert "criterion" in ds.stable.attrs or "criterion" in ds.attrs
        elif study == "rc_beam":
            # rc_beam.nc: classic SPH and CSPH on the impacts, the FEM on the modal check
            assert set(ds.solver.values) >= {"csph", "sph"}
            assert "fem" in ds.modal_solver.values
        elif study != "microcantilever":  # no closed form: csph against the FEM and physics
            assert "analytic" in ds.solver.values
        for key in ("study", "workbench_version", "git_revision", "date", "cpu_count"):
            assert key in ds.attrs
        for name, var in ds.data_vars.items():
            assert "units" in var.attrs, name
        required = {"ss_curve": ("stress", "nominal_stress", "wall_time"),
                    "cantilever": ("tip_deflection", "tip_horizontal", "wall_time"),
                    "plate": ("period", "amplitude", "tip_displacement", "wall_time",
                              "period_nondim", "amplitude_nondim"),
                    "stability": ("stable", "max_stable_dt_factor", "energy_drift"),
                    "rc_beam": ("midspan_displacement", "impact_force", "support_reaction",
                                "kinetic_energy", "released_energy", "energy_error",
                                "max_displacement", "wall_time"),
                    "microcantilever": ("load", "deflection", "failed_fraction", "released_energy",
                                        "fracture_energy", "fem_elastic_slope", "wall_time")}[study]
        for name in required:
            assert name in ds, name
    figure = "stability_max_dt.png" if study == "stability" else f"{study}_accuracy_vs_cost.png"
    assert (out / figure).stat().st_size > 5000


def test_verify_writes_the_representative_fields(verified):
    """One representative run (csph plate, H/dx = 10) writes its ParaView series; the report shows
    a snapshot where this machine renders, else a note with the reason."""
    from workbench.fields import can_render, series_frames

    out, _ = verified
    assert len(series_frames(out / "fields" / "plate_csph_H10.pvd")) >= 10
    md = (out / "report.md").read_text()
    assert "fields/plate_csph_H10.pvd" in md
    ok, why = can_render()
    if ok:
        assert (out / "plate_fields_plate_csph_H10.png").stat().st_size > 5000
    else:
        assert "No snapshot in this report" in md
