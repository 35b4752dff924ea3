"""Signatures of documented emitter findings: the region of reference points a finding
explains (:class:`phonglab.validate.known.Known` ``region``: ``covers(row)`` -> one boolean per
failing lane, or None when the row records no such input).
"""

from __future__ import annotations

import numpy as np

from .setup import RAY_EPSILON


class SphereSurfaceBand:
    """Reference points within 2·RayEpsilon (relative) of a sphere's surface: where
    sphere.cpp's sample_direction (|p − c| vs r(1 ∓ RayEpsilon)) and pdf_direction
    (r/|p − c| vs 1 − 2⁻²⁴) decide inside/outside differently."""

    limit = 2.0 * RAY_EPSILON
    text = ("reference points within 2·RayEpsilon of the sphere's surface "
            "(| |p − c|/r − 1 | ≤ 1.8e-4)")

    def covers(self, row):
        lanes = row.failing_lanes or {}
        if "rel_radius" in lanes:
            return np.abs(np.asarray(lanes["rel_radius"], np.float64)) <= self.limit
        if "cell" in lanes:
            return np.array([abs(c.get("rel_radius", np.inf)) <= self.limit
                             for c in lanes["cell"]])
        return None


class InvalidSample:
    """Lanes whose sample sample_direction marked invalid (ds.pdf = 0): what an integrator
    drops before it calls eval_direction (path.cpp:248, ``active_em &= ds.pdf != 0``)."""

    text = "lanes whose direction sample is marked invalid (ds.pdf = 0)"

    def covers(self, row):
        lanes = row.failing_lanes or {}
        if "pdf" not in lanes:
            return None
        return np.asarray(lanes["pdf"], np.float64) == 0.0


class NegativeOnly:
    """Failing lanes of a ``finite`` row whose values are all finite, some negative (no NaN,
    no infinity): a radiance or weight below zero, not a broken computation."""

    text = "failing lanes whose values are finite and only negative (no NaN or infinity)"

    def covers(self, row):
        lanes = row.failing_lanes or {}
        if "negative_only" not in lanes:
            return None
        return np.asarray(lanes["negative_only"], bool)


class SunConeRim:
    """Lanes whose ds.d lies within :attr:`limit` float32 steps (2⁻²⁴) of the rim of a
    sunsky's sun cone by sunsky.h's own test (hit_sun, line 946, on normalize(to_world⁻¹ d)
    as pdf_direction and eval apply it: ``sun_rim_ulps``): sample_direction decides whether
    its sample hits the sun by another test (line 430): none for a sun sample, drawn from
    the exact cone (warp::square_to_uniform_cone, line 903) and rounded up to 3 steps outside,
    and hit_sun on the unnormalized sample_dir for a sky sample, up to 4 steps from the
    normalized direction's -- so the two disagree only within 4 steps of the rim, on either
    side."""

    limit = 4
    text = ("ds.d within 4 float32 steps of the rim of the sun's cone by sunsky.h's own test "
            "(|dot(sun, d) − cos θ_sun| ≤ 4·2^-24)")

    def covers(self, row):
        lanes = row.failing_lanes or {}
        if "sun_rim_ulps" not in lanes:
            return None
        return on_rim(np.asarray(lanes["sun_rim_ulps"], np.float64))


def on_rim(steps: np.ndarray) -> np.ndarray:
    """:class:`SunConeRim`'s band of ``sun_rim_ulps``."""
    return np.abs(steps) <= SunConeRim.limit
