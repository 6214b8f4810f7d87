"""Smoothing kernels W(r, h) of the particle methods, value and gradient, in 2-D and 3-D.

Both kernels have compact support of radius ``2h`` (q = r/h ∈ [0, 2]); ``h`` is chosen from the
particle spacing by the ratio ``h_ratio = h/Δx`` (a parameter of every method):

* cubic spline (M4, Monaghan & Lattanzio 1985):
  W = σ_d [1 − 3/2 q² + 3/4 q³] for q < 1, σ_d/4 (2 − q)³ for 1 ≤ q < 2,
  σ_2 = 10/(7π h²), σ_3 = 1/(π h³);
* Wendland C2 (Wendland 1995, Dehnen & Aly 2012 in the support-2h convention):
  W = σ_d (1 − q/2)⁴ (2q + 1), σ_2 = 7/(4π h²), σ_3 = 21/(16π h³).

The gradient with respect to the evaluation point x_a of W(x_a − x_b) is
``dW/dr(r) (x_a − x_b)/r``, i.e. ``∇W_b(x_a)`` in the notation of 000 eq. 4.

The jitted scalar routines take the kernel by its integer code (``KERNELS``) so that one compiled
loop serves every kernel; :func:`kernel_code` maps a name to its code.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

JIT = dict(cache=True, nogil=True, error_model="numpy")
"""numba options shared by the whole particle core (one place, as style.md asks)."""
N_CHUNKS = 64
"""Work items of the chunked parallel loops (each allocates its 3×3 scratch once)."""

KERNELS = {"cubic_spline": 0, "wendland_c2": 1}
SUPPORT = 2.0
"""Support radius in units of h (both kernels)."""


def kernel_code(name: str) -> int:
    """The integer code of a kernel name; ``ValueError`` naming the allowed values otherwise."""
    try:
        return KERNELS[name]
    except KeyError:
        raise ValueError(f"kernel: {name!r} is not one of {sorted(KERNELS)}") from None


@njit(**JIT)
def sigma(kind: int, dim: int, h: float) -> float:
    """Normalisation σ_d of the kernel ``kind`` in ``dim`` dimensions, 1/m^dim."""
    if kind == 0:
        if dim == 2:
            return 10.0 / (7.0 * math.pi * h * h)
        if dim == 3:
            return 1.0 / (math.pi * h * h * h)
        return 2.0 / (3.0 * h)
    if dim == 2:
        return 7.0 / (4.0 * math.pi * h * h)
    if dim == 3:
        return 21.0 / (16.0 * math.pi * h * h * h)
    return 5.0 / (8.0 * h)  # 1-D Wendland C2 uses (1 − q/2)^3 (1.5 q + 1); only for completeness


@njit(**JIT)
def w(r: float, h: float, kind: int, dim: int) -> float:
    """Kernel value W(r, h), 1/m^dim."""
    q = r / h
    if q >= 2.0:
        return 0.0
    s = sigma(kind, dim, h)
    if kind == 0:
        if q < 1.0:
            return s * (1.0 - 1.5 * q * q + 0.75 * q * q * q)
        t = 2.0 - q
        return s * 0.25 * t * t * t
    t = 1.0 - 0.5 * q
    if dim == 1:
        return s * t * t * t * (1.5 * q + 1.0)
    return s * t * t * t * t * (2.0 * q + 1.0)


@njit(**JIT)
def dw_dr(r: float, h: float, kind: int, dim: int) -> float:
    """Radial derivative dW/dr, 1/m^(dim+1) (zero at r = 0 and beyond 2h)."""
    q = r / h
    if q >= 2.0:
        return 0.0
    s = sigma(kind, dim, h) / h
    if kind == 0:
        if q < 1.0:
            return s * (-3.0 * q + 2.25 * q * q)
        t = 2.0 - q
        return -s * 0.75 * t * t
    t = 1.0 - 0.5 * q
    if dim == 1:
        return s * (-1.5 * t * t * (1.5 * q + 1.0) + 1.5 * t * t * t)
    return s * (-5.0 * q * t * t * t)


@njit(**JIT)
def grad_w(dx: np.ndarray, h: float, kind: int, out: np.ndarray) -> None:
    """∇W at separation ``dx = x_a − x_b`` (shape (d,)), written into ``out`` (d,), 1/m^(d+1)."""
    d = dx.shape[0]
    r2 = 0.0
    for k in range(d):
        r2 += dx[k] * dx[k]
    r = math.sqrt(r2)
    if r <= 0.0:
        for k in range(d):
            out[k] = 0.0
        return
    c = dw_dr(r, h, kind, d) / r
    for k in range(d):
        out[k] = c * dx[k]


def values(r, h: float, kernel: str = "cubic_spline", dim: int = 2) -> np.ndarray:
    """W at the distances ``r`` (array), for tests and plots."""
    k = kernel_code(kernel)
    r = np.asarray(r, dtype=np.float64)
    return np.array([w(float(x), h, k, dim) for x in r.ravel()]).reshape(r.shape)


def derivatives(r, h: float, kernel: str = "cubic_spline", dim: int = 2) -> np.ndarray:
    """dW/dr at the distances ``r`` (array)."""
    k = kernel_code(kernel)
    r = np.asarray(r, dtype=np.float64)
    return np.array([dw_dr(float(x), h, k, dim) for x in r.ravel()]).reshape(r.shape)
