"""The crack of a :class:`workbench.scenes.crack_band.MortarBar` run: the energy released per
crack area against the law's fracture energy (issue 12 gate 6, the crack-band regularisation of
003 eq. 5; tests/test_crack_band.py)."""
from __future__ import annotations

import math

import numpy as np

from workbench.scenes.crack_band import MortarBar

SEPARATION = 0.05
"""The bar counts as separated from the first record after the peak at which the force is at most
this fraction of the peak: the end of the softening branch. (Past it the force does not vanish
exactly: a fixed reference neighbourhood keeps kernel pairs across the crack, and a residual
1–3 % of the peak creeps on, releasing a few per cent of G_F more per ε_0 Δx of opening.)"""


def crack_band(scene: MortarBar, resolution: int, out: dict) -> dict:
    """The crack of a :class:`MortarBar` run, from the driver's output ``out`` (histories of
    ``released_energy`` and ``force``, the final ``history`` with reference positions ``X``).

    Returns ``G_F`` (J/m², :meth:`MortarBar.fracture_energy` at the run's spacing: eq. 5's energy
    per crack area of a band one particle wide); ``released_per_area`` (J/m², the released energy
    at separation — :data:`SEPARATION` — over the crack area A (:attr:`MortarBar.area`); NaN if the bar
    did not separate) and ``ratio`` (it over G_F: the particle layers the crack consumed);
    ``final_ratio`` (the same at the end of the run); ``released_layers`` (the fully released
    mortar particles' volume over A Δx, at the end); ``full`` and ``partial`` (the history's
    released energy Σ V W_r of the fully released particles and of the others over A G_F, at the
    end; V the lattice volumes of :func:`sph.particles.discretise`); ``band`` (the lattice
    columns with a fully released particle, counted from the weak section's first);
    ``band_min_damage`` (the smallest damage — largest damage eigenvalue — over the mortar
    particles of those columns); ``separation_opening`` (the opening at separation over
    ε_0(Δx) Δx, past the elastic stretch);
    ``peak_force`` (the largest force over f_t A); ``residual_force`` (the last record's |force|
    over the largest); ``spacing`` (m)."""
    from sph.diagnostics import work_columns
    from sph.particles import discretise
    from workbench.materials.failure import damage, failed

    dx = scene.B / resolution
    ps = discretise(scene.model(dx), resolution)
    h = np.asarray(out["history"], float)
    X = np.asarray(out["X"], float)
    names = list(out["region_names"])
    mortar = np.isin(np.asarray(out["region"]), [names.index(n) for n in ("weak", "bar")])
    released = mortar & failed(ps.table, ps.mat_id, h)  # fully released (any law)
    d_all = damage(ps.table, ps.mat_id, h)
    wr = work_columns(ps.table)[1][ps.mat_id]
    W_r = np.where(wr >= 0, h[np.arange(len(wr)), np.maximum(wr, 0)], 0.0)
    GF = scene.fracture_energy(dx)
    W = np.asarray(out["released_energy"], float)
    F = np.abs(np.asarray(out["force"], float))
    u0 = scene.release_strain(dx) * dx
    opening = 2.0 * np.asarray(out["opening"], float) - scene.f_t / scene.E * scene.L
    k = int(np.argmax(F))
    sep = np.flatnonzero((np.arange(len(F)) > k) & (F <= SEPARATION * F[k]))
    W_sep = float(W[sep[0]]) if sep.size else math.nan
    w = np.where(mortar, W_r, 0.0) * ps.V
    column = np.round((X[:, 0] - scene.weak_section(dx)) / dx).astype(int)
    band = sorted(set(column[released].tolist()))
    in_band = mortar & np.isin(column, band)
    A = scene.area
    return dict(G_F=GF, released_per_area=W_sep / A, ratio=W_sep / (A * GF),
                final_ratio=float(W[-1]) / (A * GF),
                released_layers=float(ps.V[released].sum()) / (A * dx),
                full=float(w[released].sum()) / (A * GF),
                partial=float(w[~released].sum()) / (A * GF),
                band=band,
                band_min_damage=float(d_all[in_band].min()) if band else math.nan,
                separation_opening=float(opening[sep[0]] / u0) if sep.size else math.nan,
                peak_force=float(F[k]) / (scene.f_t * A),
                residual_force=float(F[-1] / F[k]) if F[k] > 0 else math.nan,
                spacing=dx)
