"""Rendering in passes: the one loop around ``mi.render``, and a scene file to EXR + PNG.

:func:`render_scene_file` is the one render of a scene file, uniform (:class:`UniformPasses`,
:func:`render_file`) or adaptive (:class:`phonglab.engine.adaptive.AdaptiveSampling`,
:func:`phonglab.engine.adaptive.render_file_adaptive`): path resolution, output checks, the
``<default>`` merge, loading (:func:`open_scene_file`), provenance, exposure and writing.

Rendering in passes (independent seeds, equal sample counts) gives both the image and a
per-pixel standard error of its mean, which the statistical checks, the convergence charts,
the bench and the planner all use.  Pass k of a render with seed s uses Mitsuba's seed
:func:`pass_seed` (s, k) = (s·1 000 003 + k) mod 2³², so renders with the same seed follow
the same paths pass by pass (the planner's depth pilot relies on that), and passes of
different seeds do not overlap.

With P passes of spp_k samples (Σ spp_k = N) and per-pixel pass means x_k, the image is
x̄ = Σ spp_k x_k / N and its standard error, from the weighted sample variance of the pass
means, is s = √( Σ spp_k (x_k − x̄)² / (N − N/P) / P ) (:func:`render_scene`).

**Independent renders of one image** (the planner's pilot renders and the render it planned,
:func:`combine_renders`): J unbiased estimates x̄_j of the same expected image, from
independent seeds, each with n_j samples and per-pixel standard error s_j, combine into
x̂ = Σ α_j x̄_j with Σ α_j = 1, unbiased for any fixed α, with Var x̂ = Σ α_j² s_j² per pixel.
With V_j = n_j · mean(s_j² w) the relative variance of one of its samples (w ≈ 1/(r² + ε), the
error metric's weights, :mod:`phonglab.engine.metrics`, drawn from *other* samples than render j's),
α_j ∝ n_j / V_j minimizes the image's relative variance, to 1 / Σ_j n_j/V_j: the
inverse-variance weights of independent unbiased estimates (Cochran, *Sampling Techniques*,
3rd ed., §5A.13; Pharr, Jakob & Humphreys, PBR 4th ed., §2.1.4).  The α_j are image-level
scalars: each depends on its render's samples only through a mean over every pixel, so the
bias it adds is of the order of that mean's relative error times a pixel's share of it
(negligible beside the noise of any image of 16 pixels or more).
"""

from __future__ import annotations

import contextlib
import math
import re
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import drjit as dr
import mitsuba as mi
import numpy as np
from tqdm import tqdm

from .. import __version__
from . import exr
from ..errors import PhonglabError, SceneError, user_errors
from .outputs import RenderOutputs
from ..runtime import quiet_mitsuba, require_memory
from .scenes import (SceneInfo, file_hash, inspect_scene, integrator_with_depth, load_scene,
                     scene_defaults, scene_path, sensor_with_sampler)
from .tonemap import auto_exposure


@dataclass
class RenderResult:
    """A rendered image, its per-pixel standard error and how it was made."""

    image: np.ndarray                 #: (H, W, C) float32 mean radiance
    stderr: np.ndarray | None         #: (H, W, C) standard error of the mean (None for 1 pass)
    seconds: float                    #: wall time of the passes (the first includes JIT compile)
    pass_seconds: list[float] = field(default_factory=list)
    metadata: dict[str, Any] = field(default_factory=dict)
    #: (passes, C) mean over all pixels of each pass: its spread gives the standard error of
    #: the image mean without assuming independent pixels (reconstruction filters correlate them).
    pass_means: np.ndarray | None = None
    pass_spp: list[int] = field(default_factory=list)
    #: (passes, H, W, C) float64 pass images, kept only when asked (``keep_passes=True``).
    passes: np.ndarray | None = None

    def mean_and_stderr(self) -> tuple[np.ndarray, np.ndarray | None]:
        """Per-channel image mean and its standard error from the pass means."""
        mean = self.image.reshape(-1, self.image.shape[-1]).mean(axis=0)
        if self.pass_means is None or len(self.pass_means) < 2:
            return mean, None
        w = np.asarray(self.pass_spp, dtype=np.float64)[:, None]
        spp = w.sum()
        var = np.sum(w * (self.pass_means - mean) ** 2, axis=0) / (spp - spp / len(w))
        return mean, np.sqrt(var / len(w))


def _to_numpy(img) -> np.ndarray:
    a = np.array(img, dtype=np.float32)
    return a if a.ndim == 3 else a[..., None]


def pass_seed(seed: int, k: int) -> int:
    """Mitsuba seed of pass k: (seed·1_000_003 + k) mod 2³² (mi.render takes a 32-bit seed)."""
    return (int(seed) * 1_000_003 + int(k)) % (1 << 32)


#: Most samples per pixel a render takes: a float32 running sum of more than 2^24 unit
#: contributions no longer grows by one sample's worth (24-bit significand).
MAX_SPP = 1 << 24
#: Most samples one ``mi.render`` call gets (Mitsuba's limit is 2^32 per call in JIT variants).
MAX_SAMPLES_PER_CALL = 1 << 31


def check_spp(spp: int) -> int:
    """``spp`` as an int when a render can take it (1 to :data:`MAX_SPP`), else one sentence."""
    if int(spp) < 1:
        raise PhonglabError(f"spp (samples per pixel) must be >= 1, got {spp}; ask for at "
                            f"least one sample (--spp 1)")
    if int(spp) > MAX_SPP:
        raise PhonglabError(f"spp (samples per pixel) must be at most {MAX_SPP}, got {spp}: a "
                            f"float32 pixel sum loses samples beyond that; render in several "
                            f"files and average them")
    return int(spp)


def render_scene(scene, spp: int, seed: int = 0, passes: int = 1, sensor: int | mi.Sensor = 0,
                 progress: bool = False, integrator=None,
                 keep_passes: bool = False) -> RenderResult:
    """Render ``scene`` with ``spp`` samples per pixel split into ``passes`` equal passes.

    Pass k uses seed :func:`pass_seed` (seed, k); the image is the sample-weighted mean of the
    passes and, with two or more passes, ``stderr`` is the per-pixel standard error of that
    mean (module docstring).  ``integrator`` overrides the scene's; ``keep_passes`` keeps
    every pass image in :attr:`RenderResult.passes`.  ``pass_seconds`` times each pass with
    the image evaluated and copied to numpy (the first includes JIT compilation).
    ``sensor`` is a sensor number of the scene or a sensor of its own
    (:func:`phonglab.engine.scenes.sensor_with_sampler`); a stratified sampler may round each pass's
    count up (:func:`pass_spps`), and the render then has more than ``spp`` samples
    (:attr:`RenderResult.pass_spp`).
    """
    spp = check_spp(spp)
    per_pass = pass_spps(scene, spp, passes, sensor)
    spp = sum(per_pass)
    iterator = range(len(per_pass))
    if progress:
        iterator = tqdm(iterator, desc="rendering", unit="pass", leave=False)
    merged = PassMerge(spp, len(per_pass), keep_passes)
    times = []
    t_start = time.perf_counter()
    for k in iterator:
        t0 = time.perf_counter()
        arr = render_pass(scene, per_pass[k], pass_seed(seed, k), sensor, integrator)
        times.append(time.perf_counter() - t0)
        merged.add(arr, per_pass[k])
    return merged.result(time.perf_counter() - t_start, times)


def pass_spps(scene, spp: int, passes: int, sensor: int | mi.Sensor = 0) -> list[int]:
    """Samples per pixel of each pass of an ``spp`` render in ``passes`` near-equal passes.

    More passes than asked when one ``mi.render`` call would exceed
    :data:`MAX_SAMPLES_PER_CALL` samples; never more passes than samples.  Each count is one
    the sensor's sampler takes as it is: with a stratified sampler every pass has the count
    ⌈spp/passes⌉ rounded up to one it can stratify (``multijitter``: rows × columns, 7 → 8),
    so the render may have more than ``spp`` samples.
    """
    chosen = preflight(scene, "the scene", sensor)
    width, height = (int(v) for v in chosen.film().size())
    # Mitsuba refuses (or splits and then fails) a single render of more than 2^32 samples.
    min_passes = -(-spp * width * height // MAX_SAMPLES_PER_CALL)
    passes = max(1, min_passes, min(int(passes), int(spp)))
    if chosen.sampler().class_name() != "IndependentSampler":  # equal, stratifiable passes
        return [sampler_count(chosen.sampler(), -(-spp // passes))] * passes
    return [spp // passes + (1 if k < spp % passes else 0) for k in range(passes)]


def sampler_count(sampler, n: int) -> int:
    """The samples per pixel ``sampler`` draws when asked for ``n`` (``n`` for ``independent``)."""
    with quiet_mitsuba():  # "sample count rounded up": the caller is asking, not rendering
        previous = sampler.sample_count()
        sampler.set_sample_count(int(n))
        taken = int(sampler.sample_count())
        sampler.set_sample_count(previous)
    return taken


def render_pass(scene, spp: int, mitsuba_seed: int, sensor: int | mi.Sensor = 0,
                integrator=None) -> np.ndarray:
    """One pass: ``mi.render`` with Mitsuba seed ``mitsuba_seed``, as (H, W, C) float64."""
    img = _render_call(scene, spp=spp, seed=mitsuba_seed, sensor=sensor, integrator=integrator)
    dr.eval(img)
    return _to_numpy(img).astype(np.float64)


class PassMerge:
    """The sample-weighted mean of pass images and its per-pixel standard error (module doc).

    Passes are added in pass order (:meth:`add`); the same passes added in the same order
    give bit-identical results wherever they were rendered.
    """

    def __init__(self, spp: int, passes: int, keep_passes: bool = False):
        self.spp, self.passes, self.keep = spp, passes, keep_passes
        self.total = self.total_sq = None
        self.means: list[np.ndarray] = []
        self.weights: list[int] = []
        self.kept: list[np.ndarray] = []

    def add(self, arr: np.ndarray, w: int) -> None:
        """Pass image ``arr`` (float64) of ``w`` samples per pixel."""
        self.means.append(arr.reshape(-1, arr.shape[-1]).mean(axis=0))
        self.weights.append(w)
        if self.keep:
            self.kept.append(arr)
        # Passes of unequal spp are weighted by their sample counts (sums kept in place).
        weighted, squared = arr * w, arr * arr
        squared *= w
        if self.total is None:
            self.total, self.total_sq = weighted, squared
        else:
            self.total += weighted
            self.total_sq += squared

    def result(self, seconds: float, pass_seconds: list[float]) -> RenderResult:
        spp, passes = self.spp, self.passes
        mean = self.total / spp
        stderr = None
        if passes > 1:
            # Pass means are unbiased estimates with variance σ²/spp_k: weighted sample variance.
            var_pass = np.maximum(self.total_sq / spp - mean * mean, 0.0) * spp / (spp - spp / passes)
            stderr = np.sqrt(var_pass / passes).astype(np.float32)
        return RenderResult(mean.astype(np.float32), stderr, seconds, list(pass_seconds),
                            pass_means=np.array(self.means), pass_spp=self.weights,
                            passes=np.stack(self.kept) if self.keep else None)


def relative_sample_variance(result: RenderResult, weight: np.ndarray) -> float:
    """V = n · mean(s² · w): the relative variance one sample of ``result`` carries (n its
    samples per pixel, s its standard error; module docstring), with the metric's weights
    ``w`` ≈ 1/(r² + ε) taken from *other* samples: weights from the render's own image
    (1/(x̄² + ε)) shrink exactly where a rare bright sample inflates s² (a firefly raises x̄
    with it), and underestimated V by 1.4x on textured_room at 16 spp (0.047 against a true
    0.065, measured against its reference).  A stratified render's V is that of its own pass
    size."""
    if result.stderr is None:
        raise ValueError("a render of one pass has no standard error to weigh it by")
    n = float(sum(result.pass_spp)) if result.pass_spp else 1.0
    se2 = result.stderr.astype(np.float64) ** 2
    return n * float(np.mean(se2 * weight))


def precision(result: RenderResult, weight: np.ndarray) -> float:
    """n/V (:func:`relative_sample_variance`): what ``result`` adds to 1/relMSE of a
    combination (inf for a render without noise)."""
    v = relative_sample_variance(result, weight)
    return float(sum(result.pass_spp)) / v if v > 0 else math.inf


@dataclass
class Prior:
    """Earlier renders of the expected image a render makes (other seeds: the planner's pilot),
    to combine it with (:func:`combine_renders`): the renders, their precisions n_j/V_j, and
    the weights ≈ 1/(r² + ε), drawn from other samples than the new render's, that its own
    precision is measured with."""

    renders: tuple[RenderResult, ...]
    precisions: tuple[float, ...]
    weight: np.ndarray

    @property
    def spp(self) -> int:
        """Samples per pixel the renders hold."""
        return int(sum(sum(r.pass_spp) for r in self.renders))


def combine_renders(parts: list[RenderResult], precisions: list[float]) -> RenderResult:
    """Independent unbiased renders of one image, combined with inverse-variance weights
    α_j ∝ n_j/V_j = ``precisions`` (:func:`precision`; module docstring): image Σ α_j x̄_j,
    standard error √(Σ α_j² s_j²).  Every part needs a standard error (two passes or more);
    the result's ``pass_spp`` lists every pass of every part, its ``seconds`` and
    ``pass_seconds`` are the *last* part's (the render; the others were made before it), and
    ``metadata`` records each part's samples and weight (``combined``) and the combination's
    relative noise 1/√(Σ n_j/V_j) (``combined_noise``)."""
    if len(parts) == 1:
        return parts[0]
    prec = list(precisions)
    if any(math.isinf(p) for p in prec):   # a noiseless part: it alone (equal weights among such)
        prec = [1.0 if math.isinf(p) else 0.0 for p in prec]
        noise = 0.0
    else:
        noise = 1.0 / math.sqrt(sum(prec))
    total = float(sum(prec))
    alpha = [p / total for p in prec]
    image = sum(a * part.image.astype(np.float64) for a, part in zip(alpha, parts))
    var = sum(a * a * part.stderr.astype(np.float64) ** 2 for a, part in zip(alpha, parts))
    last = parts[-1]
    meta = dict(last.metadata)
    meta["combined"] = [{"spp": int(sum(p.pass_spp)), "weight": a} for p, a in zip(parts, alpha)]
    meta["combined_noise"] = noise
    # pass_means stay None: the parts' passes have different weights, so their plain spread
    # (RenderResult.mean_and_stderr) is not the combined image's error.
    return RenderResult(image.astype(np.float32), np.sqrt(var).astype(np.float32),
                        last.seconds, list(last.pass_seconds), meta,
                        pass_spp=[s for p in parts for s in p.pass_spp])


def _render_call(scene, **kwargs):
    """``mi.render``, with a plugin's own error unwrapped from Dr.Jit's custom-operation wrapper.

    A Python plugin that raises during the render (whitted refusing an unknown
    ``ambient_reflectance_<id>``) reaches the caller as Dr.Jit's ``RuntimeError: ... error
    while performing a custom differentiable operation``, the plugin's sentence buried in its
    ``__cause__``; that cause is raised instead.
    """
    try:
        return mi.render(scene, **kwargs)
    except RuntimeError as exc:
        if isinstance(exc.__cause__, user_errors()):
            raise exc.__cause__ from None
        raise


@dataclass
class SceneFile:
    """A scene file opened for a render (:func:`open_scene_file`): the loaded scene, the
    ``<default>`` values it is rendered with and the integrator that applies ``max_depth``."""

    path: Path
    scene: Any                        #: the loaded ``mi.Scene``
    params: dict[str, Any]            #: ``<default>`` values of the render (its provenance)
    declared: dict[str, str]          #: the scene's own ``<default>`` entries
    integrator: Any = None            #: replaces the scene's own (None: the scene's)
    max_depth: int | None = None      #: the max_depth asked for (None: the scene's)
    info: SceneInfo | None = None     #: the inspected file, when already at hand
    sensors: dict[str | None, Any] = field(default_factory=dict, repr=False)

    def sensor(self, sampler: str | None = None):
        """The render's sensor, checked by :func:`preflight`: the scene's first, or that
        sensor rebuilt with ``sampler`` when it names another sampler than the scene's
        (:func:`phonglab.engine.scenes.sensor_with_sampler`); built once per sampler."""
        key = None if sampler is None or sampler == self.inspect().sampler else sampler
        if key not in self.sensors:
            self.sensors[key] = preflight(self.scene, self.path, 0 if key is None
                                          else sensor_with_sampler(self.inspect(), key))
        return self.sensors[key]

    def inspect(self) -> SceneInfo:
        """The scene file read by :func:`phonglab.engine.scenes.inspect_scene` with :attr:`params`
        (once)."""
        if self.info is None:
            self.info = inspect_scene(self.path, **self.params)
        return self.info

    def provenance(self, fields: dict[str, Any], seconds: float) -> dict[str, Any]:
        """The EXR header of a render of this file: scene, hash and variant, the sampling's
        own ``fields``, render time, parameters and versions."""
        return {"scene": str(self.path), "scene_sha256": file_hash(self.path),
                "variant": mi.variant(), **fields, "render_seconds": round(seconds, 4),
                "params": {k: str(v) for k, v in self.params.items()},
                "phonglab_version": __version__, "mitsuba_version": mi.__version__}


def open_scene_file(scene: str | Path, *, variant: str | None = None,
                    max_depth: int | None = None, params: dict[str, Any] | None = None,
                    settings: dict[str, Any] | None = None, integrator: dict | None = None,
                    loaded=None, info: SceneInfo | None = None,
                    quiet: bool = False) -> SceneFile:
    """Load ``scene`` for a render with ``params`` for its ``<default>`` entries.

    ``max_depth`` and ``settings`` (``{"spp": 64}``) override the scene's ``<default>`` of that
    name when it declares one (they win over ``params``).  ``max_depth`` applies to the scene's
    own integrator: through its ``$max_depth`` default when it has one, else by rebuilding the
    integrator with ``max_depth`` set (refused, with the reason, when that integrator takes no
    depth).  ``integrator`` (a ``mi.load_dict`` dictionary: the planner's models) replaces the
    scene's.  ``loaded`` is the scene already loaded from this file with ``params`` in the
    active variant (the planner's pilot scene, with its ``info``): it is used as it is, and a
    declared ``max_depth`` is applied by rebuilding the integrator instead of by reloading
    (the same integrator); ``quiet`` silences Mitsuba's warnings while loading.
    """
    path = scene_path(scene)
    declared = scene_defaults(path)
    given = {k: v for k, v in (params or {}).items() if v is not None}
    merged = dict(given, **{k: v for k, v in dict(settings or {}, max_depth=max_depth).items()
                            if v is not None and k in declared})
    reuse = loaded is not None
    if reuse and max_depth is not None and "max_depth" in declared:
        info = info or inspect_scene(path, **given)
        reuse = info.integrator_dict is not None   # else reload with $max_depth
    if not reuse:
        with quiet_mitsuba() if quiet else contextlib.nullcontext():
            loaded = load_scene(path, variant, **merged)
        info = None
    sf = SceneFile(path, loaded, merged, declared, max_depth=max_depth, info=info)
    if integrator is not None:
        sf.integrator = mi.load_dict(integrator)
    elif max_depth is not None and ("max_depth" not in declared or reuse):
        sf.integrator = integrator_with_depth(sf.inspect(), max_depth)
    return sf


@dataclass
class UniformPasses:
    """Uniform sampling for :func:`render_scene_file`: ``spp`` samples per pixel (the scene's
    when None) in ``passes`` passes (8 from 16 spp on, else 1) through :func:`render_scene`,
    with the scene's sampler or ``sampler`` (a Mitsuba sampler name).  ``prior``: earlier
    renders of the same expected image with other seeds (the planner's pilot, :class:`Prior`),
    combined with this one by :func:`combine_renders`."""

    spp: int | None = None
    passes: int | None = None
    sampler: str | None = None
    progress: bool = True
    prior: Prior | None = None
    #: Mitsuba's warnings are left on while the scene loads
    quiet_load = False

    def variant(self, variant: str | None) -> str | None:
        """The variant to load in: the one given, else the active one (:func:`load_scene`)."""
        return variant

    def settings(self) -> dict[str, Any]:
        """The ``<default>`` entries this sampling sets when the scene declares them."""
        return {"spp": self.spp}

    def __post_init__(self) -> None:
        """``spp`` is checked here, where it enters (one sentence)."""
        if self.spp is not None:
            check_spp(self.spp)

    def render(self, sf: SceneFile, seed: int) -> tuple[RenderResult, dict[str, Any]]:
        """The render and its header fields (spp, passes, seed, sampler, integrator, depth,
        and the film's channel names where they are not R, G, B / Y / R, G, B, A)."""
        spp = int(self.spp or sf.sensor().sampler().sample_count())
        sensor = sf.sensor(self.sampler)
        channels = film_channels(sensor, sf.integrator or sf.scene.integrator(), sf.path)
        passes = self.passes or (min(spp, 8) if spp >= 16 else 1)
        result = render_scene(sf.scene, spp, seed=seed, passes=passes, progress=self.progress,
                              integrator=sf.integrator, sensor=sensor)
        rendered = int(sum(result.pass_spp))
        reused = {}
        if self.prior is not None:
            result = combine_renders([*self.prior.renders, result],
                                     [*self.prior.precisions, precision(result, self.prior.weight)])
            reused = {"reused_spp": self.prior.spp,
                      "combined": result.metadata["combined"],
                      "combined_noise": result.metadata["combined_noise"]}
        integrator = sf.integrator or sf.scene.integrator()
        name = (integrator.class_name() if hasattr(integrator, "class_name")
                else str(type(integrator)))
        named = {} if channels in exr.SHAPE_NAMED else {"channels": channels}
        return result, {"spp": rendered, "passes": passes, "seed": seed,
                        "sampler": sensor.sampler().class_name(), "integrator": name,
                        "max_depth": max_depth_of(integrator), **named, **reused}

    def extra_files(self, out: Path, result) -> list:
        """Files beyond the image set (none)."""
        return []


def film_channels(sensor, integrator, path: str | Path = "the scene") -> list[str]:
    """The channel names of ``sensor``'s film as ``integrator`` fills it, checked first.

    The film's own layout (its ``pixel_format``: R, G, B; R, G, B, A; X, Y, Z; Y; Y, A), read
    from the film once prepared.  Refused in one sentence, before any sample: an integrator
    with arbitrary output variables (``aov``, alone or around another), whose channels
    ``mi.render`` does not return as the film lays them out (an ``aov`` of nn:sh_normal and
    dd:depth gives 4 channels against the film's R, G, B, nn.X, nn.Y, nn.Z, dd.T), and which
    are not radiance for phonglab to compare, plan or preview.
    """
    aovs = list(integrator.aov_names())
    if aovs:
        shown = ", ".join(aovs[:4]) + (", ..." if len(aovs) > 4 else "")
        raise SceneError(f"{path}: its {integrator.class_name()} integrator writes arbitrary "
                         f"output variables ({shown}), not radiance alone; phonglab renders "
                         f"radiance images, so render the AOVs with Mitsuba itself (mi.render) "
                         f"or give the scene a radiance integrator")
    film = sensor.film()
    film.prepare([])
    struct = film.bitmap().struct_()
    return [struct[i].name for i in range(len(struct)) if struct[i].name != "W"]


def render_scene_file(scene: str | Path, out: str | Path, sampling=None, *,
                      variant: str | None = None, seed: int = 0, max_depth: int | None = None,
                      params: dict[str, Any] | None = None, integrator: dict | None = None,
                      png: bool = True, extra_metadata: dict[str, Any] | None = None,
                      loaded=None, info: SceneInfo | None = None):
    """The one render of a scene file: check, load, render, write ``out`` with provenance.

    ``sampling`` is :class:`UniformPasses` (the default) or
    :class:`phonglab.engine.adaptive.AdaptiveSampling`, whose arguments were checked when it
    was made: its ``settings()`` (``<default>`` entries it sets), ``render(scene_file, seed)
    -> (result, header fields)`` and ``extra_files(out, result)`` (members it adds to the file
    set: the spp map).  Everything that can be checked is checked before the render starts:
    the arguments (first, by the sampling), every file of the set
    (:class:`phonglab.engine.outputs.RenderOutputs`), the scene (:func:`preflight`).  The scene is opened by :func:`open_scene_file` (``variant``,
    ``max_depth``, ``params``, ``integrator``, ``loaded``, ``info``).  ``extra_metadata`` is
    added to the EXR header (the planner records its plan there); with ``png`` a preview is
    written at the auto exposure (darken only).  The image, standard error, preview and spp
    map are replaced as one set, and members this render does not produce are removed.
    """
    sampling = sampling or UniformPasses()
    outputs = RenderOutputs.beside(out, png)
    outputs.check()
    sf = open_scene_file(scene, variant=sampling.variant(variant), max_depth=max_depth,
                         params=params, settings=sampling.settings(), integrator=integrator,
                         loaded=loaded, info=info, quiet=sampling.quiet_load)
    result, fields = sampling.render(sf, seed)
    result.metadata = sf.provenance(fields, result.seconds)
    result.metadata.update(extra_metadata or {})
    ev = auto_exposure(result.image, darken_only=True) if png else 0.0
    if png:
        result.metadata["preview_exposure_ev"] = round(ev, 2)
    result.metadata["render_id"] = outputs.write(result.image, result.stderr, result.metadata,
                                                 exposure=ev,
                                                 extras=sampling.extra_files(Path(out), result))
    return result


def render_file(scene: str | Path, out: str | Path, spp: int | None = None,
                variant: str | None = None, seed: int = 0, passes: int | None = None,
                max_depth: int | None = None, progress: bool = True,
                png: bool = True, extra_metadata: dict[str, Any] | None = None,
                sampler: str | None = None,
                params: dict[str, Any] | None = None) -> RenderResult:
    """Load, render and write ``out`` (EXR with provenance) plus its standard error and a PNG.

    A uniform render (:class:`UniformPasses`) through :func:`render_scene_file`: ``spp``
    (checked first; the scene's own when None) in ``passes``, the scene's sampler or
    ``sampler``.  ``max_depth`` applies to the scene's own integrator (its ``$max_depth``
    default, else the integrator rebuilt with it: :func:`open_scene_file`); ``params`` are
    values for the scene's ``<default>`` entries (``{"res": 256}``; ``spp`` and
    ``max_depth`` given above win).  ``extra_metadata`` is added to the EXR header.
    """
    return render_scene_file(scene, out, UniformPasses(spp, passes, sampler, progress),
                             variant=variant, seed=seed, max_depth=max_depth, params=params,
                             png=png, extra_metadata=extra_metadata)


#: Host memory one film pixel costs through a render (Mitsuba's image block, the float64
#: sums of :func:`render_scene`, the numpy copies): measured 136 bytes per RGB pixel
#: (cornell_phong, llvm_ad_rgb, 1024² vs 2048², independent of spp), rounded up.
BYTES_PER_PIXEL = 160
#: Fixed cost of a render process (Python, Mitsuba, Dr.Jit, kernels): measured ~200 MB.
BASE_BYTES = 256 << 20


def preflight(scene, path: str | Path, sensor: int | mi.Sensor = 0):
    """The scene's sensor number ``sensor`` (or ``sensor`` itself, a sensor built apart from
    the scene), once the render is known to be possible.

    Raises:
        SceneError: no sensor, a film without pixels, or a film whose render would need more
            memory than this process can have (estimated as BASE_BYTES + BYTES_PER_PIXEL per
            pixel: the render is refused before anything is allocated).
    """
    sensors = [sensor] if isinstance(sensor, mi.Sensor) else scene.sensors()
    sensor = 0 if isinstance(sensor, mi.Sensor) else sensor
    if not sensors:
        raise SceneError(f"{path}: the scene has no <sensor>; add a camera (e.g. <sensor "
                         f"type=\"perspective\">) with a <film>")
    if not 0 <= sensor < len(sensors):
        raise SceneError(f"{path}: there is no sensor number {sensor}; the scene has "
                         f"{len(sensors)} (numbered from 0)")
    width, height = (int(v) for v in sensors[sensor].film().size())
    if width < 1 or height < 1:
        raise SceneError(f"{path}: the film is {width} x {height} pixels; give it a width and "
                         f"height of at least 1 (e.g. res=64)")
    require_memory(BASE_BYTES + BYTES_PER_PIXEL * width * height,
                   f"{path}: a {width} x {height} render", "lower the resolution (res=...)",
                   error=SceneError)
    return sensors[sensor]


def max_depth_of(integrator) -> int | None:
    """The max_depth an integrator was built with (its traversed parameter, else the value its
    description prints), or None when it has none."""
    try:
        params = mi.traverse(integrator)
        if "max_depth" in params:
            return int(params["max_depth"])
    except Exception:
        pass
    text = str(integrator)
    m = re.search(r"max_depth\s*=\s*(-?\d+)", text)
    return int(m.group(1)) if m else None
