r"""The seed lecture's mirror and refraction formulas in Dr.Jit, shared by the plugins.

Conventions (the seed's): ``v`` is a unit vector pointing *away* from the surface,
on the side of the unit normal ``n``; ``eta = n1 / n2`` is the index on v's side
over the index across the interface.

* Reflection:  R = 2 (N·V) N − V
* Refraction:  T = −η V + (η (V·N) − √(1 − η² (1 − (V·N)²))) N
  (n1 sin θ1 = n2 sin θ2, T in the plane of V and N, pointing into the other
  medium).  Where k = 1 − η² (1 − (V·N)²) < 0 no transmitted ray exists (total
  internal reflection): ``valid`` is False and T is 0.

This module lives in ``plugins/`` because plugins may import only Mitsuba,
Dr.Jit, numpy and their siblings; ``phonglab.optics`` (numpy in float64, and
Dr.Jit through these functions) is the one the checks call, so the formula is
written once for each array kind.  Any Dr.Jit 3-vector type works (it is used
as given, in its own precision).

Reference: D. Zorin, *Lighting* (lecture notes, 2005), slides "Reflection
geometry" and "Refracted ray direction"; T. Whitted, "An improved illumination
model for shaded display", CACM 23(6), 1980.
"""

from __future__ import annotations

import drjit as dr


def reflect(v, n):
    """Mirror direction R = 2 (N·V) N − V of v about the unit normal n."""
    return 2.0 * dr.dot(n, v) * n - v


def refract(v, n, eta):
    """(T, valid): the seed's refracted direction for v (away from the surface, on n's
    side) across an interface with index ratio eta = n1 / n2; T = 0 where not valid (TIR)."""
    cos_v = dr.dot(v, n)
    k = 1.0 - eta * eta * (1.0 - cos_v * cos_v)
    valid = k >= 0.0
    t = -eta * v + (eta * cos_v - dr.safe_sqrt(k)) * n
    return dr.select(valid, t, 0.0), valid
