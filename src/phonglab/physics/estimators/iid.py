"""The five estimators whose N samples are independent and identically distributed.

One function per estimator (the package docstring's table): the per-sample value X from the
uniform numbers u1 (lobe choice), u2 (direction) and, for MIS's second sample, the stream rng.
"""

from __future__ import annotations

import drjit as dr
import mitsuba as mi

from .kernel import Integrand, safe_ratio


def _uniform(f: Integrand, u1, u2, rng):
    """ω ~ uniform hemisphere, p = 1/(2π): X = eval · L · 2π."""
    wo = mi.warp.square_to_uniform_hemisphere(u2)
    return f.bsdf.eval(f.ctx, f.si, wo) * (f.light.emitted(wo) * dr.two_pi)


def _cosine(f: Integrand, u1, u2, rng):
    """ω ~ cos θ/π (Malley): X = eval · L / p."""
    wo = mi.warp.square_to_cosine_hemisphere(u2)
    pdf = mi.warp.square_to_cosine_hemisphere_pdf(wo)
    return f.bsdf.eval(f.ctx, f.si, wo) * safe_ratio(f.light.emitted(wo), pdf)


def _bsdf(f: Integrand, u1, u2, rng):
    """ω, w = bsdf.sample: X = w · L (w = eval / pdf)."""
    bs, weight = f.bsdf.sample(f.ctx, f.si, u1, u2)
    return weight * f.light.emitted(bs.wo)


def _light(f: Integrand, u1, u2, rng):
    """ω ~ the light's own sampling: X = eval · L_e / p."""
    wo, pdf = f.light.sample(u2)
    return f.bsdf.eval(f.ctx, f.si, wo) * safe_ratio(f.light.radiance, pdf)


def _mis(f: Integrand, u1, u2, rng):
    """One BSDF sample and one light sample, power heuristic β = 2 [Veach 1997, §9.2]."""
    bs, weight = f.bsdf.sample(f.ctx, f.si, u1, u2)
    p_b = bs.pdf
    p_l = f.light.pdf(bs.wo)
    w_b = dr.select(p_b > 0, dr.square(p_b) / (dr.square(p_b) + dr.square(p_l)), 0.0)
    value = weight * (f.light.emitted(bs.wo) * w_b)
    u3 = mi.Point2f(rng.next_float32(), rng.next_float32())
    wo, p_l = f.light.sample(u3)
    f_l, p_b = f.bsdf.eval_pdf(f.ctx, f.si, wo)
    w_l = dr.select(p_l > 0, dr.square(p_l) / (dr.square(p_l) + dr.square(p_b)), 0.0)
    return value + f_l * safe_ratio(f.light.radiance * w_l, p_l)


#: The estimators by name (the order of :data:`~.problem.METHODS`).
ESTIMATORS = {"uniform": _uniform, "cosine": _cosine, "bsdf": _bsdf, "light": _light,
               "mis": _mis}
