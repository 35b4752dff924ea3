r"""Deterministic quadrature of the reflection equation, adapted to a glossy lobe.

The directional albedo a(ω_i) = ∫_{H+} f_r(ω_i, ω_o) cos θ_o dω_o is, with constant incident
radiance L_i = 1, the reflected radiance L_r of the reflection equation (by reciprocity
f_r(ω_i, ω_r) = f_r(ω_r, ω_i)).  A Mitsuba BSDF's ``eval`` returns f_r cos θ_o, so
:func:`albedo_by_quadrature` is Σ_k w_k eval(ω_i, ω_k) over the nodes of :func:`lobe_quadrature`.

The rule.  Coordinates (α, φ) in the frame centred on the mirror direction R(ω_i):
ω = cos α R + sin α (cos φ T₁ + sin φ T₂), dω = sin α dα dφ, with
R = (−sin θ_i, 0, cos θ_i), T₁ = (−cos θ_i, 0, −sin θ_i), T₂ = (0, 1, 0).  The upper
hemisphere is exactly α < α_h(φ) = atan2(cos θ_i, sin θ_i cos φ) (where
ω_z = cos α cos θ_i − sin α cos φ sin θ_i = 0), so the horizon is a panel edge and the
integrand is smooth inside each panel.  Composite Gauss–Legendre with n nodes per panel:
α panels doubling from width/4 (a lobe cos^p α has width ≈ 1/√p; :func:`lobe_width` gives
1/√(p + 2)) plus an edge at α = π/2 (where max(0, cos α)^p has its kink), φ panels doubling
away from π/2 (where α_h turns quickly at grazing incidence).  Only φ ∈ [0, π] is used and
the weights are doubled: isotropic BSDFs with ω_i in the xz-plane are symmetric under y → −y.

Accuracy.  The rule integrates 1 and cos θ over the hemisphere (2π and π) to 1e-12 relative
at any θ_i, grazing included (tested).  Through a BSDF's float32 ``eval`` the error
estimate |Q(n = 20) − Q(n = 40)| is about 1e-8 for a modified-Phong lobe up to p = 10⁴; at
p = 10⁵ it grows to ~4e-5 because float32 cos α = ω_o·R has spacing 2⁻²⁴ near 1, which turns
cos^p α into a staircase with steps of p·2⁻²⁴ ≈ 0.6 % per node.

Not to be confused with :func:`phonglab.physics.radiometry.hemisphere_quadrature` (a fixed
product Gauss rule in cos θ and φ, not adapted to a lobe) nor with
:func:`phonglab.physics.radiometry.directional_albedo` (a Monte Carlo estimate from
``sample``).
"""

from __future__ import annotations

import math

import numpy as np

from .. import probe


def _geometric_edges(lo: float, hi: float, start: float) -> list[float]:
    """start, 2 start, 4 start, ... strictly between lo and hi."""
    edges, e = [], start
    while e < hi:
        if e > lo:
            edges.append(e)
        e *= 2.0
    return edges


def lobe_width(p: float) -> float:
    """Angular width 1/√(p + 2) of a modified-Phong lobe cos^p α (radians)."""
    return 1.0 / math.sqrt(p + 2.0)


def lobe_quadrature(theta_i: float, width: float, n: int = 20, azimuth: float = math.pi,
                    symmetric: bool = True) -> tuple[np.ndarray, np.ndarray]:
    r"""Nodes and weights for ∫_{H+} g(ω) dω, refined around the mirror direction R(ω_i).

    ``theta_i`` is the incidence angle (radians, ω_i in the xz-plane at φ = 0), ``width`` the
    angular width of the lobe around R, ``n`` the Gauss–Legendre nodes per panel (the module
    docstring states the rule).

    A lobe centred elsewhere (a normal-mapped or measured BSDF): the centre is the direction
    at polar angle ``theta_i`` and azimuth ``azimuth`` (default π, the mirror direction R);
    ``symmetric=False`` integrates the whole circle φ ∈ [0, 2π] around it instead of doubling
    the half φ ∈ [0, π] (which assumes g symmetric about the plane through the centre and the
    normal).

    Returns:
        (wo (M, 3), weights (M,)) in float64.
    """
    c, s = math.cos(theta_i), math.sin(theta_i)
    R = np.array([-s, 0.0, c])
    T1 = np.array([-c, 0.0, -s])
    T2 = np.array([0.0, 1.0, 0.0])
    dphi = max(c, 1e-4) / 4.0
    side = _geometric_edges(0.0, math.pi / 2, dphi)
    half = {0.0, math.pi, math.pi / 2} | {math.pi / 2 - e for e in side} | \
        {math.pi / 2 + e for e in side}
    phi_edges = np.array(sorted(half if symmetric else half | {2 * math.pi - e for e in half}))
    fold = 2.0 if symmetric else 1.0
    x, w = np.polynomial.legendre.leggauss(n)
    # φ nodes: composite Gauss-Legendre over the φ panels.
    h = 0.5 * np.diff(phi_edges)
    phi = (phi_edges[:-1, None] + h[:, None] * (x + 1.0)).ravel()
    wphi = (h[:, None] * w).ravel()
    alpha_h = np.arctan2(c, s * np.cos(phi))                          # horizon, per φ node
    # α panels: fixed edges clipped to [0, α_h(φ)]; panels past the horizon get zero width.
    edges = np.array([0.0] + sorted(set(_geometric_edges(0.0, math.pi, width / 4.0))
                                    | {math.pi / 2}) + [math.pi])
    lo = np.minimum(edges[None, :-1], alpha_h[:, None])               # (φ, panel)
    hi = np.minimum(edges[None, 1:], alpha_h[:, None])
    ha = 0.5 * (hi - lo)
    alpha = lo[..., None] + ha[..., None] * (x + 1.0)                  # (φ, panel, node)
    walpha = ha[..., None] * w
    keep = np.broadcast_to((ha > 0)[..., None], alpha.shape)
    al = alpha[keep]
    sa, ca = np.sin(al), np.cos(al)
    wts = fold * np.broadcast_to(wphi[:, None, None], alpha.shape)[keep] * walpha[keep] * sa
    # cos φ and sin φ once per φ node, then spread over its α nodes
    cph = np.broadcast_to(np.cos(phi)[:, None, None], alpha.shape)[keep]
    sph = np.broadcast_to(np.sin(phi)[:, None, None], alpha.shape)[keep]
    dirs = (ca[:, None] * R + sa[:, None] * (cph[:, None] * T1 + sph[:, None] * T2))
    if azimuth != math.pi:                                 # rotate the centre about the normal
        cr, sr = math.cos(azimuth - math.pi), math.sin(azimuth - math.pi)
        dirs = np.column_stack([cr * dirs[:, 0] - sr * dirs[:, 1],
                                sr * dirs[:, 0] + cr * dirs[:, 1], dirs[:, 2]])
    return dirs, wts


def albedo_by_quadrature(bsdf, theta_i: float, width: float, n: int = 20) -> float:
    """a(ω_i) = ∫ f_r(ω_i, ω_o) cos θ_o dω_o = ∫ eval dω_o by :func:`lobe_quadrature`, channel 0.

    ``bsdf`` is a Mitsuba BSDF probed through :mod:`phonglab.probe` (one kernel launch for
    all nodes); ω_i = (sin θ_i, 0, cos θ_i).  With L_i = 1 this is the reflected radiance L_r.
    """
    wo, w = lobe_quadrature(theta_i, width, n)
    wo = wo / np.linalg.norm(wo, axis=1, keepdims=True)
    return float(np.sum(w * probe.eval(bsdf, probe.direction(theta_i), wo)[:, 0]))
