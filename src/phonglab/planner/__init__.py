r"""The planner: the leanest variant, path depth and sample count that meet an error target.

``plan(scene, PlanOptions(target_error=E))`` answers "how should this scene be rendered to reach a relative
RMSE of E, and at what cost?" in four steps, each with a reason the user can read
(:attr:`Plan.reasons`):

1. **Variant**, from the scene file alone (:func:`phonglab.engine.scenes.inspect_scene`, ElementTree
   with the scene's ``<default>`` values and ``$name`` substitutions resolved): ``mono`` when
   every reflectance, texture and emitter is gray (equal RGB components, or a single-valued
   ``<spectrum>``), ``rgb`` otherwise, ``spectral`` only when the scene carries spectral data (a
   ``<spectrum>`` with a wavelength list, a spectral file, a ``blackbody``, a conductor's
   measured ``material``); never polarized unless asked.  The JIT backend is the best one that
   works here (:func:`phonglab.runtime.available_backend`): ``cuda`` (Dr.Jit finds a CUDA
   device) > ``llvm`` (a usable libLLVM) > ``scalar``; :func:`phonglab.runtime.variant_for`
   names the variant.

2. **max_depth**, from a pilot render.  Mitsuba's ``path`` integrator with ``max_depth = d``
   adds the contributions of paths of at most d segments.  The pilot renders ``P`` passes at
   full depth (``max_depth = -1``: unbounded, ended by Russian roulette, unbiased) and at
   candidate depths with the *same seeds*, so pass k of depth d and of full depth follow the same
   paths up to d segments and their difference ``D_k = full_k − depth_k`` is the energy carried
   by deeper bounces, with little noise.  The relative RMS bias the metric would see is, with
   means over every pixel and channel::

       b(d)² = mean[ ((mean_k D_k)² − var_k(D_k)/P) · w ],   w ≈ 1/(r² + ε)

   (E[(mean_k D_k)²] = (E D)² + var(D)/P, so the subtraction makes it an unbiased estimate of
   the squared mean and pure noise does not pass for bias).  The weights w come from a second
   full-depth pilot with other seeds, independent of D_k: with r̂ its pass mean and se² the
   squared standard error of r̂, the delta method gives E[1/(r̂² + ε)] ≈ (1 + (3r² − ε)·se²/
   (r² + ε)²)/(r² + ε), and w = 1/(r̂² + ε) divided by that factor (kept >= 1/2) removes the
   second-order bias of the plug-in weight (:func:`phonglab.planner.pilot._weights`).  At
   depths 1 to 4 the second pilot's own depth images (the same one-render ladder) give a
   second estimate, weighted by the first pilot's w, pooled with the first by samples: where
   deeper bounces are rare a pixel's term needs two passes that found them, and a small pilot
   alone can miss them (:mod:`phonglab.planner.pilot`, nb_sphere_row).  The
   plan takes the smallest d with ``b(d) <= BIAS_FRACTION · E`` (candidates 1, 2, 3, 4, 6, 8,
   12, ... then bisection, b being non-increasing in d, when the bisection's render can pay
   for itself: :meth:`.pilot.Pilot.gap_value`).  Delta chains (glass, mirrors) need
   no special rule: the energy they carry shows in D_k, so the search follows them as deep as
   they carry energy; the scene's delta BSDFs are listed in the reasons.

3. **spp**, from the pilot's per-pixel variance at the chosen depth.  With ``σ²`` the variance
   of one sample (``P`` pass means of ``s`` samples each: ``σ² = s · var_k(pass_k)``), N samples
   per pixel leave the noise ``n(N)² = mean[σ² · w] / N``.  The plan takes the smallest N with
   ``b(d)² + n(N)² <= E²``; the predicted error is ``√(b(d)² + n(N)²)``.

4. **Time**, steady state (JIT compile excluded): the pilot times one-pass renders of ``s``
   and ``4s`` samples per pixel at the chosen depth, alternating, and fits
   ``T(spp) = a + b·spp`` (medians); a render of N samples in ``p`` passes is predicted to take
   ``p·a + b·N``.

E is phonglab's error target, defined once in :mod:`phonglab.engine.metrics`: the total relative RMSE
(:func:`phonglab.engine.metrics.relative_rmse`, ε = 0.01) against the converged full-depth image
(:func:`phonglab.engine.references.reference`), bias included, E² = b² + n²; the achieved error is
measured with the same definition (:func:`phonglab.planner.execute.error_report`).  Monte
Carlo noise falls as ``1/√N`` (M. Pharr, W. Jakob, G. Humphreys, *Physically Based
Rendering*, 4th ed., §2.1.4, and §2.2.4 on Russian roulette).

Modules: :mod:`.planning` (:class:`PlanOptions`, :class:`Plan` and its records, :func:`plan`
and its steps), :mod:`.execute` (:func:`render_plan`: the plan's render, its error report and
what it did, for the CLI and the bench),
:mod:`.pilot` (the pilot renders, depth search, weights, noise and time model), :mod:`.ladder`
(one render that gives the image at several depths), :mod:`.benchmark` (the table of
``scripts/planner_bench.py``).
"""

from .benchmark import benchmark_table
from .execute import render_plan
from .pilot import (BIAS_FRACTION, DEPTH_LADDER, EPS, PILOT_PASSES, PILOT_SEED, PILOT_SPP,
                    DepthSample, Pilot)
from .planning import MAX_SECONDS, Plan, PlanOptions, plan, render_passes

__all__ = ["BIAS_FRACTION", "DEPTH_LADDER", "EPS", "MAX_SECONDS", "PILOT_PASSES", "PILOT_SEED",
           "PILOT_SPP", "DepthSample", "Pilot", "Plan", "PlanOptions", "benchmark_table", "plan",
           "render_passes", "render_plan"]
