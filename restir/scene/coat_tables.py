"""Host precomputation for rough dielectric coats (the `roughplastic` BSDF).

For a rough dielectric interface (GGX or Beckmann, isotropic alpha, relative IOR eta), the
directional albedos of its single-scattering reflection and transmission lobes, at incident
cosines mu_i = max(1e-6, i/63), i = 0..63 (the table Mitsuba's roughplastic interpolates):

    R(mu) = E_{m ~ D_wi}[ F(wi.m) G1(wo_r, m) ],   T(mu) = E_{m ~ D_wi}[ (1 - F(wi.m)) G1(wo_t, m) ]

with D_wi the visible-normal density, wo_r / wo_t the reflected / refracted directions (on the
right side of the surface). Integrated by quadrature over microfacet normals, with the polar
angle mapped by tan(theta) = alpha tan(u) so the lobe is resolved for any alpha.
"""
import functools

import numpy as np

TABLE_SIZE = 64


def _ndf(kind: str, alpha: float, cos_t: np.ndarray) -> np.ndarray:
    c2 = cos_t * cos_t
    tan2 = (1 - c2) / np.maximum(c2, 1e-30)
    if kind == "beckmann":
        return np.exp(-tan2 / alpha**2) / (np.pi * alpha**2 * c2 * c2)
    t = (1 - c2) / alpha**2 + c2
    return 1.0 / (np.pi * alpha**2 * t * t)


def _g1(kind: str, alpha: float, v: np.ndarray, m: np.ndarray) -> np.ndarray:
    """Smith G1 as in the device code (Walter's rational fit for Beckmann)."""
    vz = v[..., 2]
    xy = alpha**2 * (v[..., 0] ** 2 + v[..., 1] ** 2)
    tan_a2 = xy / np.maximum(vz * vz, 1e-30)
    if kind == "beckmann":
        a = 1.0 / np.sqrt(np.maximum(tan_a2, 1e-30))
        g = np.where(a >= 1.6, 1.0, (3.535 * a + 2.181 * a * a) / (1 + 2.276 * a + 2.577 * a * a))
    else:
        g = 2.0 / (1 + np.sqrt(1 + tan_a2))
    g = np.where(xy == 0, 1.0, g)
    return np.where(np.einsum("...i,...i->...", v, m) * vz > 0, g, 0.0)


def _fresnel(cos_i: np.ndarray, eta: float):
    """(reflectance, signed cos of the refracted direction, eta_ti) for cos_i > 0 (exterior side)."""
    eta_ti = 1.0 / eta
    cos_t2 = 1 - eta_ti**2 * (1 - cos_i**2)
    cos_t = np.sqrt(np.maximum(cos_t2, 0))
    a_s = (cos_i - eta * cos_t) / (cos_i + eta * cos_t)
    a_p = (cos_t - eta * cos_i) / (cos_t + eta * cos_i)
    r = np.where(cos_t2 <= 0, 1.0, 0.5 * (a_s**2 + a_p**2))
    return r, -cos_t, eta_ti


@functools.lru_cache(maxsize=None)
def _gauss_legendre(n: int) -> tuple[np.ndarray, np.ndarray]:
    """numpy's Gauss-Legendre nodes and weights, once per n (it solves an n x n eigenproblem:
    0.5 s at n = 384, which every table would otherwise pay twice)."""
    x, w = np.polynomial.legendre.leggauss(n)
    x.flags.writeable = w.flags.writeable = False
    return x, w


def albedos(kind: str, alpha: float, eta: float, mu: np.ndarray, n_theta=384, n_phi=256):
    """(R(mu), T(mu)) of the rough interface, arrays of len(mu)."""
    x, w = _gauss_legendre(n_theta)
    u = (x + 1) * (np.pi / 4)                        # u in (0, pi/2)
    du = w * (np.pi / 4)
    theta = np.arctan(alpha * np.tan(u))
    dtheta = du * alpha / np.cos(u) ** 2 / (1 + (alpha * np.tan(u)) ** 2)
    phi = (np.arange(n_phi) + 0.5) * (2 * np.pi / n_phi)
    T_, P_ = np.meshgrid(theta, phi, indexing="ij")
    m = np.stack([np.sin(T_) * np.cos(P_), np.sin(T_) * np.sin(P_), np.cos(T_)], -1)
    d_omega = (np.sin(theta) * dtheta)[:, None] * (2 * np.pi / n_phi)
    D = _ndf(kind, alpha, m[..., 2])
    R, T = np.zeros(len(mu)), np.zeros(len(mu))
    for i, c in enumerate(mu):
        wi = np.array([np.sqrt(1 - c * c), 0.0, c])
        wim = m @ wi
        dens = D * _g1(kind, alpha, np.broadcast_to(wi, m.shape), m) * np.maximum(wim, 0) / c * d_omega
        F, cos_t, eta_ti = _fresnel(np.maximum(wim, 1e-12), eta)
        wo_r = 2 * wim[..., None] * m - wi
        wo_t = m * (wim * eta_ti + cos_t)[..., None] - wi * eta_ti
        g_r = np.where(wo_r[..., 2] > 0, _g1(kind, alpha, wo_r, m), 0.0)
        g_t = np.where(wo_t[..., 2] < 0, _g1(kind, alpha, wo_t, m), 0.0)
        R[i] = np.sum(dens * F * g_r)
        T[i] = np.sum(dens * (1 - F) * g_t)
    return R, T


def roughplastic_tables(kind: str, alpha: float, eta: float) -> tuple[np.ndarray, float]:
    """External transmittance table (TABLE_SIZE) and internal reflectance, as Mitsuba defines them.
    Computed once per (kind, alpha, eta) in a process (a quadrature of about 1 s: Bitterli's
    staircase has six roughplastics with two parameter sets)."""
    t_ext, internal_reflectance = _tables(kind, float(alpha), float(eta))
    return t_ext.copy(), internal_reflectance


@functools.lru_cache(maxsize=None)
def _tables(kind: str, alpha: float, eta: float) -> tuple[np.ndarray, float]:
    mu = np.maximum(1e-6, np.linspace(0, 1, TABLE_SIZE))
    _, t_ext = albedos(kind, alpha, eta, mu)
    r_int, _ = albedos(kind, alpha, 1.0 / eta, mu)
    internal_reflectance = float(np.mean(r_int * mu) * 2.0)
    return t_ext, internal_reflectance
