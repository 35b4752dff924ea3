"""Signatures of documented emitter findings: the region of reference points a finding
explains (:class:`phonglab.validate.core.Known` ``region``: ``covers(row)`` -> one boolean per
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
