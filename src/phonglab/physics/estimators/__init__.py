r"""Monte Carlo estimators of the reflection equation at one surface point, and their exact values.

The quantity estimated is the radiance reflected towards ω_i (Mitsuba's ``si.wi``,
local shading frame, normal +Z) by a BSDF lit by a light of radiance L(ω_o)::

    L_r(ω_i) = ∫_{H²} f_r(ω_i, ω_o) L(ω_o) cos θ_o dω_o = ∫ eval(ω_i, ω_o) L(ω_o) dω_o

(Mitsuba's ``eval`` already carries cos θ_o).  Two lights are offered:

* ``constant``: L ≡ L_e over the whole sphere (a white furnace); L_r = L_e · albedo(ω_i).
* ``disk``: a distant disk light (a sun) of radiance L_e filling the cone of half-angle δ
  around the mirror direction R(ω_i) = 2(N·ω_i)N − ω_i, so the highlight sees it;
  solid angle Ω = 2π(1 − cos δ).

Estimators, each with N independent samples ω_k and the per-sample value X_k
(the estimate is the sample mean, its standard error s/√N with s the sample
standard deviation)::

    uniform   ω ~ uniform hemisphere, p = 1/(2π)          X = eval·L / p
    cosine    ω ~ cos θ/π (Malley)                        X = eval·L / p
    bsdf      ω, w = bsdf.sample(...) (the plugin's own)  X = w·L           (w = eval/pdf)
    light     disk: ω ~ uniform in the cone, p = 1/Ω;      X = eval·L_e / p
              constant: ω ~ uniform sphere, p = 1/(4π)    (the constant emitter's own sampling)
    mis       N/2 pairs (one bsdf + one light sample), power heuristic β = 2 [Veach 1997, §9.2]:
              X = f_b L_b/p_b · p_b²/(p_b²+p_l(ω_b)²) + f_l L_e/p_l · p_l²/(p_l²+p_b(ω_l)²)
    mis_optimal  pilot-chosen allocation n_b + n_l = N − M and optimal weights (:mod:`.optimal_mis`)

so every estimator draws N directions in total (MIS's N/2 pairs keep equal sample
counts; its standard error comes from the N/2 pair values).

One home per part:

* :mod:`.problem`      :class:`Problem` (BSDF, incidence, light), :class:`Estimate` (the
  record of S estimates), :data:`METHODS`;
* :mod:`.exact`        exact values by float64 quadrature (closed form in φ, Gauss–Legendre);
* :mod:`.kernel`       what every Dr.Jit kernel shares: the light, the integrand, the random
  streams, per-row float64 sums, JIT statistics;
* :mod:`.iid`          the five estimators with i.i.d. samples (uniform ... mis);
* :mod:`.optimal_mis`  ``mis_optimal``: the pilot, the allocation and weights, the main stage;
* :mod:`.reflection`   :class:`ReflectionEstimators`, which runs any of them on a problem.

References: E. Veach, *Robust Monte Carlo Methods for Light Transport Simulation*,
PhD thesis, Stanford 1997, ch. 9; M. Pharr, W. Jakob, G. Humphreys, *Physically
Based Rendering*, 4th ed., §2.2 (importance sampling) and §2.2.3 (MIS).
"""

from .exact import QUAD_NODES, QUAD_PANELS, clipped_cosine_mean, exact_normal_incidence, exact_value
from .kernel import Integrand, KernelLight, kernel_stats
from .optimal_mis import (ALLOCATIONS, PILOT_FRACTION, PILOT_MAX, PURE_PREFERENCE,
                          choose_allocation, solve_allocation, weighted_moments)
from .problem import IID_METHODS, LIGHTS, METHODS, Estimate, Problem
from .reflection import ReflectionEstimators

__all__ = ["ALLOCATIONS", "IID_METHODS", "LIGHTS", "METHODS", "PILOT_FRACTION", "PILOT_MAX",
           "PURE_PREFERENCE", "QUAD_NODES", "QUAD_PANELS", "Estimate", "Integrand", "KernelLight",
           "Problem", "ReflectionEstimators", "choose_allocation", "clipped_cosine_mean",
           "exact_normal_incidence", "exact_value", "kernel_stats", "solve_allocation",
           "weighted_moments"]
