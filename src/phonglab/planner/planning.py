"""The plan: :func:`plan` chooses the variant, runs the pilot, and picks depth, spp and time.

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
from ..engine.metrics import noise_target
from ..engine.render import MAX_SPP, Prior, check_spp, precision
from ..runtime import available_backend, check_variant, quiet_mitsuba, variant_for
from ..engine.scenes import SceneInfo, inspect_scene, load_scene, sensor_with_sampler
from ..settings import ParameterError, check_max_seconds
from . import choice, ladder
from .pilot import (BIAS_FRACTION, DEPTH_LADDER, EPS, PILOT_PASSES, PILOT_SEED, PILOT_SEEDS,
                    PILOT_SPP, DepthSample, Pilot, pilot_size)

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
    #: step 5 (:mod:`.choice`): the render's transport model and sampling; ``spp`` and
    #: ``predicted_seconds`` above stay those of uniform ``path`` at ``max_depth``
    model: str = "path"
    sampling: str = "uniform"
    chosen_spp: float = 0.0          #: samples per pixel of the choice (mean when adaptive)
    chosen_seconds: float = 0.0      #: its predicted steady-state time
    sampler: str = "independent"     #: Mitsuba sampler of the render (uniform path)
    chosen_passes: int = 0           #: passes of the chosen uniform render
    #: the scene file as :func:`plan` inspected it (with :attr:`params`), and the scene the
    #: pilot loaded (:attr:`variant`, :attr:`params`): the render reuses them
    #: (:mod:`.execute`); neither is part of :meth:`to_dict`
    info: SceneInfo | None = field(default=None, repr=False, compare=False)
    loaded: Any = field(default=None, repr=False, compare=False)
    #: the pilot's renders the chosen uniform render is combined with (:meth:`.pilot.Pilot.
    #: reusable`, :func:`phonglab.engine.render.combine_renders`); None when it renders alone
    reused: Prior | None = field(default=None, repr=False, compare=False)
    #: the pilot's weights ≈ 1/(r² + ε) (from its second render): the render's noise is
    #: measured with them (:func:`.execute.error_report`), not with its own image's
    weight: Any = field(default=None, repr=False, compare=False)
    reused_spp: int = 0              #: samples per pixel of :attr:`reused`
    pilot_seed: int = PILOT_SEED     #: the pilot's seed (its renders use it and the next ones)

    @property
    def noise_target(self) -> float:
        """The noise the render may leave, √(E² − bias²) (:func:`phonglab.engine.metrics.noise_target`:
        what a wavefront render aims at)."""
        return noise_target(self.target_error, self.predicted_bias)

    @property
    def uses_wavefront(self) -> bool:
        """True when the render goes through :mod:`phonglab.engine.adaptive` (adaptive sampling, or
        a model other than the scene's path integrator)."""
        return self.sampling == "adaptive" or self.model != "path"

    def to_dict(self) -> dict[str, Any]:
        """The plan as plain values (JSON, the EXR header), without :attr:`info` and
        :attr:`loaded`."""
        d = dataclasses.asdict(dataclasses.replace(self, info=None, loaded=None, reused=None,
                                                   weight=None))
        del d["info"], d["loaded"], d["reused"], d["weight"]
        d["resolution"] = list(self.resolution)
        return d

    def to_json(self, indent: int | None = 2) -> str:
        return json.dumps(self.to_dict(), indent=indent)

    def render_kwargs(self) -> dict[str, Any]:
        """Keyword arguments of :func:`phonglab.engine.render.render_file` that apply the plan (a
        uniform ``path`` render that reaches E on its own: the chosen sampler, spp and passes;
        when the plan combines its render with the pilot's, the uniform spp of
        :attr:`spp`)."""
        if (self.sampler != "independent" and self.sampling == "uniform"
                and self.model == "path" and self.reused is None):
            return {"spp": int(math.ceil(self.chosen_spp)), "variant": self.variant,
                    "max_depth": self.max_depth, "passes": self.chosen_passes,
                    "sampler": self.sampler}
        return {"spp": self.spp, "variant": self.variant, "max_depth": self.max_depth,
                "passes": self.passes}

    def repeats_pilot(self, seed: int) -> bool:
        """True when a render with ``seed`` would repeat the samples of the pilot's renders
        this plan combines its render with (seeds pilot_seed to pilot_seed + PILOT_SEEDS)."""
        return self.reused is not None and self.pilot_seed <= seed <= self.pilot_seed + PILOT_SEEDS

    def standalone(self) -> Plan:
        """The plan without the pilot's samples: its uniform ``path`` render of :attr:`spp`
        (:meth:`render_kwargs`), which reaches E on its own."""
        return dataclasses.replace(
            self, reused=None, reused_spp=0, sampling="uniform", model="path",
            sampler="independent", chosen_spp=float(self.spp), chosen_passes=self.passes,
            chosen_seconds=self.predicted_seconds,
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
        lines = [
            f"plan for {self.scene} ({w}x{h}), target relative RMSE {self.target_error:g} "
            f"(eps {EPS:g}):",
            f"  variant   {self.variant}",
            f"  max_depth {self.max_depth}",
            f"  spp       {self.spp}  ({self.passes} passes)",
            f"  render    {self.model}, {self.sampling} sampling ({self.sampler} sampler), "
            f"{self.chosen_spp:.1f} spp"
            f"{' on average' if self.sampling == 'adaptive' else ''}, about "
            f"{self.chosen_seconds:.3g} s",
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


def plan(scene_path: str | Path, target_error: float = 0.01, *, pilot_spp: int | None = None,
         pilot_passes: int = PILOT_PASSES, seed: int = PILOT_SEED,
         bias_fraction: float = BIAS_FRACTION, polarized: bool = False,
         variant: str | None = None, max_depth: int | None = None, spp: int | None = None,
         max_depth_cap: int = DEPTH_LADDER[-1], params: dict[str, Any] | None = None,
         max_seconds: float | None = None, straight: bool | None = None) -> Plan:
    """Plan the cheapest render of ``scene_path`` predicted to reach ``target_error``.

    Args:
        scene_path: scene file, or the name of a shipped scene (``cornell_phong``).
        target_error: E, the total relative RMSE, bias included (:mod:`phonglab.engine.metrics`;
            ``0.01`` = 1 %).
        pilot_spp, pilot_passes: pilot samples per pixel (default :func:`.pilot.pilot_size`
            of the film: 64, fewer beyond 64² pixels, at least 4) and the passes they are split
            into (at most ``pilot_passes``).
        seed: pilot seed (the render that follows should use another; the CLI uses 0).
        bias_fraction: the depth bias may use this fraction of E.
        polarized: plan a polarized variant (never chosen otherwise).
        variant, max_depth, spp: fix that part of the plan (the predictions follow it).
        max_depth_cap: deepest finite depth tried; beyond it the plan uses -1 (unbounded).
        params: values for the scene's ``<default>`` entries (``{"res": 64}``).
        straight: when the rest of the render is predicted cheaper than the pilot's first
            render, plan path at full depth at once (:func:`_straight`); default
            :data:`STRAIGHT`, False to run every step of the pilot whatever it costs.
        max_seconds: a plan predicted to take longer is refused (default :data:`MAX_SECONDS`;
            ``math.inf`` allows any).

    Returns:
        a :class:`Plan`.

    Raises:
        PlanError: bad target or pilot size, unknown variant, a scene whose integrator is not
            ``path``, a plan beyond ``max_seconds`` or beyond the spp a render takes; SceneError: a scene that cannot be found, parsed or loaded.
    """
    t_start = time.perf_counter()
    _check_arguments(target_error, PILOT_SPP if pilot_spp is None else pilot_spp, pilot_passes,
                     spp, max_depth)
    if max_seconds is not None:
        try:
            check_max_seconds(max_seconds)
        except ParameterError as exc:
            raise PlanError(str(exc)) from None
    params = {k: v for k, v in (params or {}).items() if v is not None}
    info = inspect_scene(scene_path, **params)
    if info.integrator != "path":
        raise PlanError(f"{info.path}: the planner plans path-traced scenes, but this one "
                        f"uses the '{info.integrator}' integrator; use <integrator "
                        f"type=\"path\"> or render it with 'phonglab render' directly.")
    reasons: list[str] = []
    overrides = {k: v for k, v in (("variant", variant), ("max_depth", max_depth), ("spp", spp))
                 if v is not None}
    variant, backend, color = _choose_variant(info, variant, polarized, reasons)
    with quiet_mitsuba():
        scene = load_scene(info.path, variant, **params)
    sensor = scene.sensors()[0]
    resolution = (int(sensor.film().size()[0]), int(sensor.film().size()[1]))
    scene_spp = int(sensor.sampler().sample_count())  # before the pilot: mi.render changes it
    if pilot_spp is None:
        pilot_spp, pilot_passes = pilot_size(resolution[0] * resolution[1], pilot_passes)
    stratified = _stratified_sensor(info, overrides, reasons)
    pilot = Pilot(scene, info, pilot_spp, pilot_passes, seed, stratified=stratified)
    if not overrides and (STRAIGHT if straight is None else straight):
        straight = _straight(pilot, target_error, resolution, reasons)
        if straight is not None:
            n, final, b, prior = straight
            pixels = resolution[0] * resolution[1]
            noise = pilot.measure(-1).noise_per_sample / math.sqrt(n)
            _refuse_absurd(info.path, target_error, n, b * n,
                           MAX_SECONDS if max_seconds is None else max_seconds)
            passes = max(2, min(8, final // choice.MIN_PASS_SPP))
            return Plan(scene=str(info.path), target_error=float(target_error),
                        variant=variant, backend=backend, color=color, max_depth=-1,
                        spp=int(n), passes=render_passes(n), predicted_error=noise,
                        predicted_bias=0.0, predicted_noise=noise, predicted_seconds=b * n,
                        seconds_per_sample=b / pixels, seconds_per_pass=0.0,
                        resolution=resolution, params=dict(params), pilot_spp=pilot.spp,
                        pilot_seconds=time.perf_counter() - t_start, depths=pilot.depths(),
                        reasons=reasons, overrides=overrides, chosen_spp=float(final),
                        chosen_seconds=b * final, chosen_passes=passes, info=info,
                        loaded=scene, reused=prior, weight=pilot.weight,
                        reused_spp=int(sum(sum(r.pass_spp) for r in prior.renders)),
                        pilot_seed=int(seed))
    depth = _choose_depth(pilot, target_error, bias_fraction, max_depth, max_depth_cap, reasons)
    chosen = pilot.measure(depth)
    n = _choose_spp(chosen, target_error, spp, scene_spp, reasons)
    noise = math.sqrt(chosen.noise_per_sample ** 2 / n)
    predicted = math.sqrt(chosen.bias ** 2 + noise ** 2)
    if predicted > target_error * (1 + 1e-9):
        reasons.append(f"warning: the predicted error {predicted:.4g} misses the target "
                       f"{target_error:g} with the configuration given")
    a, b, passes, seconds = _predict_time(pilot, depth, n, resolution, reasons)
    _refuse_absurd(info.path, target_error, n, seconds,
                   MAX_SECONDS if max_seconds is None else max_seconds)
    pixels = resolution[0] * resolution[1]
    prior, credit = _reusable(pilot, depth, overrides)
    option = _choose_render(pilot, depth, chosen, n, seconds, overrides, target_error,
                            pixels, passes, reasons, credit)
    reused = prior if option.reuses else None
    if reused:
        reasons.append(f"reuse: the pilot's {len(reused.renders)} renders at this depth (or "
                       f"full depth) hold {sum(sum(r.pass_spp) for r in reused.renders)} "
                       f"samples per pixel, "
                       f"worth {credit * chosen.noise_per_sample ** 2:.1f} of its independent "
                       f"ones; the render is combined with them (inverse-variance weights), "
                       f"so it takes {option.spp:g} spp")
    return Plan(scene=str(info.path), target_error=float(target_error), variant=variant,
                backend=backend, color=color, max_depth=int(depth), spp=int(n), passes=passes,
                predicted_error=predicted, predicted_bias=chosen.bias, predicted_noise=noise,
                predicted_seconds=seconds, seconds_per_sample=b / pixels,
                seconds_per_pass=a, resolution=resolution, params=dict(params),
                pilot_spp=pilot.spp, pilot_seconds=time.perf_counter() - t_start,
                depths=pilot.depths(), reasons=reasons, overrides=overrides,
                model=option.model, sampling=option.sampling, chosen_spp=float(option.spp),
                chosen_seconds=option.seconds, sampler=option.sampler,
                chosen_passes=option.passes or passes, info=info, loaded=scene,
                reused=reused, weight=pilot.weight,
                reused_spp=int(sum(sum(r.pass_spp) for r in reused.renders)) if reused else 0,
                pilot_seed=int(seed))


def _straight(pilot: Pilot, target_error: float, resolution: tuple[int, int],
              reasons: list[str]):
    """(N, spp to render, seconds per pixel sample x pixels, the pilot's renders) of a
    straight render, or None: when the rest of the render is predicted to take at most
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
    return n_total, rest, per_spp, prior


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


def _choose_render(pilot: Pilot, depth: int, sample: DepthSample, n: int, seconds: float,
                   overrides: dict[str, Any], target_error: float, pixels: int, passes: int,
                   reasons: list[str], credit: float = 0.0) -> choice.Option:
    """Step 5 (:mod:`.choice`): model and sampling; uniform path when spp or depth are given."""
    uniform = choice.Option("path", "uniform", n, seconds, sample.noise_per_sample)
    if "spp" in overrides or "max_depth" in overrides:
        reasons.append("render: uniform path, as the spp/max_depth given by the caller imply")
        return uniform
    if sample.noise_per_sample == 0.0:
        return uniform
    return choice.choose(pilot, depth, sample.bias, target_error, uniform, pixels, passes,
                         reasons, credit)


def _refuse_absurd(path, target_error: float, n: int, seconds: float, max_seconds: float) -> None:
    """A plan no one should start by accident: more spp than a render takes, or over the time limit."""
    if n > MAX_SPP:
        raise PlanError(f"{path}: reaching E = {target_error:g} needs about {n:.3g} spp, more than "
                        f"a render takes ({MAX_SPP}); ask for a larger --target-error.")
    if seconds > max_seconds:
        raise PlanError(f"{path}: reaching E = {target_error:g} needs {n} spp and about "
                        f"{_duration(seconds)}, over the limit of {_duration(max_seconds)}; ask "
                        f"for a larger --target-error, or allow it with --max-seconds.")


def _duration(seconds: float) -> str:
    for unit, size in (("years", 365.25 * 86400), ("days", 86400), ("h", 3600), ("min", 60)):
        if seconds >= size:
            return f"{seconds / size:.3g} {unit}"
    return f"{seconds:.3g} s"


def _check_arguments(target_error, pilot_spp: int, pilot_passes: int, spp: int | None,
                     max_depth: int | None) -> None:
    """Refuse a target, pilot size, spp or max_depth the plan cannot use (PlanError; a bad
    spp is render.check_spp's PhonglabError, the same sentence a render gives)."""
    if not (isinstance(target_error, (int, float)) and math.isfinite(target_error)
            and 0 < target_error < 10):
        raise PlanError(f"target error must be a relative RMSE in (0, 10), e.g. 0.01 for "
                        f"1 %, got {target_error!r}.")
    if pilot_passes < 2 or pilot_spp < pilot_passes:
        raise PlanError(f"the pilot needs at least 2 passes of at least 1 spp, got "
                        f"pilot_spp={pilot_spp}, pilot_passes={pilot_passes}.")
    if spp is not None:
        check_spp(spp)
    if max_depth is not None and (max_depth == 0 or max_depth < -1):
        raise PlanError(f"max_depth must be -1 (unbounded) or >= 1, got {max_depth}.")


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
