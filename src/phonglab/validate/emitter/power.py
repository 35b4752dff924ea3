r"""The ``power`` topic: the emitter's radiant power from ``sample_ray`` against an independent
value, ``sample_position``/``pdf_position``, and the delta lights' laws.

Mitsuba's ``sample_ray(time, λ-sample, u₂, u₃)`` returns (ray, weight) with E[weight] = Φ, the
power leaving the emitter (src/emitters/*.cpp, 3.9.1; pbrt-v4 §12 "Light Sources" gives the
same powers, ``Light::Phi``):

* area (area.cpp ``sample_ray``): a point by area (weight 1/p_A = A), a cosine-weighted
  direction, weight = A · π · L: Φ = π ∫_A L dA for a radiance that does not depend on
  direction.  The expectation here: π A · mean L(x) over points x drawn by the *shape's*
  ``sample_position`` (uniform by area, independent of the emitter), L = eval at x towards
  its normal;
* constant and envmap (constant.cpp: weight = L · 4πR² · π; envmap.cpp: L(ω) π R² / p(ω)):
  Φ = π R² ∫_{S²} L(ω) dω, R the bounding-sphere radius set_scene gave the emitter (the
  scene's r(1 + RayEpsilon), :mod:`.setup`); the expectation: 4π² R² · mean L(ω) over
  uniform directions ω (eval at si.wi = −ω); an environment with a concentrated feature
  (sample_direction's density above PEAK_RATIO/4π: sunsky's sun) has the cone of
  PEAK_CONE/pdf_max sr about its most probable direction integrated apart (half the
  directions each), which uniform directions alone hit about once in 2·10⁵ (sunsky: 20.2
  for the 54.4 of 2·10⁷ stratified directions);
* point (point.cpp: weight = 4π I): Φ = 4π I; spot (spot.cpp: I · falloff / p_cone over the
  cutoff cone): Φ = 2π I₀ ∫₀^{θ_c} f(θ) sin θ dθ with f = 1 for θ ≤ θ_b (beam_width),
  (θ_c − θ)/(θ_c − θ_b) up to the cutoff θ_c and 0 beyond (spot.cpp ``falloff_curve``,
  lines 143-150), integrated here by a 20 000-node midpoint rule; any other delta-position
  light: 4π · mean I(ω) over uniform directions, I(ω) = weight · r² of sample_direction at
  r = 1;
* directional (directional.cpp: weight = E π R²): Φ = E π R².

In spectral variants Mitsuba's sample_ray draws the wavelengths too (weight L(λ)/p(λ), whose
mean is ∫ L(λ) dλ over [MI_CIE_MIN, MI_CIE_MAX]); the expectation then evaluates L at
wavelengths uniform over that range and multiplies by its width (:func:`~.setup.wavelengths`).

The estimate is the mean of ``power_samples`` sample_ray weights (channels summed) with its
standard error, the expectation's own Monte Carlo error (0 for a constant radiance) added in
quadrature; the row passes when |mean − Φ| ≤ z · stderr + 2⁻¹⁰ |Φ| (float32 accumulation),
z the two-sided normal quantile at the Šidák level of the emitter's m statistical tests.

Laws of delta lights (identities at round-off, ``roundoff.REL_TOL``, plus the weight's
sensitivity to an 8u move of the reference point, ``roundoff.sensitivity``): the intensity
I = weight · r² of a delta-position light is the same at r = 0.5, 1, 2 along each direction
(the inverse-square law E = I cos θ / r²; a weight falling as 1/r fails here); a spot's
I(θ)/I₀ equals f(θ) above, I₀ the weight · r² on its axis (the law's own conditioning added:
f at θ ± 16u/sin θ, the float32 error of spot.cpp's acos); a directional light's weight
(its irradiance E) is the same at every reference point.

Positions (surface emitters): ``pdf_position(ps)`` = ps.pdf, and for a radiance that is not
spatially varying ps.pdf = 1/A (area.cpp ``sample_position``: the shape's uniform sampling,
e.g. sphere.cpp ``m_inv_surface_area``).
"""

from __future__ import annotations

import math

import drjit as dr
import mitsuba as mi
import numpy as np

from ... import probe, stats
from ...verdict import NOT_APPLICABLE
from ..roundoff import REL_TOL, rel_diff, sensitivity
from .config import rng
from .identities import bounded
from .setup import (Setup, cone_dirs, float_, interaction, point2, ref_groups, sphere_dirs,
                    surface_interaction, wavelengths)
from .topics import Row


def _mean(x: np.ndarray) -> tuple[float, float]:
    return float(np.mean(x)), float(np.std(x, ddof=1) / math.sqrt(len(x))) if len(x) > 1 else 0.0


#: An environment whose sample_direction density peaks above this many times the uniform
#: 1/4π has a concentrated feature (a sun) that its power expectation integrates apart.
PEAK_RATIO = 1000.0
#: The feature's cone: its solid angle is this many times 1/pdf_max (at least as many times
#: the feature's own solid angle, whose density is at most 1/Ω_feature).
PEAK_CONE = 10.0


def _env_radiance(e, d: np.ndarray, lam) -> np.ndarray:
    """L(ω) of an environment along directions ω (eval at si.wi = −ω), channels summed."""
    n = len(d)
    si = surface_interaction(n, lam)
    si.wi = -probe.to_vectors(d)
    return np.sum(probe.to_numpy(e.eval(si), n), axis=1)


def _peak(setup: Setup, r) -> tuple[np.ndarray, float] | None:
    """(the direction, the cosine of the cone) of an environment's concentrated feature, found
    as sample_direction's most probable direction from the scene centre; None if none."""
    n = 4096
    ds, _ = setup.calls.sample_direction(interaction(np.tile(setup.center, (n, 1))),
                                           point2(r.random((n, 2))))
    pdf = probe.to_numpy(ds.pdf, n)
    pdf = np.where(np.isfinite(pdf), pdf, 0.0)
    k = int(np.argmax(pdf))
    if pdf[k] * 4.0 * math.pi < PEAK_RATIO:
        return None
    omega = min(PEAK_CONE / pdf[k], math.pi)
    return probe.to_numpy(ds.d, n)[k], 1.0 - omega / (2.0 * math.pi)


def sample_ray_mean(setup: Setup, opts) -> tuple[float, float]:
    n = opts.power_samples
    u = rng(opts.seed, "power").random((n, 5))
    _, w = setup.calls.sample_ray(float_(np.zeros(n)), float_(u[:, 4]), point2(u[:, :2]),
                                    point2(u[:, 2:4]))
    x = np.sum(probe.to_numpy(w, n), axis=1)
    return _mean(np.where(np.isfinite(x), x, 0.0))


def intensity(setup: Setup, d: np.ndarray, r: float = 1.0, lam=None) -> np.ndarray:
    """I(ω) = weight · r² of sample_direction from P + r ω (channels summed; wavelengths
    ``lam`` in spectral variants)."""
    p = setup.center + r * d
    it = interaction(p, lam)
    _, w = setup.calls.sample_direction(it, point2(np.full((len(p), 2), 0.5)))
    return np.sum(probe.to_numpy(w, len(p)), axis=1) * r * r


def falloff(setup: Setup, d: np.ndarray, dtheta=0.0) -> np.ndarray:
    """spot.cpp's falloff_curve at directions d (from the light), their angle to the axis moved
    by ``dtheta``, from its cutoff and beam width as mi.traverse reports them."""
    params = mi.traverse(setup.emitter)
    tc = math.radians(float(np.ravel(params["cutoff_angle"])[0]))
    tb = math.radians(float(np.ravel(params["beam_width"])[0]))
    theta = np.arccos(np.clip(d @ setup.axis, -1.0, 1.0)) + dtheta
    return np.where(theta <= tb, 1.0, np.where(theta < tc, (tc - theta) / (tc - tb), 0.0)), tc, tb


#: float32 error of θ = acos(cos θ) in spot.cpp's falloff_curve, times sin θ: cos θ of a
#: normalized float32 vector is good to a few u, and acos divides that by sin θ (×4 margin).
ACOS_ERROR = 16 * 2.0 ** -24


def expected_power(setup: Setup, opts) -> tuple[float | None, float, str]:
    """(Φ, its standard error, how it was computed); Φ None when it cannot be known."""
    n = opts.power_samples
    r = rng(opts.seed, "power")
    e = setup.calls
    lam, width = wavelengths(n, r)
    if setup.kind == "surface":
        u = r.random((n, 2))
        ps = setup.shape.sample_position(float_(np.zeros(n)), point2(u))
        si = mi.SurfaceInteraction3f(ps, surface_interaction(n, lam).wavelengths)
        si.wi = mi.Vector3f(0.0, 0.0, 1.0)
        m, se = _mean(width * np.sum(probe.to_numpy(e.eval(si), n), axis=1))
        A = float(np.ravel(setup.shape.surface_area())[0])
        return math.pi * A * m, math.pi * A * se, f"π·A·mean L, A = {A:.6g} (shape's area)"
    if setup.kind == "infinite":
        if setup.bsphere_radius is None:
            return None, 0.0, ("Mitsuba 3.9.1 never calls a Python emitter's set_scene: its "
                               "bounding sphere, on which its power depends, is unknown")
        k = 4.0 * math.pi ** 2 * setup.bsphere_radius ** 2
        peak = _peak(setup, r)
        if peak is None:
            m, se = _mean(width * _env_radiance(e, sphere_dirs(r, n), lam))
            return k * m, k * se, f"4π²R²·mean L(ω), R = {setup.bsphere_radius:.6g}"
        # a concentrated feature (a sun): the cone around it and the rest apart, each with
        # half the directions (uniform ones hit a 0.5 deg sun once in 2e5 and miss its power)
        axis, cos_max = peak
        omega = 2.0 * math.pi * (1.0 - cos_max)
        h = n // 2
        lc = width * _env_radiance(e, cone_dirs(r, h, axis, cos_max), lam[:h] if lam is not None
                                   else None)
        du = sphere_dirs(r, n - h)
        lu = width * _env_radiance(e, du, lam[h:] if lam is not None else None) \
            * (du @ axis < cos_max)
        (mc, sc), (mu, su) = _mean(lc), _mean(lu)
        m = (omega * mc + 4.0 * math.pi * mu) / (4.0 * math.pi)
        se = math.hypot(omega * sc, 4.0 * math.pi * su) / (4.0 * math.pi)
        return k * m, k * se, (f"4π²R²·mean L(ω), R = {setup.bsphere_radius:.6g}, the cone of "
                               f"{math.degrees(math.acos(cos_max)):.3g} deg about its peak "
                               f"integrated apart")
    if setup.kind == "direction":
        if setup.bsphere_radius is None:
            return None, 0.0, ("Mitsuba 3.9.1 never calls a Python emitter's set_scene: its "
                               "bounding sphere, on which its power depends, is unknown")
        it = interaction(np.tile(setup.center, (n, 1)), lam)
        _, w = e.sample_direction(it, point2(np.full((n, 2), 0.5)))
        E, se = _mean(width * np.sum(probe.to_numpy(w, n), axis=1))
        k = math.pi * setup.bsphere_radius ** 2
        return E * k, se * k, f"E·π·R², E = {E:.6g}, R = {setup.bsphere_radius:.6g}"
    if setup.axis is not None:
        i0, se0 = _mean(width * intensity(setup, np.tile(setup.axis, (n, 1)), lam=lam))
        k = 20000
        _, tc, tb = falloff(setup, setup.axis[None])
        th = (np.arange(k) + 0.5) * tc / k
        f = np.where(th <= tb, 1.0, (tc - th) / (tc - tb))
        lobe = 2.0 * math.pi * float(np.sum(f * np.sin(th)) * tc / k)
        return lobe * i0, lobe * se0, f"2π I₀ ∫ f(θ) sin θ dθ, I₀ = {i0:.6g}"
    m, se = _mean(width * intensity(setup, sphere_dirs(r, n), lam=lam))
    return 4.0 * math.pi * m, 4.0 * math.pi * se, "4π·mean I(ω) over uniform directions"


def power(setup: Setup, opts, m_tests: int) -> list[Row]:
    rows = [_power_row(setup, opts, m_tests)]
    if setup.kind == "surface":
        rows += _positions(setup, opts)
    elif setup.kind == "position":
        rows += _intensity_laws(setup, opts)
    else:
        rows += _irradiance_law(setup, opts) if setup.kind == "direction" else []
    return rows


def _power_row(setup, opts, m_tests) -> Row:
    phi, se_phi, how = expected_power(setup, opts)
    if phi is None:
        # a Python environment or directional emitter: no author can give it a bounding sphere
        # in 3.9.1, so the topic does not apply (not a coverage the author failed to give)
        inapplicable = setup.python and setup.kind in ("infinite", "direction")
        return Row("power", "mean sample_ray weight = power", None, None, None, None, "skipped",
                   (f"not applicable in Mitsuba 3.9.1: {how}" if inapplicable else how),
                   {NOT_APPLICABLE: True} if inapplicable else {})
    mean, se = sample_ray_mean(setup, opts)
    stderr = math.hypot(se, se_phi)
    z = stats.z_critical(stats.ALPHA, m_tests)
    tol = z * stderr + REL_TOL * abs(phi)
    ok = math.isfinite(mean) and abs(mean - phi) <= tol
    return Row("power", "mean sample_ray weight = power", mean, phi, stderr, tol,
               "pass" if ok else "fail",
               f"mean of {opts.power_samples} sample_ray weights (channels summed) against "
               f"Φ = {how}; tolerance z·stderr + 2^-10|Φ|, z = {z:.3g} (Šidák level of the "
               f"emitter's {m_tests} statistical tests)",
               {"z": (mean - phi) / stderr if stderr > 0 else None, "relation": "=="})


def position_pdf(setup: Setup, ps, n: int) -> tuple[np.ndarray, str]:
    """(pdf_position(ps), whose): the emitter's, or the shape's where the emitter has none
    (area.cpp defines no pdf_position: Endpoint::pdf_position raises 'not implemented'; a
    renderer asks the shape, as Mitsuba's integrators do)."""
    try:
        return probe.to_numpy(setup.calls.pdf_position(ps), n), "the emitter's"
    except RuntimeError as exc:
        if "not implemented" not in str(exc):
            raise
        return probe.to_numpy(setup.shape.pdf_position(ps), n), \
            "the shape's (the emitter has no pdf_position)"


def _positions(setup, opts) -> list[Row]:
    n = opts.n_lanes
    u = rng(opts.seed, "power").random((n, 2))
    ps, w = setup.calls.sample_position(float_(np.zeros(n)), point2(u))
    a = probe.to_numpy(ps.pdf, n)
    b, whose = position_pdf(setup, ps, n)
    weight = np.sum(probe.to_numpy(w, n), axis=1) if dr.depth_v(w) > 1 else probe.to_numpy(w, n)
    inputs = {"u": u}
    rows = [bounded("power", "pdf_position(ps) = ps.pdf", np.nan_to_num(rel_diff(b, a),
                                                                      nan=np.inf),
                    REL_TOL, f"max over {n} sample_position lanes of rel_diff({whose} "
                    f"pdf_position, ps.pdf); float32 round-off 2^-10", {"lanes": n}, inputs)]
    rows.append(bounded("power", "sample_position weight = 1/ps.pdf",
                        np.nan_to_num(rel_diff(weight * a, np.ones(n)), nan=np.inf), REL_TOL,
                        f"max over {n} lanes of rel_diff(weight·ps.pdf, 1)", {"lanes": n},
                        inputs))
    if not int(setup.emitter.flags()) & int(mi.EmitterFlags.SpatiallyVarying):
        A = float(np.ravel(setup.shape.surface_area())[0])
        rows.append(bounded("power", "ps.pdf = 1/area (uniform by area)",
                            np.nan_to_num(rel_diff(a, np.full(n, 1.0 / A)), nan=np.inf),
                            REL_TOL, f"max over {n} lanes of rel_diff(ps.pdf, 1/A), A = {A:.6g} "
                            f"(the shape's surface_area); radiance not spatially varying",
                            {"lanes": n, "area": A}, inputs))
    return rows


def _intensity_sensitivity(setup, d, r, value, gen) -> np.ndarray:
    """Per direction: the relative change of weight·r² when the reference point P + r d moves
    by 8u per component (roundoff.sensitivity): a spot's I(θ) near its cutoff, where
    f → 0 while its slope is 1/(θ_c − θ_b), is ill-conditioned in the point's rounding."""
    def at(p, _):
        it = interaction(p)
        _, w = setup.calls.sample_direction(it, point2(np.full((len(p), 2), 0.5)))
        return np.sum(probe.to_numpy(w, len(p)), axis=1) * r * r

    return sensitivity(at, setup.center + r * d, d, gen, value=value)


def _intensity_laws(setup, opts) -> list[Row]:
    groups = ref_groups(setup, opts.n_lanes, opts.seed)
    d = (groups[1].p - setup.center)                      # unit directions (r = 1)
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    gen = rng(opts.seed, "power")
    i = {r: intensity(setup, d, r) for r in (0.5, 1.0, 2.0)}
    sens = {r: _intensity_sensitivity(setup, d, r, i[r], gen) for r in i}
    excess = np.maximum(
        np.nan_to_num(rel_diff(i[0.5], i[1.0]), nan=np.inf) / (REL_TOL + sens[0.5] + sens[1.0]),
        np.nan_to_num(rel_diff(i[2.0], i[1.0]), nan=np.inf) / (REL_TOL + sens[2.0] + sens[1.0]))
    worst = int(np.argmax(excess))
    rows = [bounded("power", "intensity law: weight·r² the same at r = 0.5, 1, 2", excess, 1.0,
                    f"measured = max over {len(d)} directions of rel_diff(weight·r² at r = 0.5 "
                    f"or 2, at r = 1) / (2^-10 + both sides' sensitivity to an 8u move of the "
                    f"reference point), must be ≤ 1: the inverse-square law E = I/r²; at the "
                    f"worst direction I = {i[0.5][worst]:.6g}, {i[1.0][worst]:.6g}, "
                    f"{i[2.0][worst]:.6g}", {"lanes": len(d)}, {"direction": d})]
    if setup.axis is not None:
        f, _, _ = falloff(setup, d)
        i0 = float(intensity(setup, setup.axis[None])[0])
        dtheta = ACOS_ERROR / np.maximum(np.sqrt(np.maximum(0.0, 1.0 - (d @ setup.axis) ** 2)),
                                         1e-3)
        law = np.max([np.nan_to_num(rel_diff(i0 * f, i0 * falloff(setup, d, k * dtheta)[0]),
                                    nan=0.0) for k in (-1.0, 1.0)], axis=0)
        excess = np.nan_to_num(rel_diff(i[1.0], i0 * f), nan=np.inf) / (REL_TOL + sens[1.0]
                                                                         + law)
        rows.append(bounded("power", "spot falloff: I(θ) = I₀ f(θ)", excess, 1.0,
                            f"measured = max over {len(d)} directions of rel_diff(weight·r², "
                            f"I₀·f(θ)) / (2^-10 + the weight's sensitivity to an 8u move of the "
                            f"reference point + I₀f's to θ ± 16u/sin θ, spot.cpp's float32 acos), "
                            f"must be ≤ 1; f from cutoff_angle and beam_width "
                            f"as spot.cpp:143-150, I₀ = {i0:.6g} on the axis",
                            {"lanes": len(d)}, {"direction": d}))
    return rows


def _irradiance_law(setup, opts) -> list[Row]:
    groups = ref_groups(setup, opts.n_lanes, opts.seed)
    p = np.concatenate([g.p for g in groups])
    it = interaction(p)
    _, w = setup.calls.sample_direction(it, point2(np.full((len(p), 2), 0.5)))
    E = np.sum(probe.to_numpy(w, len(p)), axis=1)
    rel = np.nan_to_num(rel_diff(E, np.full(len(p), E[0])), nan=np.inf)
    return [bounded("power", "irradiance E the same at every reference point", rel, REL_TOL,
                    f"max over {len(p)} points inside and outside the scene's bounding sphere "
                    f"of rel_diff(weight, weight at the first), E = {E[0]:.6g}; a directional "
                    f"light's irradiance on a surface is E cos θ; float32 round-off 2^-10",
                    {"lanes": len(p)}, {"ref": p})]
