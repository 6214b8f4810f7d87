"""Why the RC beam's damage spreads (issue 35, item 1): short coarse runs that switch one suspect
off at a time, and what each measures of the mortar's damage; the 1-D closed form of the impact
wave against the mortar's tensile strength; the mortar law's released energy on a crack that
slides as it opens against its closed form (:func:`tension_shear_reference`). The measured table and its reading are in
``notes.md`` ("Why the damage spreads"); ``python -m studies.rc_beam.diagnose`` reruns it.

The measures (:func:`damage_measures`, mortar particles only, by volume):

* ``damaged`` — the fraction with the damage value D > 0.5 (issue 35's measure). With 003's long
  linear release (ε_0/ε_cr = 126 at 5 mm, 50 at 12.5 mm) D = 1 − φ passes 0.5 at κ ≈ 4 ε_cr, where
  the point still carries (ε_0 − κ)/(ε_0 − ε_cr) ≈ 0.94 f_t (:func:`stress_left`): D > 0.5 says a
  point has passed its peak, not that it has softened;
* ``softened`` — the fraction that has lost half its strength (κ ≥ ½(ε_0 + ε_cr), σ ≤ ½ f_t on
  the release line: D ≥ :func:`half_strength_damage`);
* ``released`` — fully released (a crack axis with φ = 0, the study's cracked particles);
* ``first_damage`` — the first record with a damaged point, and the P-wave's travel c_p t then;
* a map: the damaged fraction of each lattice column along the span (x) and of each layer (z).
"""
from __future__ import annotations

import dataclasses
import math

import numpy as np

from .ladders import OPTIONS
from .scene import RCBeam

T_DIAG = 5e-4
"""The diagnostic runs' length, s: issue 35's 0.5 ms, where 68 % (csph) / 37 % (sph) of the
mortar already has D > 0.5."""
N_OUT = 50
"""Records over a diagnostic run (every 10 µs: the first damage's time to 10 µs, 2.5 cm of the
mortar's P-wave)."""
SUSPECTS = {
    "baseline": ({}, {}),
    "soft_contact": (dict(contact_stiffness=0.05), {}),
    "no_viscosity": ({}, dict(sph=dict(alpha=0.0, beta=0.0))),
    "release_unscaled": (dict(scale_release=False), {}),
    "slow_impact": (dict(velocity=0.14), {}),
    "as_printed": (dict(shear_retention=0.0), {}),
    "shear_kept": (dict(phi_min=0.999, shear_retention=0.0), {}),
    "retention_0.2": (dict(shear_retention=0.2), {}),
    "no_rebar": (dict(rebar=False), {}),
    "slow_bend": (dict(velocity=0.14, mass=1e4), {}),
    "slow_bend_plain": (dict(velocity=0.14, mass=1e4, rebar=False), {}),
    "consistent": (dict(dt_reference="spectrum", dt_factor=0.9),
                   dict(csph=dict(integration="consistent"))),
}
"""Suspect → (scene changes, solver options by method): ``soft_contact`` the penalty k = 0.05 E_s
(10 GPa, the mortar's own stiffness; the windowed impact force is converged in k from 0.25 E_s
on, ``notes.md``); ``no_viscosity`` classic SPH without its Monaghan viscosity (csph has none;
its hourglass control, which now builds with the symmetry planes' mirror images, was not tried as
a suspect); ``release_unscaled`` the release strain held
at the paper's 5 mm value (17 000 µ at every spacing); ``slow_impact`` a tenth of B's speed (the
wave's stress ρ c v a tenth, below f_t: what cracks then is bending, not the wave; run ten times
as long and compared at the same mid-span displacement); ``consistent`` csph with its
integration-consistent correction instead of nodal integration (no zero-energy modes; at 0.9 of
its critical step, ``dt_reference='spectrum'``); ``as_printed`` 003's eq. 7 as printed (shear
rates φ̃_iφ̃_j falling with the opening; the baseline before the shear retention, the mortar's
default since issue 35's cure); ``shear_kept`` that law with the shear floor φ_min of eq. 6 at
0.999 (a crack keeps its shear stiffness: eq. 7's shear rates release nothing);
``retention_0.2`` the constant shear retention at 0.2 (the default 0.05: the range of fixed
smeared-crack models is 0.05–0.2); ``no_rebar`` a
plain mortar beam (does the mortar alone localise, without a perfectly bonded bar beside it?);
``slow_bend`` / ``slow_bend_plain`` a slow three-point bend of the reinforced / plain beam: a
weight a hundred times heavier at a tenth of the speed (the same 98 J; the wave's stress a
tenth, and the weight's period on the beam ten times longer, so the beam bends nearly
statically: run it about six times as long, 30 ms, for the same mid-span displacement)."""


def p_wave_speed(E: float, nu: float, rho: float) -> float:
    """The dilatational wave speed c_p = √((λ + 2μ)/ρ), m/s."""
    return math.sqrt(E * (1 - nu) / ((1 + nu) * (1 - 2 * nu) * rho))


def impact_stress(v: float, rho_1: float, c_1: float, rho_2: float, c_2: float) -> float:
    """The stress (compressive, Pa, as a positive number) of the plane wave when a body of
    impedance Z_1 = ρ_1 c_1 strikes one of Z_2 at speed v: σ = Z_1 Z_2 v/(Z_1 + Z_2) (continuity of
    velocity and traction at the interface; σ = ρ c v/2 for equal bodies, → Z_2 v for a rigid
    striker). At a free face it reflects with its sign reversed: a tension of the same size."""
    z1, z2 = rho_1 * c_1, rho_2 * c_2
    return z1 * z2 * v / (z1 + z2)


def stress_left(kappa: float, eps_cr: float, eps_0: float) -> float:
    """The uniaxial stress over f_t that a point whose largest normal strain reached κ carries on
    the linear release (Fig. 8): 1 up to ε_cr, (ε_0 − κ)/(ε_0 − ε_cr) on to ε_0, 0 beyond."""
    if kappa <= eps_cr:
        return 1.0
    return max(0.0, (eps_0 - kappa) / (eps_0 - eps_cr))


def half_strength_damage(eps_cr: float, eps_0: float) -> float:
    """The damage D = 1 − φ at which a point has lost half its strength, κ = ½(ε_0 + ε_cr)."""
    from workbench.materials.mortar import reduction_factor

    return 1.0 - float(reduction_factor(0.5 * (eps_0 + eps_cr), eps_cr, eps_0))


def damage_measures(D: np.ndarray, released: np.ndarray, V: np.ndarray, eps_cr: float,
                    eps_0: float) -> dict:
    """The volume fractions of the mortar (module docstring) from the damage value D (n,), the
    fully released flag (n,) and the volumes V (n,): ``damaged`` (D > 0.5), ``softened`` (D ≥
    :func:`half_strength_damage`), ``released``, ``cracking`` (any damage, D > 0)."""
    D, V = np.asarray(D, float), np.asarray(V, float)
    tot = V.sum()
    frac = lambda sel: float(V[sel].sum() / tot)  # noqa: E731
    return dict(damaged=frac(D > 0.5), softened=frac(D >= half_strength_damage(eps_cr, eps_0)),
                released=frac(np.asarray(released) > 0), cracking=frac(D > 0.0))


def damage_map(X: np.ndarray, D: np.ndarray, dx: float, axis: int) -> tuple:
    """(positions, damaged fraction D > 0.5) of the mortar in each lattice slab along ``axis``
    (0: x along the span, 2: z up)."""
    k = np.rint(X[:, axis] / dx).astype(int)
    ks = np.unique(k)
    return ks * dx, np.array([float(np.mean(D[k == i] > 0.5)) for i in ks])


def energy_per_softened_area(released: float, V_mortar: float, softened: float, dx: float,
                             G_F: float) -> float:
    """The released energy ``released`` (J) over G_F (J/m²) times the crack area the softened
    mortar would make as bands :data:`.derive.CRACK_BAND_WIDTH` spacings wide,
    softened · V_mortar/(2Δx) (m²): 2 where every softened particle lies in a clean band that has
    released its G_F (as the crack-band bar), less where softened mortar has not yet released all
    of it. Beside :func:`.derive.crack_band_energy` (the fully released volume as the area), it
    tells an energy excess per crack (the measure above 2 here too) from a diffuse softening
    (near or below 2 here, far above with the fully released volume). NaN without softening."""
    from .derive import CRACK_BAND_WIDTH

    A = softened * V_mortar / (CRACK_BAND_WIDTH * dx)
    return released / (A * G_F) if A > 0 else math.nan


def diagnose(method: str, scene: RCBeam, resolution: int, **options) -> dict:
    """One diagnostic run: ``method`` on ``scene`` (its t_end and n_out as given) at
    ``resolution`` with the study's options (:data:`.ladders.OPTIONS`) updated by ``options``.
    Returns the measures at every record (``time`` and each of :func:`damage_measures`), the
    first damage's time and the P-wave's travel then (``first_damage``, ``wave_travel``, m), the
    final maps (``map_x``, ``map_z``), the first damage in the bottom face's layer
    (``first_bottom``) beside the P-wave's arrival there from the top, H/c_p (``bottom_arrival``),
    the energy released per crack area over G_F (``per_area``, :func:`.derive.crack_band_energy`)
    and the fully released particles' share of it (``share_full``), the same per the softened
    mortar's band area (``per_softened_area``, :func:`energy_per_softened_area`), the released
    energy (J, full
    beam), the mid-span displacement (``midspan`` at the end, ``w`` at the records), the run's status
    and its result dict (``run``) with the mortar's mask (``mortar``)."""
    from sph.driver import model_at, solve
    from sph.particles import discretise
    from workbench.materials.mortar import H_DAMAGE, H_RELEASED

    model, dx = model_at(scene, resolution)
    ps = discretise(model, resolution)
    mortar = ps.region == ps.region_names.index("mortar")
    eps_cr, eps_0 = scene.f_t / scene.E_m, scene.release_strain(dx)
    rec = dict(time=[], damaged=[], softened=[], released=[], cracking=[], bottom=[])
    bottom = ps.X[mortar][:, 2] < 0.5 * dx  # the bottom face's layer
    last = {}

    def on_record(body, run, t):
        h = run.material_state()["history"][mortar]
        rec["time"].append(float(t))
        for k, v in damage_measures(h[:, H_DAMAGE], h[:, H_RELEASED], ps.V[mortar], eps_cr,
                                    eps_0).items():
            rec[k].append(v)
        rec["bottom"].append(float(np.mean(h[bottom, H_DAMAGE] > 0.0)))
        last["D"] = h[:, H_DAMAGE].copy()

    out = solve(method, scene, resolution, on_record=on_record, **{**OPTIONS[method], **options})
    from .derive import crack_band_energy

    band = crack_band_energy(scene, resolution, out)
    from workbench.materials.mortar import fracture_energy

    W = scene.copies * float(out["released_energy"][-1])
    per_softened = energy_per_softened_area(W, scene.copies * float(ps.V[mortar].sum()),
                                            rec["softened"][-1] if rec["softened"] else 0.0, dx,
                                            fracture_energy(scene.f_t, eps_0, dx))
    res = {k: np.asarray(v) for k, v in rec.items()}
    t = res["time"]
    hit = np.flatnonzero(res["cracking"] > 0)
    first = float(t[hit[0]]) if hit.size else math.nan
    hit = np.flatnonzero(res["bottom"] > 0)
    first_bottom = float(t[hit[0]]) if hit.size else math.nan
    cp = p_wave_speed(scene.E_m, scene.nu_m, scene.rho_m)
    X = ps.X[mortar]
    res.update(first_damage=first, wave_travel=cp * first, c_p=cp, dx=dx,
               first_bottom=first_bottom, bottom_arrival=scene.H / cp,
               map_x=damage_map(X, last["D"], dx, 0), map_z=damage_map(X, last["D"], dx, 2),
               midspan=float(out["midspan_displacement"][-1]),
               w=np.asarray(out["midspan_displacement"], float), run=out,
               per_area=band["released_per_crack_area_over_GF"],
               share_full=band["released_share_full"],
               per_softened_area=per_softened,
               released_energy=W, mortar=mortar, status=out.get("status", ""),
               wall=float(out["total_time"]))
    return res


def tension_shear_path(mat, g: float, n: int = 4000) -> list:
    """Green–Lagrange strains of a crack opening under shear: E_xx = e from 0 to 1.2 ε_0 in n
    steps, lateral normal strains held at zero (uniaxial strain), and a shear E_xy = g (e − 2ε_cr)
    from twice the cracking strain on (a crack, its frame set along x at ε_cr, that slides as it
    opens: what the beam's shear span does)."""
    eps_cr = mat.f_t / mat.E
    out = []
    for e in np.linspace(0.0, 1.2 * mat.eps_release, n):
        E = np.diag([e, 0.0, 0.0])
        E[0, 1] = E[1, 0] = g * max(0.0, e - 2.0 * eps_cr)
        out.append(E)
    return out


def released_on_path(mat, path) -> float:
    """The mortar law's released energy (history column W_r) at the end of a path of
    Green–Lagrange strains (the symmetric stretch U with ½(U² − I) = E at each step), J/m³."""
    from workbench.materials import evaluate
    from workbench.materials.mortar import H_W_RELEASED

    h = mat.initial_history(1)[0]
    for E in path:
        w, Vv = np.linalg.eigh(np.eye(3) + 2.0 * E)
        h = evaluate(mat, Vv @ np.diag(np.sqrt(w)) @ Vv.T, h)["history"]
    return float(h[H_W_RELEASED])


def tension_shear_reference(mat, g: float) -> float:
    """The energy (J/m³) eq. 6–8 release on :func:`tension_shear_path`, in closed form: the normal
    part (λ + 2μ)/E · g_F (uniaxial strain: σ = φ²(λ + 2μ)e, φ²Ee on the release line of Fig. 8),
    plus, with eq. 7 as printed (``shear_retention`` 0), the shear part ∫ 2μ E_xy² (−dα), the
    shear factor α = max(φ, φ_min) of eq. 7 falling as the crack opens (quadrature of the
    closed-form φ(e), :func:`reduction_factor`'s formula); with a constant shear retention the
    shear rate does not change once the crack is set (at ε_cr, before the shear starts at 2ε_cr),
    so there is no shear part."""
    from scipy.integrate import quad

    E, nu, ft, e0, pmin = mat.E, mat.nu, mat.f_t, mat.eps_release, mat.phi_min
    lam, mu = E * nu / ((1 + nu) * (1 - 2 * nu)), E / (2 * (1 + nu))
    ecr = ft / E
    gF = 0.5 * ft * e0
    if mat.shear_retention > 0:
        return (lam + 2 * mu) / E * gF

    def dphi(e):  # dφ/de of φ = √(ε_cr(ε_0 − e)/(e(ε_0 − ε_cr))) on (ε_cr, ε_0)
        phi = math.sqrt(ecr * (e0 - e) / (e * (e0 - ecr)))
        return -0.5 / phi * ecr * e0 / ((e0 - ecr) * e * e)

    # φ reaches the floor φ_min at e_f: ε_cr(ε_0 − e) = φ_min² e(ε_0 − ε_cr)
    e_f = ecr * e0 / (ecr + pmin * pmin * (e0 - ecr))
    shear = quad(lambda e: 2 * mu * (g * max(0.0, e - 2 * ecr)) ** 2 * -dphi(e), ecr, e_f,
                 points=[2 * ecr], limit=200, epsabs=0.0, epsrel=1e-10)[0]
    return (lam + 2 * mu) / E * gF + shear


def suspect_scene(scene: RCBeam, suspect: str) -> RCBeam:
    """The scene of one suspect (:data:`SUSPECTS`), B over :data:`T_DIAG` by default."""
    return dataclasses.replace(scene, **SUSPECTS[suspect][0])


def table(resolution: int = 5, suspects=None, methods=("csph", "sph"), t_end: float = T_DIAG):
    """Suspect → method → :func:`diagnose` on specimen B over ``t_end`` (give the slow impact ten
    times as long, ``--t-end``: the same mid-span displacement needs about ten times the time)."""
    base = RCBeam(specimen="B", name="rc_beam_B_diag", t_end=t_end, n_out=N_OUT)
    out = {}
    for s in suspects or SUSPECTS:
        sc = suspect_scene(base, s)
        for m in methods:
            if s in ("no_viscosity", "consistent") and m not in SUSPECTS[s][1]:
                continue
            opts = SUSPECTS[s][1].get(m, {})
            out.setdefault(s, {})[m] = diagnose(m, sc, resolution, **opts)
    return out


def main(argv=None) -> None:  # pragma: no cover - the measurement behind notes.md
    import argparse

    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--resolution", type=int, default=5)
    p.add_argument("--suspect", action="append")
    p.add_argument("--method", action="append")
    p.add_argument("--t-end", type=float, default=T_DIAG)
    a = p.parse_args(argv)
    res = table(a.resolution, a.suspect, tuple(a.method or ("csph", "sph")), a.t_end)
    for s, by in res.items():
        for m, r in by.items():
            print(f"{s:17s} {m:5s} damaged {r['damaged'][-1]:.3f} softened {r['softened'][-1]:.3f} "
                  f"released {r['released'][-1]:.3f} first {r['first_damage'] * 1e6:6.1f} us "
                  f"(c_p t {r['wave_travel'] * 1e3:6.1f} mm) bottom {r['first_bottom'] * 1e6:6.1f} us "
                  f"(H/c_p {r['bottom_arrival'] * 1e6:.1f} us) w {r['midspan'] * 1e3:.3f} mm "
                  f"wall {r['wall']:.0f} s {r['status']}")
            from .derive import history_maximum

            wmax, tmax, cut = history_maximum(r["run"]["time"], r["w"])
            print(f"   released {r['released_energy']:.3g} J, per crack area {r['per_area']:.3g} G_F, "
                  f"fully released share {r['share_full']:.3g}, per softened area "
                  f"{r['per_softened_area']:.3g} G_F, largest w {wmax * 1e3:.3f} mm at "
                  f"{tmax * 1e3:.2f} ms{' (truncated: a lower bound)' if cut else ''}")
            k = [int(i) for i in np.searchsorted(r["time"], np.linspace(0.1, 1, 10) * a.t_end)
                 if i < len(r["time"])]
            print("   t us / w mm / damaged / softened / released:", " ".join(
                f"{r['time'][i] * 1e6:.0f}/{r['w'][i] * 1e3:.2f}/{r['damaged'][i]:.2f}/"
                f"{r['softened'][i]:.2f}/{r['released'][i]:.2f}" for i in k))
            print("   x map:", " ".join(f"{v:.2f}" for v in r["map_x"][1]))
            print("   z map:", " ".join(f"{v:.2f}" for v in r["map_z"][1]))


if __name__ == "__main__":  # pragma: no cover
    main()
