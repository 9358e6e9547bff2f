"""Material: compressible neo-Hookean solid, plane strain or plane stress.

Energy density, first Piola-Kirchhoff stress and tangent at the quadrature points
(:func:`_neo_hookean`), the Lame parameters, the plane-stress out-of-plane stretch and the
logarithmic strain measure of the reported peak strain.
"""

from __future__ import annotations

import numpy as np

_PLANES = ("strain", "stress")


def _check_plane(plane: str) -> str:
    if plane not in _PLANES:
        raise ValueError(f"plane must be one of {list(_PLANES)}, got {plane!r}")
    return plane


def _lame(youngs_modulus_pa: float, poisson_ratio: float) -> tuple[float, float]:
    mu = youngs_modulus_pa / (2 * (1 + poisson_ratio))
    lam = youngs_modulus_pa * poisson_ratio / ((1 + poisson_ratio) * (1 - 2 * poisson_ratio))
    return mu, lam


def _out_of_plane_log_stretch(ln_j2: np.ndarray, mu: float, lam: float) -> np.ndarray:
    """Solve ``mu (l3^2 - 1) + lam ln(J2 l3) = 0`` for ``a = ln l3`` (plane stress)."""
    a = -lam / (lam + 2 * mu) * ln_j2  # small-strain guess
    for _ in range(50):
        em = np.expm1(2 * a)
        f = mu * em + lam * (ln_j2 + a)
        da = -f / (2 * mu * (1 + em) + lam)
        a = a + da
        if np.max(np.abs(da), initial=0.0) < 1e-14:
            break
    return a


def _neo_hookean(
    hmat: np.ndarray,
    mu: float,
    lam: float,
    plane: str,
    stress: bool,
    tangent: bool | None = None,
) -> tuple[np.ndarray, np.ndarray | None, np.ndarray | None, bool]:
    """Energy density, first Piola-Kirchhoff stress and tangent at quadrature points.

    ``W = mu/2 (I1 - 3) - mu ln J + lam/2 (ln J)^2`` with ``I1 = tr(F^T F) + lambda_3^2`` and
    ``J = det(F) lambda_3`` (``lambda_3 = 1`` in plane strain, from ``S_33 = 0`` in plane stress).
    The energy is evaluated from the displacement gradient ``H = F - I`` in a form free of
    first-order cancellations (``W = mu/2 H:H - mu det H + mu (z - log1p z) + ...`` with
    ``z = tr H + det H``) so that it stays accurate to round-off at tiny strains, which the line
    search relies on.

    Parameters
    ----------
    hmat
        In-plane displacement gradients ``H = F - I``, shape ``(2, 2, ...)``.
    mu, lam
        Lame parameters [Pa].
    plane
        ``"strain"`` or ``"stress"``.
    stress
        Whether to compute the stress ``P`` (shape ``(2, 2, ...)``).
    tangent
        Whether to compute the tangent ``dP/dF`` (shape ``(2, 2, 2, 2, ...)``); defaults to
        ``stress``.

    Returns
    -------
    w, p, a, ok
        Energy density [J/m^3], stress, tangent (``None`` when not requested) and ``ok`` = all
        ``det F > 0``.
    """
    h11, h12, h21, h22 = hmat[0, 0], hmat[0, 1], hmat[1, 0], hmat[1, 1]
    det_h = h11 * h22 - h12 * h21
    z = h11 + h22 + det_h  # det F - 1
    if not np.all(z > -1.0):
        return np.full(z.shape, np.inf), None, None, False
    ln_j2 = np.log1p(z)
    hh = h11**2 + h12**2 + h21**2 + h22**2
    # mu/2 (2 tr H + H:H) - mu ln J2 = mu/2 H:H - mu det H + mu (z - log1p z)
    w = 0.5 * mu * hh - mu * det_h + mu * (z - ln_j2)
    if plane == "stress":
        a3 = _out_of_plane_log_stretch(ln_j2, mu, lam)
        em = np.expm1(2 * a3)  # lambda_3^2 - 1
        ln_j = ln_j2 + a3
        w = w + mu * (0.5 * em - a3)
        lam_eff = lam - lam**2 / (2 * mu * (1 + em) + lam)
    else:
        ln_j = ln_j2
        lam_eff = lam
    w = w + 0.5 * lam * ln_j**2
    if not stress:
        return w, None, None, True
    j2 = 1.0 + z
    f11, f12, f21, f22 = 1.0 + h11, h12, h21, 1.0 + h22
    finv = np.array([[f22, -f12], [-f21, f11]]) / j2  # F^-1
    finv_t = np.swapaxes(finv, 0, 1)  # F^-T
    coef = lam * ln_j - mu
    p = mu * np.array([[f11, f12], [f21, f22]]) + coef * finv_t
    if tangent is False:
        return w, p, None, True
    eye = np.eye(2)
    a = (
        mu * np.einsum("ik,jl->ijkl", eye, eye).reshape((2, 2, 2, 2) + (1,) * (hmat.ndim - 2))
        + lam_eff * np.einsum("ij...,kl...->ijkl...", finv_t, finv_t)
        - coef * np.einsum("li...,jk...->ijkl...", finv, finv)
    )
    return w, p, a, True


def _cauchy_green_eigenvalues(fmat: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Eigenvalues ``(largest, smallest)`` of the in-plane ``C = F^T F``: the squared
    principal stretches."""
    c11 = fmat[0, 0] ** 2 + fmat[1, 0] ** 2
    c22 = fmat[0, 1] ** 2 + fmat[1, 1] ** 2
    c12 = fmat[0, 0] * fmat[0, 1] + fmat[1, 0] * fmat[1, 1]
    mean = 0.5 * (c11 + c22)
    rad = np.sqrt(0.25 * (c11 - c22) ** 2 + c12**2)
    return mean + rad, mean - rad


def _stretch_strain_magnitude(fmat: np.ndarray) -> np.ndarray:
    """Largest in-plane principal engineering strain magnitude ``max |lambda_i - 1|``."""
    hi, lo = _cauchy_green_eigenvalues(fmat)
    return np.maximum(np.abs(np.sqrt(hi) - 1.0), np.abs(np.sqrt(np.maximum(lo, 0.0)) - 1.0))


def _log_strain_magnitude(fmat: np.ndarray) -> np.ndarray:
    """Largest in-plane principal logarithmic (Hencky) strain magnitude ``max |ln lambda_i|``."""
    hi, lo = _cauchy_green_eigenvalues(fmat)
    lo = np.maximum(lo, 1e-300)
    return np.maximum(np.abs(0.5 * np.log(hi)), np.abs(0.5 * np.log(lo)))
