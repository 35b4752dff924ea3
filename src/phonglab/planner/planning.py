"""The plan: :func:`plan` chooses the variant, runs the pilot, and picks depth, spp and time.

:func:`plan` takes what it is asked (:class:`PlanOptions`, checked on construction) and gives
a :class:`Plan` made of the choices of its steps: the variant (step 1) and depth (step 2),
the uniform ``path`` render that reaches E on its own (:class:`Uniform`, steps 3-4), the render
that runs (:class:`.choice.Option`, step 5) and what it keeps of its pilot (:class:`PilotRecord`).
Each step is a function of its own and appends its reason to :attr:`Plan.reasons`; the math
is in the package docstring (:mod:`phonglab.planner`), the pilot in :mod:`.pilot`.
"""

from __future__ import annotations

import dataclasses
import json
import math
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ..errors import PlanError, SceneError
from ..engine.metrics import check_target, noise_target
from ..engine.render import MAX_SPP, Prior, check_spp, precision
from ..runtime import available_backend, check_variant, quiet_mitsuba, variant_for
from ..engine.scenes import SceneInfo, inspect_scene, load_scene, sensor_with_sampler
from ..settings import ParameterError, check_max_seconds
from . import choice, ladder
from .pilot import (BIAS_FRACTION, DEPTH_LADDER, EPS, PILOT_PASSES, PILOT_SEED, PILOT_SEEDS,
                    DepthSample, Pilot, pilot_size)

#: :func:`plan` renders straight away (:func:`_straight`) when it pays, unless told not to.
STRAIGHT = True
#: :func:`_straight` goes straight when the rest of the render, priced at the pilot's first
#: render's time per spp, takes at most this many first renders.  The later pilot steps (ladder
#: stages, the time model's seven renders) cost 0.3-5.9 first renders before the render they
#: choose, median 3.9 (the seven bench scenes at 128², 256², 512², warm, in-process), and a
#: full-depth ``path`` sample costs 1/1.9-1/1.5 of the ladder sample the rest is priced at
#: (an image per depth: gray_room 512² 65 against 121 ms/spp, 256² 16 against 25,
#: textured_room 128² 4.1 against 6.4): a rest priced at 8 first renders takes about as long
#: as the later steps alone.  Measured, plan + render, warm: gray_room 256² straight 0.86 s
#: against 0.96 s, 512² 3.6 s against 4.7 s, textured_room 128² 0.73 s against 0.79 s
#: (rests of 7.0, 5.75 and 7.7 first renders); textured_room 256² (a rest of 36) took 2.74 s
#: straight against 2.34 s planned, and gray_direct 128² (12.7) gains 1.3x from a multijitter
#: sampler only its later steps find.
STRAIGHT_RENDERS = 8
#: A plan predicted to take longer than this (seconds) is refused unless asked for.
MAX_SECONDS = 3600.0


@dataclass
class PlanOptions:
    """What :func:`plan` is asked for, checked on construction (PlanError, one sentence each;
    a bad spp is render.check_spp's sentence, the one a render gives): the command line builds
    it from its flags before any work."""

    target_error: float = 0.01  #: E, the total relative RMSE, bias included (engine.metrics)
    variant: str | None = None  #: fix the variant (the predictions follow it)
    max_depth: int | None = None  #: fix max_depth (-1: unbounded)
    spp: int | None = None      #: fix the uniform spp (the error is then predicted)
    polarized: bool = False     #: plan a polarized variant (never chosen otherwise)
    #: values for the scene's ``<default>`` entries (``{"res": 64}``; None values are dropped)
    params: dict[str, Any] = field(default_factory=dict)
    #: refuse a plan predicted to take longer (seconds; None: :data:`MAX_SECONDS`; ``math.inf``
    #: allows any)
    max_seconds: float | None = None
    #: when the rest of the render is predicted cheaper than the pilot's later steps, plan path
    #: at full depth at once (:func:`_straight`); None: :data:`STRAIGHT`; False: every step
    straight: bool | None = None
    #: pilot samples per pixel (None: :func:`.pilot.pilot_size` of the film), in at most
    #: PILOT_PASSES passes
    pilot_spp: int | None = None
    #: the seed of the render the plan is for (:func:`.execute.render_plan`'s default): the
    #: pilot renders with :attr:`pilot_seed` and the seeds after it, so that the render, which
    #: is combined with the pilot's samples, never repeats them
    seed: int = 0

    def __post_init__(self) -> None:
        self.params = {k: v for k, v in (self.params or {}).items() if v is not None}
        try:
            check_target(self.target_error)
            if self.max_seconds is not None:
                check_max_seconds(self.max_seconds)
        except ParameterError as exc:
            raise PlanError(str(exc)) from None
        if self.pilot_spp is not None and self.pilot_spp < PILOT_PASSES:
            raise PlanError(f"the pilot needs at least {PILOT_PASSES} spp ({PILOT_PASSES} "
                            f"passes of at least 1), got pilot_spp={self.pilot_spp}.")
        if self.spp is not None:
            check_spp(self.spp)
        if self.max_depth is not None and (self.max_depth == 0 or self.max_depth < -1):
            raise PlanError(f"max_depth must be -1 (unbounded) or >= 1, got {self.max_depth}.")

    @property
    def overrides(self) -> dict[str, Any]:
        """The parts of the plan the caller fixed (variant, max_depth, spp)."""
        return {k: v for k, v in (("variant", self.variant), ("max_depth", self.max_depth),
                                  ("spp", self.spp)) if v is not None}

    @property
    def pilot_seed(self) -> int:
        """The pilot's seed: the render's + :data:`.pilot.PILOT_SEED`."""
        return self.seed + PILOT_SEED

    @property
    def time_limit(self) -> float:
        """Seconds beyond which a plan is refused."""
        return MAX_SECONDS if self.max_seconds is None else float(self.max_seconds)


@dataclass
class Uniform:
    """Steps 2-4: uniform ``path`` at :attr:`Plan.max_depth`, the render that reaches E on its
    own, and what the pilot predicts for it."""

    spp: int
    passes: int                #: passes the render uses (for the standard error)
    predicted_error: float     #: √(bias² + noise²)
    predicted_bias: float      #: b(max_depth)
    predicted_noise: float     #: noise at spp
    predicted_seconds: float   #: steady-state render time (JIT compile excluded)
    seconds_per_sample: float  #: b of T = a + b·spp, per pixel sample
    seconds_per_pass: float    #: a of T = a + b·spp


@dataclass
class PilotRecord:
    """What a plan keeps of its pilot (:class:`.pilot.Pilot`)."""

    spp: int
    seconds: float             #: wall time of the whole plan (inspection, renders, timing)
    seed: int                  #: its seed (its renders use it and the next PILOT_SEEDS ones)
    depths: list[DepthSample] = field(default_factory=list)
    #: its weights ≈ 1/(r² + ε) (from its second render): the render's noise is measured with
    #: them (:func:`.execute.error_report`), not with its own image's
    weight: Any = field(default=None, repr=False, compare=False)


@dataclass
class Plan:
    """A rendering configuration for a target error: the choices of :func:`plan`'s steps, with
    their predictions and reasons."""

    scene: str
    options: PlanOptions       #: what the plan was asked for (target, params, fixed parts, seed)
    variant: str
    backend: str
    color: str
    max_depth: int
    resolution: tuple[int, int]
    #: steps 3-4: uniform ``path`` at :attr:`max_depth`, whatever renders
    uniform: Uniform
    #: step 5 (:mod:`.choice`): the render that runs, its transport model, sampling, sampler,
    #: samples per pixel (mean when adaptive), passes and predicted steady-state time
    render: choice.Option
    pilot: PilotRecord
    reasons: list[str] = field(default_factory=list)
    #: the scene file as :func:`plan` inspected it (with the options' params), and the scene
    #: the pilot loaded (:attr:`variant`): the render reuses them (:mod:`.execute`)
    info: SceneInfo | None = field(default=None, repr=False, compare=False)
    loaded: Any = field(default=None, repr=False, compare=False)
    #: the pilot's renders the chosen uniform render is combined with (:meth:`.pilot.Pilot.
    #: reusable`, :func:`phonglab.engine.render.combine_renders`); None when it renders alone
    reused: Prior | None = field(default=None, repr=False, compare=False)

    @property
    def target_error(self) -> float:
        """E, the plan's total relative error target (:attr:`PlanOptions.target_error`)."""
        return float(self.options.target_error)

    @property
    def noise_target(self) -> float:
        """The noise the render may leave, √(E² − bias²) (:func:`phonglab.engine.metrics.noise_target`:
        what a wavefront render aims at)."""
        return noise_target(self.target_error, self.uniform.predicted_bias)

    @property
    def uses_wavefront(self) -> bool:
        """True when the render goes through :mod:`phonglab.engine.adaptive` (adaptive sampling, or
        a model other than the scene's path integrator)."""
        return self.render.sampling == "adaptive" or self.render.model != "path"

    @property
    def reused_spp(self) -> int:
        """Samples per pixel of :attr:`reused` (0: the render renders alone)."""
        return self.reused.spp if self.reused is not None else 0

    def to_dict(self) -> dict[str, Any]:
        """The plan as plain values (JSON, the EXR header), one level deep as the keys of
        docs/planner.md, without the scene and pilot images it holds."""
        r, p = self.render, self.pilot
        return {"scene": self.scene, "target_error": self.target_error, "variant": self.variant,
                "backend": self.backend, "color": self.color, "max_depth": self.max_depth,
                **dataclasses.asdict(self.uniform), "resolution": list(self.resolution),
                "params": dict(self.options.params), "pilot_spp": p.spp,
                "pilot_seconds": p.seconds, "depths": [dataclasses.asdict(d) for d in p.depths],
                "reasons": list(self.reasons), "overrides": self.options.overrides,
                "model": r.model, "sampling": r.sampling, "chosen_spp": float(r.spp),
                "chosen_seconds": r.seconds, "sampler": r.sampler, "chosen_passes": r.passes,
                "reused_spp": self.reused_spp, "pilot_seed": p.seed}

    def to_json(self, indent: int | None = 2) -> str:
        return json.dumps(self.to_dict(), indent=indent)

    def render_kwargs(self) -> dict[str, Any]:
        """Keyword arguments of :func:`phonglab.engine.render.render_file` that apply the plan (a
        uniform ``path`` render that reaches E on its own: the chosen sampler, spp and passes;
        when the plan combines its render with the pilot's, the uniform spp of
        :attr:`uniform`)."""
        r = self.render
        if (r.sampler != "independent" and r.sampling == "uniform"
                and r.model == "path" and self.reused is None):
            return {"spp": int(math.ceil(r.spp)), "variant": self.variant,
                    "max_depth": self.max_depth, "passes": r.passes, "sampler": r.sampler}
        return {"spp": self.uniform.spp, "variant": self.variant, "max_depth": self.max_depth,
                "passes": self.uniform.passes}

    def repeats_pilot(self, seed: int) -> bool:
        """True when a render with ``seed`` would repeat the samples of the pilot's renders
        this plan combines its render with (seeds pilot seed to pilot seed + PILOT_SEEDS)."""
        return (self.reused is not None
                and self.pilot.seed <= seed <= self.pilot.seed + PILOT_SEEDS)

    def standalone(self) -> Plan:
        """The plan without the pilot's samples: its uniform ``path`` render of
        :attr:`uniform` (:meth:`render_kwargs`), which reaches E on its own."""
        u = self.uniform
        return dataclasses.replace(
            self, reused=None,
            render=choice.Option("path", "uniform", float(u.spp), u.predicted_seconds,
                                 u.predicted_noise * math.sqrt(u.spp), passes=u.passes),
            reasons=self.reasons + ["the render's seed is one of the pilot's: it renders the "
                                    "uniform spp alone, without the pilot's samples"])

    def uniform_sensor(self, info: SceneInfo):
        """The sensor of the plan's uniform render of the scene ``info`` describes: 0 (its own)
        or its first sensor rebuilt with the chosen sampler (``render_scene(sensor=...)``)."""
        sampler = self.render_kwargs().get("sampler")
        return sensor_with_sampler(info, sampler) if sampler else 0

    def summary(self) -> str:
        """The plan and its reasons, as the CLI prints them."""
        w, h = self.resolution
        u, r = self.uniform, self.render
        lines = [
            f"plan for {self.scene} ({w}x{h}), target relative RMSE {self.target_error:g} "
            f"(eps {EPS:g}):",
            f"  variant   {self.variant}",
            f"  max_depth {self.max_depth}",
            f"  spp       {u.spp}  ({u.passes} passes)",
            f"  render    {r.model}, {r.sampling} sampling ({r.sampler} sampler), "
            f"{r.spp:.1f} spp"
            f"{' on average' if r.sampling == 'adaptive' else ''}, about "
            f"{r.seconds:.3g} s",
            f"  predicted error {u.predicted_error:.4g} (depth bias {u.predicted_bias:.3g}, "
            f"noise {u.predicted_noise:.4g}); time {u.predicted_seconds:.3g} s "
            f"steady state ({u.seconds_per_sample * 1e9:.3g} ns per sample + "
            f"{u.seconds_per_pass * 1e3:.3g} ms per pass); pilot took "
            f"{self.pilot.seconds:.2f} s",
            "because:",
        ]
        lines += [f"  - {reason}" for reason in self.reasons]
        return "\n".join(lines)

    def __str__(self) -> str:
        return self.summary()


def render_passes(spp: int) -> int:
    """Passes a planned render uses: 8 (or spp when fewer), at least 2 so it has a stderr."""
    return max(1, min(int(spp), 8)) if spp >= 2 else 1


def plan(scene_path: str | Path, options: PlanOptions | None = None) -> Plan:
    """Plan the cheapest render of ``scene_path`` predicted to reach ``options.target_error``.

    Args:
        scene_path: scene file, or the name of a shipped scene (``cornell_phong``).
        options: what is asked (:class:`PlanOptions`; default: E = 0.01, nothing fixed).

    Returns:
        a :class:`Plan`.

    Raises:
        PlanError: unknown variant, a scene whose integrator is not ``path``, a plan beyond
            the options' time limit or beyond the spp a render takes; SceneError: a scene
            that cannot be found, parsed or loaded.
    """
    t_start = time.perf_counter()
    options = PlanOptions() if options is None else options
    info = inspect_scene(scene_path, **options.params)
    if info.integrator != "path":
        raise PlanError(f"{info.path}: the planner plans path-traced scenes, but this one "
                        f"uses the '{info.integrator}' integrator; use <integrator "
                        f"type=\"path\"> or render it with 'phonglab render' directly.")
    reasons: list[str] = []
    variant, backend, color = _choose_variant(info, options.variant, options.polarized, reasons)
    with quiet_mitsuba():
        scene = load_scene(info.path, variant, **options.params)
    sensor = scene.sensors()[0]
    resolution = (int(sensor.film().size()[0]), int(sensor.film().size()[1]))
    scene_spp = int(sensor.sampler().sample_count())  # before the pilot: mi.render changes it
    pilot_spp, pilot_passes = (pilot_size(resolution[0] * resolution[1])
                               if options.pilot_spp is None else (options.pilot_spp, PILOT_PASSES))
    stratified = _stratified_sensor(info, options.overrides, reasons)
    pilot = Pilot(scene, info, pilot_spp, pilot_passes, options.pilot_seed, stratified=stratified)
    straight = None
    if not options.overrides and (STRAIGHT if options.straight is None else options.straight):
        straight = _straight(pilot, options.target_error, resolution, reasons)
    if straight is not None:
        depth, (uniform, render, reused) = -1, straight
        _refuse_absurd(info.path, options, uniform)
    else:
        depth = _choose_depth(pilot, options.target_error, BIAS_FRACTION, options.max_depth,
                              DEPTH_LADDER[-1], reasons)
        uniform = _choose_uniform(pilot, depth, options, resolution, scene_spp, reasons)
        _refuse_absurd(info.path, options, uniform)
        render, reused = _choose_render(pilot, depth, uniform, options, resolution, reasons)
    record = PilotRecord(pilot.spp, time.perf_counter() - t_start, options.pilot_seed,
                         pilot.depths(), pilot.weight)
    return Plan(str(info.path), options, variant, backend, color, int(depth), resolution,
                uniform, render, record, reasons, info=info, loaded=scene, reused=reused)


def _straight(pilot: Pilot, target_error: float, resolution: tuple[int, int],
              reasons: list[str]) -> tuple[Uniform, choice.Option, Prior] | None:
    """(uniform path, the render, the pilot's renders it is combined with) of a straight
    render, or None: when the rest of the render is predicted to take at most
    :data:`STRAIGHT_RENDERS` times what the pilot's first render did, the rest of the pilot
    (the depth search, the time model) cannot save more than it costs, and the plan is the
    default configuration at once:
    ``path`` at full depth (unbiased), independent samples, combined with the pilot's two
    full-depth renders.

    With n(1) the first pilot's relative noise at full depth and P the two renders'
    precision (:func:`_reusable`), the render needs n = ⌈n(1)² (1/E² − P)⌉ samples (at
    least 2); the first render took t seconds for s samples per pixel of the ladder, whose
    time per sample is 1.5-1.9 times a full-depth ``path`` sample's, so the rest takes at most
    t·n/s.  The later steps of the pilot cost about 4 first renders (0.3-5.9) before the
    render they choose, so a rest of at most :data:`STRAIGHT_RENDERS` · t (at most about
    4-5 t of ``path``) cannot be shortened by more than it would cost to find out how.
    """
    full = pilot.measure(-1)
    if full.noise_per_sample == 0.0 or pilot.first_seconds <= 0.0:
        return None
    parts = pilot.reusable(-1)
    precisions = tuple(precision(part, weight) for part, weight in parts)
    if not all(math.isfinite(p) and p > 0 for p in precisions):
        return None
    credit = sum(precisions)
    v1 = full.noise_per_sample ** 2
    n_total = max(1, math.ceil(v1 / target_error ** 2))
    rest = choice.credited_spp(full.noise_per_sample, target_error ** 2, credit)
    per_spp = pilot.first_seconds / pilot.spp
    if per_spp * rest > STRAIGHT_RENDERS * pilot.first_seconds:
        return None
    reasons.append(f"straight: the pilot's first render took {pilot.first_seconds:.3g} s for "
                   f"{pilot.spp} spp at full depth; with its two full-depth renders (worth "
                   f"{credit * v1:.1f} independent samples) the image needs {rest} more spp "
                   f"of {n_total}, at most {per_spp * rest:.3g} s at that render's rate "
                   f"({STRAIGHT_RENDERS} first renders or less: about what the depth search and "
                   f"the time model would cost before their render), so no depth search or "
                   f"timing: path at full depth (max_depth -1, unbiased), {rest} spp, combined "
                   f"with the pilot's renders")
    prior = Prior(tuple(part for part, _ in parts), precisions, pilot.weight)
    noise = full.noise_per_sample / math.sqrt(n_total)
    uniform = Uniform(int(n_total), render_passes(n_total), noise, 0.0, noise,
                      per_spp * n_total, per_spp / (resolution[0] * resolution[1]), 0.0)
    render = choice.Option("path", "uniform", float(rest), per_spp * rest, full.noise_per_sample,
                           passes=max(2, min(8, rest // choice.MIN_PASS_SPP)), reuses=True)
    return uniform, render, prior


def _reusable(pilot: Pilot, depth: int, overrides: dict[str, Any]) -> tuple[Prior | None, float]:
    """The pilot's renders a uniform ``path`` render at ``depth`` may be combined with
    (:class:`phonglab.engine.render.Prior`), and the precision Σ n_j/V_j they bring
    (:func:`phonglab.engine.render.combine_renders`): none when the caller fixed spp or depth (the
    render is then the one asked for)."""
    if "spp" in overrides or "max_depth" in overrides:
        return None, 0.0
    parts = pilot.reusable(depth)
    precisions = tuple(precision(part, weight) for part, weight in parts)
    if not all(math.isfinite(p) and p > 0 for p in precisions):
        return None, 0.0   # a noiseless pilot: nothing to weigh (the plan renders 1 spp)
    return Prior(tuple(part for part, _ in parts), precisions, pilot.weight), sum(precisions)


def _stratified_sensor(info: SceneInfo, overrides: dict[str, Any], reasons: list[str]):
    """The scene's sensor with :data:`.choice.STRATIFIED` sampling, when the plan may price it:
    the scene samples independently and the caller fixed neither spp nor depth."""
    if info.sampler != "independent" or "spp" in overrides or "max_depth" in overrides:
        if info.sampler != "independent":
            reasons.append(f"sampler: the scene's own {info.sampler!r} (only an independent "
                           f"one is replaced)")
        return None
    try:
        return sensor_with_sampler(info, choice.STRATIFIED)
    except SceneError as exc:
        reasons.append(f"sampler: independent kept ({exc})")
        return None


def _choose_uniform(pilot: Pilot, depth: int, options: PlanOptions, resolution: tuple[int, int],
                    scene_spp: int, reasons: list[str]) -> Uniform:
    """Steps 3-4: uniform ``path`` at ``depth``, its spp, predicted error and time."""
    chosen = pilot.measure(depth)
    target_error = options.target_error
    n = _choose_spp(chosen, target_error, options.spp, scene_spp, reasons)
    noise = math.sqrt(chosen.noise_per_sample ** 2 / n)
    predicted = math.sqrt(chosen.bias ** 2 + noise ** 2)
    if predicted > target_error * (1 + 1e-9):
        reasons.append(f"warning: the predicted error {predicted:.4g} misses the target "
                       f"{target_error:g} with the configuration given")
    a, b, passes, seconds = _predict_time(pilot, depth, n, resolution, reasons)
    return Uniform(int(n), passes, predicted, chosen.bias, noise, seconds,
                   b / (resolution[0] * resolution[1]), a)


def _choose_render(pilot: Pilot, depth: int, uniform: Uniform, options: PlanOptions,
                   resolution: tuple[int, int],
                   reasons: list[str]) -> tuple[choice.Option, Prior | None]:
    """Step 5 (:mod:`.choice`): model and sampling, and the pilot's renders the render is
    combined with (None: it renders alone); uniform path when spp or depth are given."""
    sample = pilot.measure(depth)
    passes = uniform.passes
    option = choice.Option("path", "uniform", uniform.spp, uniform.predicted_seconds,
                           sample.noise_per_sample)
    prior, credit = _reusable(pilot, depth, options.overrides)
    if "spp" in options.overrides or "max_depth" in options.overrides:
        reasons.append("render: uniform path, as the spp/max_depth given by the caller imply")
    elif sample.noise_per_sample != 0.0:
        option = choice.choose(pilot, depth, sample.bias, options.target_error, option,
                               resolution[0] * resolution[1], passes, reasons, credit)
    reused = prior if option.reuses else None
    if reused:
        reasons.append(f"reuse: the pilot's {len(reused.renders)} renders at this depth (or "
                       f"full depth) hold {reused.spp} samples per pixel, "
                       f"worth {credit * sample.noise_per_sample ** 2:.1f} of its independent "
                       f"ones; the render is combined with them (inverse-variance weights), "
                       f"so it takes {option.spp:g} spp")
    return dataclasses.replace(option, spp=float(option.spp),
                               passes=option.passes or passes), reused


def _refuse_absurd(path, options: PlanOptions, uniform: Uniform) -> None:
    """A plan no one should start by accident: more spp than a render takes, or over the
    options' time limit."""
    target_error, n, seconds = options.target_error, uniform.spp, uniform.predicted_seconds
    if n > MAX_SPP:
        raise PlanError(f"{path}: reaching E = {target_error:g} needs about {n:.3g} spp, more than "
                        f"a render takes ({MAX_SPP}); ask for a larger --target-error.")
    if seconds > options.time_limit:
        raise PlanError(f"{path}: reaching E = {target_error:g} needs {n} spp and about "
                        f"{_duration(seconds)}, over the limit of "
                        f"{_duration(options.time_limit)}; ask for a larger --target-error, or "
                        f"allow it with --max-seconds.")


def _duration(seconds: float) -> str:
    for unit, size in (("years", 365.25 * 86400), ("days", 86400), ("h", 3600), ("min", 60)):
        if seconds >= size:
            return f"{seconds / size:.3g} {unit}"
    return f"{seconds:.3g} s"


def _choose_variant(info: SceneInfo, variant: str | None, polarized: bool,
                    reasons: list[str]) -> tuple[str, str, str]:
    """Step 1: (variant, backend, colour model), from the scene file alone unless given."""
    if variant is not None:
        try:
            check_variant(variant)
        except ValueError as exc:  # the one "unknown variant" message, as a planner error
            raise PlanError(str(exc)) from None
        color = "spectral" if "spectral" in variant else "mono" if "mono" in variant else "rgb"
        reasons.append(f"variant {variant}: given by the caller (the scene alone would need "
                       f"{info.color})")
        return variant, variant.split("_")[0], color
    backend, backend_why = available_backend()
    color = info.color
    if color == "spectral":
        reasons.append("spectral: the scene carries spectral data: " + "; ".join(info.spectral[:3]))
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
    return chosen, backend, color


def _choose_depth(pilot: Pilot, target_error: float, bias_fraction: float,
                  max_depth: int | None, cap: int, reasons: list[str]) -> int:
    """Step 2: the smallest depth whose bias b(d) is <= bias_fraction · E (or the given one)."""
    allowed = bias_fraction * target_error
    if max_depth is not None:
        bias = pilot.measure(max_depth).bias
        reasons.append(f"max_depth {max_depth}: given by the caller; its omitted contribution "
                       f"is a relative RMS {bias:.3g}"
                       + (f" (more than the {allowed:.3g} the planner would allow)"
                          if bias > allowed else ""))
        return max_depth
    depth, failing = pilot.search_depth(allowed, cap, target_error)
    if depth == -1:
        reasons.append(f"max_depth -1 (unbounded, Russian roulette): even depth {failing} "
                       f"omits a relative RMS {pilot.measure(failing).bias:.3g} > "
                       f"{bias_fraction:g} x E = {allowed:.3g}")
    else:
        s = pilot.measure(depth)
        why = (f"max_depth {depth}: the smallest depth whose omitted contribution (deeper "
               f"bounces: {100 * s.energy_omitted:.3g} % of the image's energy, relative RMS "
               f"{s.bias:.3g}) is <= {bias_fraction:g} x E = {allowed:.3g}")
        if failing >= 1:
            f = pilot.measure(failing)
            why += (f"; depth {failing} omits {100 * f.energy_omitted:.3g} % "
                    f"(relative RMS {f.bias:.3g})")
        if pilot.gap_skipped is not None:
            f_, p_, value = pilot.gap_skipped
            why += (f"; depths {f_ + 1} to {p_ - 1} were not searched: the pilot's paths cast "
                    f"{ladder.work(pilot.lengths, p_):.3g} rays per sample at depth {p_} and "
                    f"{ladder.work(pilot.lengths, f_ + 1):.3g} at {f_ + 1}, so a shallower depth "
                    f"could save the render at most {value:.2g}x what rendering the gap "
                    f"would cost")
        reasons.append(why)
    if pilot.info.delta_bsdfs:
        names = sorted(set(pilot.info.delta_bsdfs))
        reasons.append(f"delta BSDFs ({', '.join(names)}): their chains were followed as far "
                       f"as the pilot saw them carry energy (the depth search measures what "
                       f"deeper bounces add, delta paths included)")
    return depth


def _choose_spp(chosen: DepthSample, target_error: float, spp: int | None, scene_spp: int,
                reasons: list[str]) -> int:
    """Step 3: the smallest N with b(d)² + n(1)²/N <= E² (or the given spp)."""
    if spp is not None:
        reasons.append(f"spp {int(spp)}: given by the caller")
        return int(spp)
    v1 = chosen.noise_per_sample ** 2
    if v1 == 0.0:
        reasons.append("spp 1: the pilot shows no variance at all at this depth")
        return 1
    budget2 = target_error ** 2 - chosen.bias ** 2
    if budget2 <= 0:        # a max_depth given whose bias alone misses E: no N reaches it
        raise PlanError(f"max_depth {chosen.depth} omits a relative RMS {chosen.bias:.3g} of "
                        f"the image (deeper bounces), more than the target error "
                        f"{target_error:g} on its own, so no spp reaches the target; raise "
                        f"--max-depth (or leave it out: the plan chooses one), raise "
                        f"--target-error, or give --spp to render at that depth anyway")
    n = max(1, math.ceil(v1 / budget2))
    reasons.append(f"spp {n}: the pilot's per-pixel variance gives a relative noise of "
                   f"{chosen.noise_per_sample:.4g} at 1 spp, falling as 1/sqrt(spp); "
                   f"sqrt(E^2 - bias^2) = {math.sqrt(budget2):.4g} needs {n} spp "
                   f"(the scene's own spp is {scene_spp})")
    return n


def _predict_time(pilot: Pilot, depth: int, n: int, resolution: tuple[int, int],
                  reasons: list[str]) -> tuple[float, float, int, float]:
    """Step 4: (a, b, passes, seconds): T(spp) = a + b·spp at ``depth``, and p·a + b·N."""
    a, b = pilot.time_model(depth)
    passes = render_passes(n)
    seconds = passes * a + b * n
    pixels = resolution[0] * resolution[1]
    reasons.append(f"time: {b / pixels * 1e9:.3g} ns per pixel sample + {a * 1e3:.3g} ms per "
                   f"pass, measured at this depth after JIT compilation, so {passes} passes "
                   f"of {n} spp take about {seconds:.3g} s")
    return a, b, passes, seconds
