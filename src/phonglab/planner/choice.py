r"""Step 5 of the plan: the transport model and the sampling that reach E in the least time.

Once the depth d and the uniform spp N of the ``path`` integrator are known (steps 2-3), the
planner prices every configuration that is **exact** for the same target — the same expected
image at depth d — and keeps the fastest, with the reason:

* **Models** (only when d = 2: one bounce is all the target needs).  Direct-only transport
  is ``path`` at ``max_depth`` 2 itself; Mitsuba's ``direct`` integrator (directly seen
  emitters plus emitter and BSDF sampling with MIS) computes exactly the same paths and was
  measured no faster (:data:`DIRECT_VS_PATH`), so it is not priced (a pilot render and a JIT
  compilation each).  ``whitted`` in radiance units (phonglab's integrator:
  ``f_r cos θ I/r²`` per light, a shadow ray each) is term for term ``path`` at depth 2 when
  every emitter is a delta light (point, spot, directional: ``mi.EmitterFlags.Delta*``) —
  there is then no light to sample but the deterministic one, and a pixel's only noise is
  where its samples land (antialiasing).  Each candidate is rendered like the pilot
  (:meth:`.pilot.Pilot.measure_model`): its relative noise n_m(1) and its time model
  T_m = a_m + b_m·spp; it needs N_m = ⌈n_m(1)² / (E² − b²)⌉ samples.

* **Sampling.**  Uniform: N_m samples everywhere.  Adaptive (:mod:`phonglab.engine.adaptive`):
  with v_p the pilot's per-pixel relative variance of one sample (:attr:`.pilot.Pilot.
  variance_maps`), guarded as the renderer guards it (v ← max(v, 5×5 mean)), the Neyman
  allocation needs N_p = max(√v_p · mean √v / (E² − b²), MIN_SPP) samples, on average
  N̄ = mean N_p; the predicted *gain* is N_m / N̄ (at most mean v / (mean √v)², the
  unguarded optimum).  Its time is b_m·N̄ plus :data:`ADAPTIVE_PASSES` passes of a_m and of
  the host's per-pass work (:data:`HOST_SECONDS_PER_PIXEL`, measured: developing the image,
  the variance estimate and the allocation, ~0.4 µs per pixel and pass at 128²).  Adaptive is chosen when it is
  predicted at least :data:`ADAPTIVE_MARGIN` faster than uniform: a noisy v map can only
  mislead it by that much.

* **Sampler.**  The scene's ``independent`` sampler draws every dimension of every sample at
  random; Mitsuba's ``multijitter`` (correlated multi-jittered sampling, Kensler 2013)
  stratifies each 2D projection of a pixel's samples — the pixel position, the first light
  sample, the first BSDF sample — and stays unbiased.  The pilot measures its gain g (the
  ratio of relative variances at equal samples, :func:`.pilot.stratification_gain`, from
  the weights render, drawn with it) and the uniform option with it needs ⌈N/g⌉ samples,
  laid out by :func:`stratified_layout` in passes of a count whose stratification grid has
  power-of-two sides (:data:`CHEAP_PASS_SPP`), at :data:`STRATIFIED_COST` times the time per
  sample.  It is chosen when it is the fastest; adaptive sampling keeps ``independent`` (its
  passes give pixels unequal counts, which a per-pixel stratification would need to know ahead).

The predictions are steady-state times (JIT compilation excluded), as in step 4.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import mitsuba as mi
import numpy as np

from ..engine.adaptive import MIN_SPP, NEIGHBOURHOOD
from ..engine.wavefront import window_mean
from ..engine.scenes import SceneInfo, inspect_scene
from .pilot import STRATIFIED_COST, Pilot

#: Passes an adaptive render typically takes (pilot and 2-4 more: measured on the bench scenes).
ADAPTIVE_PASSES = 4
#: Host work per pixel and pass of an adaptive render (image, variance, allocation): 6 ms a
#: pass at 128² (gray_direct, median of 7), rounded up.
HOST_SECONDS_PER_PIXEL = 5e-7
#: Adaptive must be predicted this much faster than uniform to be chosen.
ADAPTIVE_MARGIN = 1.15
#: Time of Mitsuba's ``direct`` integrator over ``path`` at max_depth 2, equal error (gray_direct,
#: 64², 80 spp, priced by this module's pilot: 0.341 s vs 0.350 s; direct adaptive 0.226 s vs
#: path adaptive 0.228 s): no gain worth a pilot render, so ``direct`` is not priced.
DIRECT_VS_PATH = 0.97


@dataclass
class Option:
    """One priced configuration."""

    model: str          #: 'path', 'direct' or 'whitted'
    sampling: str       #: 'uniform' or 'adaptive'
    spp: float          #: samples per pixel (mean for adaptive)
    seconds: float      #: predicted steady-state time
    noise1: float       #: relative noise of one sample, n(1)
    sampler: str = "independent"  #: Mitsuba sampler of a uniform render
    passes: int = 0     #: passes of a uniform render (0: the planner's default)
    reuses: bool = False  #: combined with the pilot's reusable renders

    def label(self) -> str:
        extra = f" ({self.sampler})" if self.sampler != "independent" else ""
        reuse = " + the pilot's samples" if self.reuses else ""
        return f"{self.model}, {self.sampling}{extra}{reuse}"


#: The stratified sampler priced against ``independent`` (Mitsuba's ``multijitter``).
STRATIFIED = "multijitter"
#: Pass sizes at which ``multijitter`` costs no more than :data:`STRATIFIED_COST`.  Its grid is
#: ⌊√n⌋ rows by ⌈n/⌊√n⌋⌉ columns (``src/samplers/multijitter.cpp``, ``set_sample_count``)
#: and each 2D sample permutes the sample index, row and column with ``permute_kensler``
#: (``include/mitsuba/core/random.h``), a cycle-walking loop that redraws until the value
#: falls below the count: one round when the count is a power of two, several for the
#: slowest lane of a SIMD packet otherwise.  So n, its rows and its columns must all be
#: powers of two: 8 (2×4), 16, 64, 256, ... (4^k from 16 on; 32 becomes 5×7 = 35).
#: Measured per sample against ``independent`` (128², medians of 5): gray_direct (mono,
#: depth 2) 1.07x at 8, 1.06x at 16, 1.08x at 64 but 1.35x at 35 and 1.52x at 132;
#: cornell_phong (rgb, depth 10) 1.05x at 8, 1.06x at 16, 1.07x at 64, 1.32x at 35, 1.45x at 132.
CHEAP_PASS_SPP = (8, 16, 64, 256, 1024, 4096, 16384, 65536)
#: Samples per pass of a planned render combined with the pilot's, where it has that many:
#: each pass costs a launch and a copy (a ms or two at 128²), and its standard error needs
#: only two of them.
MIN_PASS_SPP = 4
#: Passes of a planned stratified render: at least 2 (a standard error), at most 8.
MIN_STRATIFIED_PASSES, MAX_STRATIFIED_PASSES = 2, 8


def stratified_layout(n: int, min_pass: int, a: float, b: float) -> tuple[int, int]:
    """(passes, samples per pass) of a :data:`STRATIFIED` render of at least ``n`` samples
    per pixel: 2 to 8 passes of a :data:`CHEAP_PASS_SPP` count >= ``min_pass`` (the pilot's
    pass size, at which the gain was measured), the layout of least predicted time
    ``passes·a + b·samples`` (ties: the larger passes, which stratify more).  Beyond 8 passes
    of the largest count: 8 equal passes (the sampler rounds each up)."""
    best = None
    for s in (c for c in CHEAP_PASS_SPP if c >= min_pass):
        p = max(MIN_STRATIFIED_PASSES, -(-int(n) // s))
        if p > MAX_STRATIFIED_PASSES:
            continue
        key = (p * a + b * p * s, -s)
        if best is None or key < best[0]:
            best = (key, (p, s))
    if best is None:
        return MAX_STRATIFIED_PASSES, -(-int(n) // MAX_STRATIFIED_PASSES)
    return best[1]


def delta_lights_only(scene) -> bool:
    """Every emitter of the loaded scene is a point, spot or directional light."""
    delta = int(mi.EmitterFlags.DeltaPosition) | int(mi.EmitterFlags.DeltaDirection)
    emitters = scene.emitters()
    return bool(emitters) and all(int(e.flags()) & delta for e in emitters)


def model_dict(model: str, depth: int, scene, params: dict | None = None) -> dict:
    """The ``mi.load_dict`` dictionary of a model's integrator, keeping the scene's
    hide_emitters (``scene``: a :class:`SceneInfo`, or a scene file read with ``params``)."""
    info = scene if isinstance(scene, SceneInfo) else inspect_scene(scene, **(params or {}))
    hide = info.integrator_props.get("hide_emitters", "false").lower() == "true"
    if model == "direct":
        return {"type": "direct", "hide_emitters": hide}
    if model == "whitted":
        return {"type": "whitted", "units": "radiance", "max_depth": depth,
                "hide_emitters": hide}
    raise ValueError(f"unknown model {model!r}")


def adaptive_spp(vmap: np.ndarray, budget2: float) -> float:
    """Mean samples per pixel the adaptive renderer's allocation predicts (module docstring)."""
    v = np.maximum(vmap, window_mean(vmap, NEIGHBOURHOOD))
    root = np.sqrt(v)
    want = root * root.mean() / budget2
    return float(np.mean(np.maximum(np.ceil(want), MIN_SPP)))


def price(pilot: Pilot, model: str, noise1: float, vmap: np.ndarray, time_model, budget2: float,
          pixels: int, passes: int) -> list[Option]:
    """The uniform and adaptive options of one model."""
    a, b = time_model
    n = max(1, math.ceil(noise1 ** 2 / budget2)) if noise1 > 0 else 1
    options = [Option(model, "uniform", n, passes * a + b * n, noise1)]
    mean_spp = adaptive_spp(vmap, budget2)
    host = HOST_SECONDS_PER_PIXEL * pixels
    options.append(Option(model, "adaptive", mean_spp,
                          b * mean_spp + ADAPTIVE_PASSES * (a + host), noise1))
    return options


def credited_spp(noise1: float, budget2: float, credit: float) -> int:
    """Samples per pixel a uniform render of relative noise ``noise1`` at 1 spp needs when the
    pilot's reusable renders bring the precision ``credit`` (Σ n_j/V_j,
    :func:`phonglab.engine.render.combine_renders`): the combination's relative variance
    1/(credit + n/noise1²) must be <= E² − b², so n = ⌈noise1² (1/(E² − b²) − credit)⌉,
    at least 2 (a render of two passes: its standard error weighs it)."""
    return max(2, math.ceil(noise1 ** 2 * (1.0 / budget2 - credit))) if noise1 > 0 else 2


def reused_path(pilot: Pilot, depth: int, noise1: float, budget2: float, credit: float,
                passes: int) -> Option:
    """Uniform ``path`` (independent sampler) combined with the pilot's reusable renders."""
    a, b = pilot.time_model(depth)
    n = credited_spp(noise1, budget2, credit)
    p = max(2, min(passes, n // MIN_PASS_SPP))   # the combination needs a standard error
    return Option("path", "uniform", n, p * a + b * n, noise1, passes=p, reuses=True)


def price_stratified(pilot: Pilot, depth: int, noise1: float, budget2: float,
                     reasons: list[str], credit: float = 0.0) -> Option:
    """Uniform ``path`` with the :data:`STRATIFIED` sampler: ⌈N/g⌉ samples (less what the
    pilot's reusable renders bring, ``credit``), its own timing."""
    gain = pilot.gain
    # passes of at least the pilot's pass size: the gain was measured there, and smaller
    # passes stratify less (gray_direct at 32²: 2 spp where 4 independent ones were needed
    # missed E by 1.3x)
    needed = credited_spp(noise1 / math.sqrt(max(gain, 1e-9)), budget2, credit)
    a, b = pilot.time_model(depth)
    b *= STRATIFIED_COST
    passes, per_pass = stratified_layout(max(2 * pilot.stratified_pass_spp, needed),
                                         pilot.stratified_pass_spp, a, b)
    n = passes * per_pass
    reasons.append(f"sampler: {STRATIFIED} (stratified) measured {gain:.2f}x lower variance "
                   f"than independent at equal samples ({pilot.stratified_pass_spp} spp "
                   f"passes, full depth), so uniform needs {needed} spp instead of "
                   f"{credited_spp(noise1, budget2, credit)}: {passes} passes of {per_pass} "
                   f"(a count {STRATIFIED} permutes without redraws)")
    return Option("path", "uniform", n, passes * a + b * n, noise1 / math.sqrt(max(gain, 1e-9)),
                  sampler=STRATIFIED, passes=passes, reuses=credit > 0)


def choose(pilot: Pilot, depth: int, bias: float, target_error: float, uniform_path: Option,
           pixels: int, passes: int, reasons: list[str], credit: float = 0.0) -> Option:
    """Step 5: the fastest exact option (module docstring), with its reasons appended.
    ``credit``: the precision the pilot's reusable renders bring to a uniform ``path`` render
    at ``depth`` (:meth:`.pilot.Pilot.reusable`), which its uniform options count."""
    budget2 = target_error ** 2 - bias ** 2
    vmap = pilot.variance_maps[depth]
    options = [uniform_path]
    if credit > 0:
        options = [reused_path(pilot, depth, uniform_path.noise1, budget2, credit, passes)]
    path_adaptive = price(pilot, "path", uniform_path.noise1, vmap, pilot.time_model(depth),
                          budget2, pixels, passes)[1]
    options.append(path_adaptive)
    if depth == 2:
        reasons.append("direct-only transport: path at max_depth 2 is that model (Mitsuba's "
                       "'direct' integrator computes the same paths and measured no faster: "
                       f"{DIRECT_VS_PATH:g}x path's time at equal error on gray_direct), so it "
                       "is not priced again")
        if delta_lights_only(pilot.scene):
            integ = mi.load_dict(model_dict("whitted", depth, pilot.info))
            noise1, mvmap, tm = pilot.measure_model(integ)
            options += price(pilot, "whitted", noise1, mvmap, tm, budget2, pixels, passes)
        else:
            reasons.append("whitted (radiance units) not considered: not every emitter is a "
                           "point, spot or directional light, and whitted lights surfaces "
                           "with those alone")
    else:
        reasons.append(f"no cheaper exact model: direct and whitted compute paths of at "
                       f"most 2 segments, and this scene needs depth {depth}")
    if pilot.stratified is not None:
        options.append(price_stratified(pilot, depth, uniform_path.noise1, budget2, reasons,
                                        credit))
    best_uniform = min((o for o in options if o.sampling == "uniform"), key=lambda o: o.seconds)
    best_adaptive = min((o for o in options if o.sampling == "adaptive"), key=lambda o: o.seconds)
    gain = uniform_path.spp / path_adaptive.spp
    reasons.append(f"sampling: the pilot's per-pixel variance predicts adaptive sampling "
                   f"needs {path_adaptive.spp:.1f} spp on average against {uniform_path.spp} "
                   f"uniform (gain {gain:.2f}x in samples; unguarded optimum "
                   f"{_optimum(vmap):.2f}x)")
    ranked = sorted(options, key=lambda o: o.seconds)
    reasons.append("priced (steady state): " + "; ".join(
        f"{o.label()} {o.spp:.1f} spp {o.seconds:.3g} s" for o in ranked))
    best = best_uniform
    if best_adaptive.seconds * ADAPTIVE_MARGIN < best_uniform.seconds:
        best = best_adaptive
    elif best_adaptive.seconds < best_uniform.seconds:
        reasons.append(f"adaptive is predicted less than {ADAPTIVE_MARGIN:g}x faster: uniform "
                       f"kept")
    reasons.append(f"chosen: {best.label()}, {best.spp:.1f} spp, about {best.seconds:.3g} s "
                   f"({uniform_path.seconds / max(best.seconds, 1e-12):.2f}x faster than "
                   f"uniform path predicted)")
    return best


def _optimum(vmap: np.ndarray) -> float:
    """mean v / (mean √v)²: the sample ratio of uniform to the ideal allocation."""
    root = np.sqrt(np.maximum(vmap, 0.0))
    return float(np.mean(vmap) / max(np.mean(root) ** 2, 1e-300))
