r"""The planner: the leanest variant, path depth and sample count that meet an error target.

``plan(scene, target_error=E)`` answers "how should this scene be rendered to reach a relative
RMSE of E, and at what cost?" in three steps, each with a reason the user can read
(:attr:`Plan.reasons`):

1. **Variant**, from the scene file alone (:func:`inspect_scene`, ElementTree with the scene's
   ``<default>`` values and ``$name`` substitutions resolved): ``mono`` when every reflectance,
   texture and emitter is gray (equal RGB components, or a single-valued ``<spectrum>``),
   ``rgb`` otherwise, ``spectral`` only when the scene carries spectral data (a ``<spectrum>``
   with a wavelength list, a spectral file, a ``blackbody``, a conductor's measured ``material``);
   never polarized unless asked.  The JIT backend is the best one that works here:
   ``cuda`` (Dr.Jit finds a CUDA device) > ``llvm`` (a usable libLLVM) > ``scalar``.

2. **max_depth**, from a pilot render.  Mitsuba's ``path`` integrator with ``max_depth = d``
   adds the contributions of paths of at most d segments.  The pilot renders ``P`` passes at
   full depth (``max_depth = -1``: unbounded, ended by Russian roulette, unbiased) and at
   candidate depths with the *same seeds*, so pass k of depth d and of full depth follow the same
   paths up to d segments and their difference ``D_k = full_k − depth_k`` is the energy carried
   by deeper bounces, with little noise.  The relative RMS bias the metric would see is::

       b(d)² = mean_pixels[ ((mean_k D_k)² − var_k(D_k)/P) / (r² + ε) ]

   (the subtraction makes it an unbiased estimate of the squared mean, so pure noise does not
   pass for bias; the weights 1/(r² + ε) come from a second full-depth pilot with other seeds,
   see :func:`_weights`).  The plan takes the smallest d with
   ``b(d) <= BIAS_FRACTION · E`` (candidates 1, 2, 3, 4, 6, 8, 12, ... then bisection, b being
   non-increasing in d).  Delta chains (glass, mirrors) need no special rule: the energy they
   carry shows in D_k, so the search follows them as deep as they carry energy; the scene's
   delta BSDFs are listed in the reasons.

3. **spp**, from the pilot's per-pixel variance at the chosen depth.  With ``σ²`` the variance
   of one sample (``P`` pass means of ``s`` samples each: ``σ² = s · var_k(pass_k)``), N samples
   per pixel leave the noise ``n(N)² = mean_pixels[σ² / (r² + ε)] / N``.  The plan takes the
   smallest N with ``b(d)² + n(N)² <= E²``; the predicted error is ``√(b(d)² + n(N)²)``.

The error is phonglab's relative error, :func:`phonglab.metrics.relative_rmse` with
ε = 0.01: ``E = √mean((x − r)² / (r² + ε))`` over every pixel and channel, ``r`` the
converged full-depth image (:func:`phonglab.references.reference`); the same definition is
used when the achieved error is measured (:func:`phonglab.metrics.errors` with the
reference's standard error subtracted).  Monte Carlo noise falls as ``1/√N``, so E² is the sum of the
squared depth bias and the variance term: MSE = bias² + variance (E. Veach, *Robust Monte Carlo
Methods for Light Transport Simulation*, PhD thesis, Stanford 1997, §2.4.3; M. Pharr, W. Jakob,
G. Humphreys, *Physically Based Rendering*, 4th ed., §2.1.4, and §2.2.4 on Russian roulette).

The predicted time is steady state (JIT compile excluded): the pilot times renders of ``s`` and
``4s`` samples per pixel at the chosen depth, alternating, and fits ``T(spp) = a + b·spp``
(medians); a render of N samples in ``p`` passes is predicted to take ``p·a + b·N``.
"""

from __future__ import annotations

import dataclasses
import json
import math
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .. import render
from ..errors import PhonglabError
from ..metrics import REL_EPS
from ..runtime import available_backend, quiet_mitsuba, variant_for
from ..scenes import inspect_scene, load_scene, path_integrator

#: ε of the relative error E = √mean((x − r)²/(r² + ε)) (phonglab.metrics.relative_rmse).
EPS = REL_EPS
#: The depth bias may use at most this fraction of the target error (b(d) <= BIAS_FRACTION · E).
BIAS_FRACTION = 0.25
#: Candidate depths, searched in order, then bisected between the last failing and first passing.
DEPTH_LADDER = (1, 2, 3, 4, 6, 8, 12, 16, 24, 32, 48, 64)
#: Pilot: total samples per pixel, split into this many passes of equal size (same seeds per depth).
PILOT_SPP = 64
PILOT_PASSES = 8
#: Seed of the pilot (pass k uses seed·1_000_003 + k, as render_scene does); renders use seed 0.
PILOT_SEED = 1

_PASSTHROUGH = {"twosided", "mask", "bumpmap", "normalmap", "blendbsdf"}


# --------------------------------------------------------------------------------------------
# The plan
# --------------------------------------------------------------------------------------------

@dataclass
class DepthSample:
    """Pilot statistics at one max_depth."""

    depth: int
    bias: float            #: b(d): relative RMS of the omitted (deeper) contribution
    energy_omitted: float  #: Σ(full − depth) / Σ full over the image: energy of deeper bounces
    noise_per_sample: float  #: √mean(σ²/(r+eps)²): relative noise of a 1-spp image


@dataclass
class Plan:
    """A rendering configuration for a target error, with its predictions and reasons."""

    scene: str
    target_error: float
    variant: str
    backend: str
    color: str
    max_depth: int
    spp: int
    passes: int                #: passes the render uses (for the standard error)
    predicted_error: float     #: √(bias² + noise²)
    predicted_bias: float      #: b(max_depth)
    predicted_noise: float     #: noise at spp
    predicted_seconds: float   #: steady-state render time (JIT compile excluded)
    seconds_per_sample: float  #: b of T = a + b·spp, per pixel sample
    seconds_per_pass: float    #: a of T = a + b·spp
    resolution: tuple[int, int]
    params: dict[str, Any]     #: scene parameters the plan was made with (res=..., ...)
    pilot_spp: int
    pilot_seconds: float       #: wall time of the whole pilot (inspection, renders, timing)
    depths: list[DepthSample] = field(default_factory=list)
    reasons: list[str] = field(default_factory=list)
    overrides: dict[str, Any] = field(default_factory=dict)

    def to_dict(self) -> dict[str, Any]:
        d = dataclasses.asdict(self)
        d["resolution"] = list(self.resolution)
        return d

    def to_json(self, indent: int | None = 2) -> str:
        return json.dumps(self.to_dict(), indent=indent)

    def render_kwargs(self) -> dict[str, Any]:
        """Keyword arguments of :func:`phonglab.render.render_file` that apply the plan."""
        return {"spp": self.spp, "variant": self.variant, "max_depth": self.max_depth,
                "passes": self.passes}

    def summary(self) -> str:
        """The plan and its reasons, as the CLI prints them."""
        w, h = self.resolution
        lines = [
            f"plan for {self.scene} ({w}x{h}), target relative RMSE {self.target_error:g} "
            f"(eps {EPS:g}):",
            f"  variant   {self.variant}",
            f"  max_depth {self.max_depth}",
            f"  spp       {self.spp}  ({self.passes} passes)",
            f"  predicted error {self.predicted_error:.4g} (depth bias {self.predicted_bias:.3g}, "
            f"noise {self.predicted_noise:.4g}); time {self.predicted_seconds:.3g} s "
            f"steady state ({self.seconds_per_sample * 1e9:.3g} ns per sample + "
            f"{self.seconds_per_pass * 1e3:.3g} ms per pass); pilot took "
            f"{self.pilot_seconds:.2f} s",
            "because:",
        ]
        lines += [f"  - {r}" for r in self.reasons]
        return "\n".join(lines)

    def __str__(self) -> str:
        return self.summary()


def render_passes(spp: int) -> int:
    """Passes a planned render uses: 8 (or spp when fewer), at least 2 so it has a stderr."""
    return max(1, min(int(spp), 8)) if spp >= 2 else 1


def _passes(scene, integrator, spp_per_pass: int, passes: int, seed: int) -> render.RenderResult:
    """``passes`` independent passes of ``spp_per_pass`` samples, every pass image kept."""
    return render.render_scene(scene, spp_per_pass * passes, seed=seed, passes=passes,
                               integrator=integrator, keep_passes=True)


def _time_model(scene, integrator, spp_small: int, repeats: int = 3) -> tuple[float, float]:
    """(a, b) of T(spp) = a + b·spp from alternating renders of spp_small and 4·spp_small."""
    import drjit as dr
    import mitsuba as mi

    spp_big = 4 * spp_small
    t_small, t_big = [], []
    for k in range(repeats):
        for spp, bucket in ((spp_small, t_small), (spp_big, t_big)):
            t0 = time.perf_counter()
            img = mi.render(scene, spp=spp, seed=7 + k, integrator=integrator)
            dr.eval(img)
            np.array(img)
            bucket.append(time.perf_counter() - t0)
    ts, tb = float(np.median(t_small)), float(np.median(t_big))
    b = (tb - ts) / (spp_big - spp_small)
    if b <= 0:  # timing noise swamped the difference: charge everything per sample
        return 0.0, tb / spp_big
    return max(ts - b * spp_small, 0.0), b


def _weights(passes_img: np.ndarray) -> np.ndarray:
    """Per-pixel weights ≈ 1/(r² + ε) of the relative MSE, from P pass images of an estimate of r.

    With r̂ the pass mean and se² its squared standard error, the delta method gives
    E[1/(r̂² + ε)] ≈ (1 + (3r² − ε)·se²/(r² + ε)²)/(r² + ε), so dividing by that factor
    removes the second-order bias a noisy r̂ would add (dark, noisy pixels would otherwise
    dominate).  The factor is kept >= 1/2: where se² is comparable to ε the expansion no
    longer holds and the uncorrected weight is the safer estimate.
    """
    r2 = passes_img.mean(axis=0) ** 2
    se2 = passes_img.var(axis=0, ddof=1) / passes_img.shape[0]
    q = r2 + EPS
    return 1.0 / q / np.maximum(1.0 + (3.0 * r2 - EPS) * se2 / (q * q), 0.5)


def plan(scene_path: str | Path, target_error: float = 0.01, *, pilot_spp: int = PILOT_SPP,
         pilot_passes: int = PILOT_PASSES, seed: int = PILOT_SEED,
         bias_fraction: float = BIAS_FRACTION, polarized: bool = False,
         variant: str | None = None, max_depth: int | None = None, spp: int | None = None,
         max_depth_cap: int = DEPTH_LADDER[-1], params: dict[str, Any] | None = None) -> Plan:
    """Plan the cheapest render of ``scene_path`` predicted to reach ``target_error``.

    Args:
        scene_path: scene file, or a name in ``scenes_xml/``.
        target_error: E, a relative RMSE (module docstring; ``0.01`` = 1 %).
        pilot_spp, pilot_passes: pilot samples per pixel and the passes they are split into.
        seed: pilot seed (the render that follows should use another; the CLI uses 0).
        bias_fraction: the depth bias may use this fraction of E.
        polarized: plan a polarized variant (never chosen otherwise).
        variant, max_depth, spp: fix that part of the plan (the predictions follow it).
        max_depth_cap: deepest finite depth tried; beyond it the plan uses -1 (unbounded).
        params: values for the scene's ``<default>`` entries (``{"res": 64}``).

    Returns:
        a :class:`Plan`.

    Raises:
        PhonglabError: bad target, unknown variant, a scene whose integrator is not ``path``.
    """
    import mitsuba as mi

    t_start = time.perf_counter()
    if not (isinstance(target_error, (int, float)) and math.isfinite(target_error)
            and 0 < target_error < 10):
        raise PhonglabError(f"target error must be a relative RMSE in (0, 10), e.g. 0.01 for "
                            f"1 %, got {target_error!r}.")
    if pilot_passes < 2 or pilot_spp < pilot_passes:
        raise PhonglabError(f"the pilot needs at least 2 passes of at least 1 spp, got "
                            f"pilot_spp={pilot_spp}, pilot_passes={pilot_passes}.")
    if spp is not None and spp < 1:
        raise PhonglabError(f"spp must be >= 1, got {spp}.")
    if max_depth is not None and (max_depth == 0 or max_depth < -1):
        raise PhonglabError(f"max_depth must be -1 (unbounded) or >= 1, got {max_depth}.")
    params = {k: v for k, v in (params or {}).items() if v is not None}
    info = inspect_scene(scene_path, **params)
    if info.integrator != "path":
        raise PhonglabError(f"{info.path}: the planner plans path-traced scenes, but this one "
                            f"uses the '{info.integrator}' integrator; use <integrator "
                            f"type=\"path\"> or render it with 'phonglab render' directly.")
    reasons: list[str] = []
    overrides = {k: v for k, v in (("variant", variant), ("max_depth", max_depth), ("spp", spp))
                 if v is not None}

    # 1. Variant.
    if variant is None:
        backend, backend_why = available_backend()
        color = info.color
        if color == "spectral":
            reasons.append("spectral: the scene carries spectral data: "
                           + "; ".join(info.spectral[:3]))
        elif color == "rgb":
            more = f" (and {len(info.colored) - 2} more)" if len(info.colored) > 2 else ""
            reasons.append("rgb: not every reflectance/emitter is gray: "
                           + "; ".join(info.colored[:2]) + more)
        else:
            reasons.append(f"mono: every reflectance, texture and emitter value is gray "
                           f"({info.gray_values} values, none coloured, no spectral data)")
        chosen, notes = variant_for(color, backend, polarized)
        reasons.append(f"backend {backend}: {backend_why}")
        reasons += notes
        if not polarized:
            reasons.append("not polarized: not asked for")
        variant = chosen
    else:
        if variant not in mi.variants():
            raise PhonglabError(f"unknown Mitsuba variant {variant!r}; choose one of "
                                f"{', '.join(mi.variants())}.")
        backend = variant.split("_")[0]
        color = "spectral" if "spectral" in variant else "mono" if "mono" in variant else "rgb"
        reasons.append(f"variant {variant}: given by the caller (the scene alone would need "
                       f"{info.color})")

    with quiet_mitsuba():
        scene = load_scene(info.path, variant, **params)
    film = scene.sensors()[0].film()
    resolution = (int(film.size()[0]), int(film.size()[1]))
    scene_spp = int(scene.sensors()[0].sampler().sample_count())

    # 2. Pilot at full depth: the reference the depth bias is measured against.
    s = pilot_spp // pilot_passes
    full = _passes(scene, path_integrator(-1, info), s, pilot_passes, seed).passes
    # The weights 1/(r + eps)² come from an independent full-depth pilot (other seeds): taken
    # from `full` itself they would shrink exactly where a rare bright sample inflates the
    # variance (a caustic firefly raises both), and the noise would be underestimated.
    indep = _passes(scene, path_integrator(-1, info), s, pilot_passes, seed + 1).passes
    weight = _weights(indep)
    total_energy = float(full.mean(axis=0).sum()) or 1.0
    samples: dict[int, DepthSample] = {}
    timings: dict[int, list[float]] = {}

    def noise_of(passes_img: np.ndarray) -> float:
        sigma2 = passes_img.var(axis=0, ddof=1) * s      # variance of one sample
        return math.sqrt(float(np.mean(sigma2 * weight)))

    def measure(d: int) -> DepthSample:
        if d not in samples:
            if d == -1:
                samples[d] = DepthSample(-1, 0.0, 0.0, noise_of(full))
            else:
                pilot = _passes(scene, path_integrator(d, info), s, pilot_passes, seed)
                imgs, times = pilot.passes, pilot.pass_seconds
                diff = full - imgs
                mean = diff.mean(axis=0)
                se2 = diff.var(axis=0, ddof=1) / pilot_passes
                bias2 = float(np.mean((mean * mean - se2) * weight))
                energy = float(mean.sum()) / total_energy
                samples[d] = DepthSample(d, math.sqrt(max(bias2, 0.0)),
                                         energy if abs(energy) > 1e-9 else 0.0, noise_of(imgs))
                timings[d] = times
        return samples[d]

    allowed = bias_fraction * target_error
    if max_depth is None:
        ladder = [d for d in DEPTH_LADDER if d <= max_depth_cap]
        failing, passing = 0, None
        for d in ladder:
            if measure(d).bias <= allowed:
                passing = d
                break
            failing = d
        if passing is None:
            depth = -1
            measure(-1)
            reasons.append(f"max_depth -1 (unbounded, Russian roulette): even depth "
                           f"{failing} omits a relative RMS {samples[failing].bias:.3g} > "
                           f"{bias_fraction:g} x E = {allowed:.3g}")
        else:
            while passing - failing > 1:
                mid = (passing + failing) // 2
                if measure(mid).bias <= allowed:
                    passing = mid
                else:
                    failing = mid
            depth = passing
            chosen_s = samples[depth]
            why = (f"max_depth {depth}: the smallest depth whose omitted contribution "
                   f"(deeper bounces: {100 * chosen_s.energy_omitted:.3g} % of the image's "
                   f"energy, relative RMS {chosen_s.bias:.3g}) is <= {bias_fraction:g} x E = "
                   f"{allowed:.3g}")
            if failing >= 1:
                f = samples[failing]
                why += (f"; depth {failing} omits {100 * f.energy_omitted:.3g} % "
                        f"(relative RMS {f.bias:.3g})")
            reasons.append(why)
        if info.delta_bsdfs:
            names = sorted(set(info.delta_bsdfs))
            reasons.append(f"delta BSDFs ({', '.join(names)}): their chains were followed as "
                           f"far as the pilot saw them carry energy (the depth search measures "
                           f"what deeper bounces add, delta paths included)")
    else:
        depth = max_depth
        measure(depth)
        reasons.append(f"max_depth {depth}: given by the caller; its omitted contribution is "
                       f"a relative RMS {samples[depth].bias:.3g}"
                       + (f" (more than the {allowed:.3g} the planner would allow)"
                          if samples[depth].bias > allowed else ""))
    chosen = samples[depth]

    # 3. spp from the variance at the chosen depth.
    bias = chosen.bias
    v1 = chosen.noise_per_sample ** 2
    if spp is None:
        budget2 = target_error ** 2 - bias ** 2
        if v1 == 0.0:
            n = 1
            reasons.append("spp 1: the pilot shows no variance at all at this depth")
        else:
            n = max(1, math.ceil(v1 / budget2))
            reasons.append(f"spp {n}: the pilot's per-pixel variance gives a relative noise of "
                           f"{chosen.noise_per_sample:.4g} at 1 spp, falling as 1/sqrt(spp); "
                           f"sqrt(E^2 - bias^2) = {math.sqrt(budget2):.4g} needs {n} spp "
                           f"(the scene's own spp is {scene_spp})")
    else:
        n = int(spp)
        reasons.append(f"spp {n}: given by the caller")
    noise = math.sqrt(v1 / n)
    predicted = math.sqrt(bias ** 2 + noise ** 2)
    if predicted > target_error * (1 + 1e-9):
        reasons.append(f"warning: the predicted error {predicted:.4g} misses the target "
                       f"{target_error:g} with the configuration given")

    # Steady-state time: T(spp) = a + b·spp at the chosen depth (kernel already compiled).
    integrator = path_integrator(depth, info)
    if depth not in timings:  # compile the kernel before timing
        _passes(scene, integrator, 1, 1, seed + 99)
    a, b = _time_model(scene, integrator, s)
    passes = render_passes(n)
    seconds = passes * a + b * n
    pixels = resolution[0] * resolution[1]
    reasons.append(f"time: {b / pixels * 1e9:.3g} ns per pixel sample + {a * 1e3:.3g} ms per "
                   f"pass, measured at this depth after JIT compilation, so {passes} passes "
                   f"of {n} spp take about {seconds:.3g} s")
    return Plan(scene=str(info.path), target_error=float(target_error), variant=variant,
                backend=backend, color=color, max_depth=int(depth), spp=int(n), passes=passes,
                predicted_error=predicted, predicted_bias=bias, predicted_noise=noise,
                predicted_seconds=seconds, seconds_per_sample=b / pixels,
                seconds_per_pass=a, resolution=resolution,
                params={k: v for k, v in params.items()}, pilot_spp=s * pilot_passes,
                pilot_seconds=time.perf_counter() - t_start,
                depths=[samples[d] for d in sorted(samples, key=lambda d: (d == -1, d))],
                reasons=reasons, overrides=overrides)


def benchmark_table(rows: list[dict]) -> str:
    """Markdown table of ``scripts/planner_bench.py`` rows (planned vs default at equal error)."""
    out = ["| scene | default (rgb, depth 8, scene spp): time, error | planned: variant, depth, "
           "spp | planned: time (predicted), error (predicted) | speed-up | efficiency ratio "
           "| pilot |",
           "|---|---|---|---|---|---|---|"]
    for r in rows:
        d, p = r["default"], r["planned"]
        out.append(
            f"| {r['scene']} ({r['res']}²) | {d['seconds_median'] * 1e3:.0f} ms, "
            f"{d['error']:.4f} ± {d['error_sd']:.4f} | {p['variant']}, {p['max_depth']}, "
            f"{p['spp']} | {p['seconds_median'] * 1e3:.0f} ms "
            f"({p['predicted_seconds_one_pass'] * 1e3:.0f}), {p['error']:.4f} ± "
            f"{p['error_sd']:.4f} ({p['predicted_error']:.4f}) | {r['speedup']:.2f}x | "
            f"{r['efficiency_ratio']:.2f}x | "
            f"{p['pilot_seconds']:.1f} s |")
    return "\n".join(out)
