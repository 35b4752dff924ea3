r"""Beckmann roughness α ↔ Phong exponent p ↔ Blinn–Phong exponent p_h: the folk rules.

α is the Beckmann width; renderers apply the same rules to GGX.  Near the lobe's peak every
one of these distributions is a Gaussian in an angle, and the rules match the Gaussians' widths:

* Blinn–Phong: D_Blinn ∝ cos^{p_h} θ_h ≈ exp(−p_h θ_h²/2) against Beckmann's
  D ∝ exp(−tan²θ_h/α²) ≈ exp(−θ_h²/α²) gives α = √(2/(p_h + 2)) (Walter et al. 2007,
  "Microfacet models for refraction through rough surfaces", eq. 33), so p_h = 2/α² − 2
  (:func:`blinn_phong_exponent`);
* Phong lobe around the mirror direction, cos^p α_R with α_R the angle to the mirror
  direction: the outgoing angle is about twice the half-vector angle θ_h, so
  cos^p α_R ≈ exp(−p α_R²/2) = exp(−2p θ_h²), the Blinn–Phong lobe with p_h = 4p.  Walter's
  rule with the microfacet exponent 4p gives α = √(2/(4p + 2)) (:func:`beckmann_alpha`,
  ≈ 1/√(2p) for large p), and its inverse p = p_h/4 = (1/α² − 1)/2 (:func:`phong_exponent`).

Users: the bench's Cornell box gives ``roughplastic`` the α matching phong's exponent
(:mod:`phonglab.bench.cornell`); ``phonglab fit`` starts from the Phong-lobe rule and its table
prints both rules beside the fitted exponent (:mod:`phonglab.fit`).
"""

from __future__ import annotations

import math


def beckmann_alpha(exponent: float) -> float:
    r"""Beckmann roughness α = √(2/(4p + 2)) whose highlight matches the Phong lobe cos^p α_R."""
    return math.sqrt(2.0 / (4.0 * exponent + 2.0))


def phong_exponent(alpha: float) -> float:
    """The Phong-lobe folk rule p = (1/α² − 1)/2 (inverse of :func:`beckmann_alpha`)."""
    return 0.5 * (1.0 / alpha ** 2 - 1.0)


def blinn_phong_exponent(alpha: float) -> float:
    """The Blinn–Phong folk rule p_h = 2/α² − 2 (inverse of α = √(2/(p_h + 2)))."""
    return 2.0 / alpha ** 2 - 2.0
