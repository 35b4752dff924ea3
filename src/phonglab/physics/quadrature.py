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
integrand is smooth inside each panel (as is any given height ω_z = h where it may jump:
``heights``).  Composite Gauss–Legendre with n nodes per panel:
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


#: A ``refine`` lobe of width w (the 10 % quantile of its samples' angles, 0.46 σ for a
#: Gaussian lobe) is resolved by a panel at most RESOLVED·w ≈ 1.8 σ wide, whatever its Gauss-
#: Legendre order from 8 on; a wider panel of the rule there is graded down towards it.
RESOLVED = 4.0


def _panel(edges: np.ndarray, x: float) -> float:
    """Width of the panel of sorted ``edges`` that contains x."""
    j = int(np.clip(np.searchsorted(edges, x), 1, len(edges) - 1))
    return float(edges[j] - edges[j - 1])


def _refinement_edges(points, frame, alpha_edges: np.ndarray, phi_edges: np.ndarray,
                      symmetric: bool) -> tuple[set, set]:
    """(α edges, φ edges) graded towards each (polar angle, azimuth, width) of ``points`` in
    the rule's frame ``frame`` = (R, T1, T2, rotation about the normal), where the rule's own
    panels there (``alpha_edges``, ``phi_edges``) are wider than :data:`RESOLVED` widths:
    α_k ± (w/4)·2^j and φ_k ± (w/4)·2^j / sin α_k, j = 0, 1, ..., up to twice that panel's
    width (:func:`lobe_quadrature`'s ``refine``)."""
    R, T1, T2, turn = frame
    out_alpha, out_phi = set(), set()
    two_pi = 2.0 * math.pi
    for theta, phi, width in points:
        v = np.array([math.sin(theta) * math.cos(phi - turn),
                      math.sin(theta) * math.sin(phi - turn), math.cos(theta)])
        a = math.acos(min(1.0, max(-1.0, float(v @ R))))
        f = math.atan2(float(v @ T2), float(v @ T1)) % two_pi
        if symmetric and f > math.pi:
            f = two_pi - f
        reach_a = _panel(alpha_edges, a)
        if reach_a > RESOLVED * width:
            e = width / 4.0
            while e < 2.0 * reach_a:
                out_alpha |= {x for x in (a - e, a + e) if 0.0 < x < math.pi}
                e *= 2.0
        arc = math.sin(a)
        reach_f = _panel(phi_edges, f) * arc
        if arc > width and reach_f > RESOLVED * width:   # nearer the pole: the polar panels
            e = width / 4.0
            while e < 2.0 * reach_f and e / arc < math.pi:
                out_phi |= {(f + e / arc) % two_pi, (f - e / arc) % two_pi}
                e *= 2.0
    if symmetric:
        out_phi = {x for x in out_phi if x <= math.pi}
    return out_alpha, out_phi


def _height_edges(c: float, s: float, phi: np.ndarray, heights) -> np.ndarray:
    """Per φ node, the α (in (0, α_h(φ))) where ω_z = cos α cos θ_i − sin α cos φ sin θ_i
    equals each of ``heights``; π where there is none (clipped away by the horizon).  With
    A = hypot(cos θ_i, sin θ_i cos φ) and δ = atan2(sin θ_i cos φ, cos θ_i), ω_z = A cos(α + δ)
    and α_h = π/2 − δ: ω_z = h at α = ±acos(h/A) − δ (two crossings where the circle of α
    rises towards the pole before it falls to the horizon, cos φ < 0)."""
    cos_phi = s * np.cos(phi)
    amp, delta = np.hypot(c, cos_phi), np.arctan2(cos_phi, c)
    horizon = 0.5 * math.pi - delta
    out = []
    for h in heights:
        with np.errstate(invalid="ignore"):
            a = np.arccos(h / amp)
        for alpha in (a - delta, -a - delta):
            ok = np.isfinite(alpha) & (alpha > 0.0) & (alpha < horizon)
            out.append(np.where(ok, alpha, math.pi))
    return np.stack(out, axis=1)


def lobe_quadrature(theta_i: float, width: float, n: int = 20, azimuth: float = math.pi,
                    symmetric: bool = True, refine=(),
                    heights=()) -> tuple[np.ndarray, np.ndarray]:
    r"""Nodes and weights for ∫_{H+} g(ω) dω, refined around the mirror direction R(ω_i).

    ``theta_i`` is the incidence angle (radians, ω_i in the xz-plane at φ = 0), ``width`` the
    angular width of the lobe around R, ``n`` the Gauss–Legendre nodes per panel (the module
    docstring states the rule).

    A lobe centred elsewhere (a normal-mapped or measured BSDF): the centre is the direction
    at polar angle ``theta_i`` and azimuth ``azimuth`` (default π, the mirror direction R);
    ``symmetric=False`` integrates the whole circle φ ∈ [0, 2π] around it instead of doubling
    the half φ ∈ [0, π] (which assumes g symmetric about the plane through the centre and the
    normal).

    ``refine``: further lobes (polar angle, azimuth, width) in the same frame as the centre,
    away from it (a broad lobe beside the narrow one the rule is centred on, or a narrow one
    off the centre): where the rule's own α or φ panel there is wider than
    :data:`RESOLVED` widths, its edges are graded towards the lobe as they are towards the
    centre, α_k ± (w/4)·2^j and φ_k ± (w/4)·2^j / sin α_k, so that the cells near
    (α_k, φ_k) are no larger than their distance to it and the lobe is resolved as the
    centred one is (a cos^3000 lobe 1.3 rad off the centre: 1 to 1e-9 by 8, 12 and 16 nodes,
    against 0.88 to 1.10 unrefined).  The edges apply to every φ (α edges) and every α
    (φ edges): a product rule, refined towards a point in both coordinates.

    ``heights``: values h ∈ (0, 1) of ω_z at which the integrand may jump (a support that
    ends short of the horizon, parallel to it): each is an α edge of every φ node, where that
    node's circle of α crosses ω_z = h (:func:`_height_edges`), as the horizon is: a jump
    there is integrated exactly where the centre lies above it (cos θ_i > h; a cap of
    ω_z > h away from the centre also ends in φ, which no φ panel follows).  A rough
    dielectric's transmitted pdf at grazing incidence ends at |ω_z| = cos θ_i / η (the
    refraction through microfacets perpendicular to the surface) with a jump there, which a
    panel running on to the horizon integrates with an error no coarser rule reveals
    (``phonglab.validate.bsdf.lobes`` measures it).

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
    edges = np.array([0.0] + sorted(set(_geometric_edges(0.0, math.pi, width / 4.0))
                                    | {math.pi / 2}) + [math.pi])
    if refine:
        extra_alpha, extra_phi = _refinement_edges(refine, (R, T1, T2, azimuth - math.pi),
                                                   edges, phi_edges, symmetric)
        edges = np.unique(np.concatenate([edges, sorted(extra_alpha)]))
        phi_edges = np.unique(np.concatenate([phi_edges, sorted(extra_phi)]))
    fold = 2.0 if symmetric else 1.0
    x, w = np.polynomial.legendre.leggauss(n)
    # φ nodes: composite Gauss-Legendre over the φ panels.
    h = 0.5 * np.diff(phi_edges)
    phi = (phi_edges[:-1, None] + h[:, None] * (x + 1.0)).ravel()
    wphi = (h[:, None] * w).ravel()
    alpha_h = np.arctan2(c, s * np.cos(phi))                          # horizon, per φ node
    # α panels: fixed edges clipped to [0, α_h(φ)]; panels past the horizon get zero width.
    if len(heights):                                                  # per-φ edges as well
        grid = np.sort(np.concatenate([np.broadcast_to(edges, (len(phi), len(edges))),
                                       _height_edges(c, s, phi, heights)], axis=1), axis=1)
    else:
        grid = edges[None, :]
    lo = np.minimum(grid[:, :-1], alpha_h[:, None])                   # (φ, panel)
    hi = np.minimum(grid[:, 1:], alpha_h[:, None])
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
