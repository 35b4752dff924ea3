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

       b(d)² = mean_pixels[ (mean_k D_k)² − var_k(D_k)/P ] / (r + eps)²

   (the subtraction makes it an unbiased estimate of the squared mean, so pure noise does not
   pass for bias; the weights 1/(r + eps)² come from a second full-depth pilot with other seeds,
   see :func:`_weights`).  The plan takes the smallest d with
   ``b(d) <= BIAS_FRACTION · E`` (candidates 1, 2, 3, 4, 6, 8, 12, ... then bisection, b being
   non-increasing in d).  Delta chains (glass, mirrors) need no special rule: the energy they
   carry shows in D_k, so the search follows them as deep as they carry energy; the scene's
   delta BSDFs are listed in the reasons.

3. **spp**, from the pilot's per-pixel variance at the chosen depth.  With ``σ²`` the variance
   of one sample (``P`` pass means of ``s`` samples each: ``σ² = s · var_k(pass_k)``), N samples
   per pixel leave the noise ``n(N)² = mean_pixels[σ² / (r + eps)²] / N``.  The plan takes the
   smallest N with ``b(d)² + n(N)² <= E²``; the predicted error is ``√(b(d)² + n(N)²)``.

The error is :func:`phonglab.render.relative_rmse` with ``eps = 0.01`` (:data:`EPS`):
``E = √mean(((x − r)/(|r| + eps))²)`` over every pixel and channel, ``r`` the converged
full-depth image; the same definition is used when the achieved error is measured
(:func:`achieved_error`).  Monte Carlo noise falls as ``1/√N``, so E² is the sum of the
squared depth bias and the variance term: MSE = bias² + variance (E. Veach, *Robust Monte Carlo
Methods for Light Transport Simulation*, PhD thesis, Stanford 1997, §2.4.3; M. Pharr, W. Jakob,
G. Humphreys, *Physically Based Rendering*, 4th ed., §2.1.4, and §2.2.4 on Russian roulette).

The predicted time is steady state (JIT compile excluded): the pilot times renders of ``s`` and
``4s`` samples per pixel at the chosen depth, alternating, and fits ``T(spp) = a + b·spp``
(medians); a render of N samples in ``p`` passes is predicted to take ``p·a + b·N``.
"""

from __future__ import annotations

import contextlib
import dataclasses
import hashlib
import json
import math
import re
import time
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from . import exr, render
from .render import PhonglabError

#: eps of the relative error: E = √mean(((x − r)/(|r| + EPS))²) (phonglab.render.relative_rmse).
EPS = 1e-2
#: The depth bias may use at most this fraction of the target error (b(d) <= BIAS_FRACTION · E).
BIAS_FRACTION = 0.25
#: Candidate depths, searched in order, then bisected between the last failing and first passing.
DEPTH_LADDER = (1, 2, 3, 4, 6, 8, 12, 16, 24, 32, 48, 64)
#: Pilot: total samples per pixel, split into this many passes of equal size (same seeds per depth).
PILOT_SPP = 64
PILOT_PASSES = 8
#: Seed of the pilot (pass k uses seed·1_000_003 + k, as render_scene does); renders use seed 0.
PILOT_SEED = 1
#: Where references and benchmark data are cached (git-ignored).
CACHE_DIR = render.REPO_ROOT / ".bench_cache"
#: Rec. 709 luminance, which Mitsuba's mono variants take of an <rgb> value.
LUMINANCE = np.array([0.212671, 0.715160, 0.072169])

_DELTA_BSDFS = {"dielectric", "thindielectric", "conductor", "polarizer", "retarder"}
_PASSTHROUGH = {"twosided", "mask", "bumpmap", "normalmap", "blendbsdf"}


# --------------------------------------------------------------------------------------------
# Scene inspection (XML only)
# --------------------------------------------------------------------------------------------

@dataclass
class SceneInfo:
    """What the scene file says about colour, spectra, delta BSDFs and its integrator."""

    path: Path
    defaults: dict[str, str]
    colored: list[str] = field(default_factory=list)      #: descriptions of non-gray values
    spectral: list[str] = field(default_factory=list)     #: descriptions of spectral data
    delta_bsdfs: list[str] = field(default_factory=list)  #: "dielectric 'glass'" ...
    integrator: str = "path"
    integrator_props: dict[str, str] = field(default_factory=dict)
    gray_values: int = 0                                  #: gray colour values seen
    bsdf_types: set[str] = field(default_factory=set)     #: every <bsdf type=...> in the file

    @property
    def color(self) -> str:
        """'spectral', 'rgb' or 'mono': the leanest colour model the scene's data needs."""
        if self.spectral:
            return "spectral"
        if self.colored:
            return "rgb"
        return "mono"


def _parse(path: Path) -> ET.Element:
    try:
        return ET.parse(path).getroot()
    except ET.ParseError as exc:
        line = exc.position[0] if exc.position else "?"
        raise PhonglabError(f"{path}: malformed XML at line {line}: {exc}; fix the markup "
                            f"there (unclosed tag or stray character).") from None


def _substitute(root: ET.Element, values: dict[str, str], path: Path) -> None:
    """Replace ``$name`` in every attribute by its value, as Mitsuba's loader does."""
    pattern = re.compile(r"\$(\w+)")

    def repl(m: re.Match) -> str:
        if m.group(1) not in values:
            raise PhonglabError(f"{path}: '${m.group(1)}' is used but has no <default> and no "
                                f"value was given; add <default name=\"{m.group(1)}\" "
                                f"value=\"...\"/> to the scene or pass it as a parameter.")
        return values[m.group(1)]

    for el in root.iter():
        for key, value in el.attrib.items():
            if "$" in value:
                el.set(key, pattern.sub(repl, value))


def _floats(text: str) -> list[float]:
    return [float(t) for t in re.split(r"[,\s]+", text.strip()) if t]


def _is_gray(values: list[float]) -> bool:
    scale = max(abs(v) for v in values) or 1.0
    return max(values) - min(values) <= 1e-6 * scale


def _owner(parents: dict, el: ET.Element) -> str:
    """A short description of the plugin an element belongs to: "bsdf 'red' (lambert)"."""
    p = parents.get(el)
    while p is not None and p.tag not in ("bsdf", "emitter", "texture", "medium", "shape",
                                          "phase", "sensor"):
        p = parents.get(p)
    if p is None:
        return "the scene"
    ident = p.get("id")
    return f"{p.tag} {ident!r} ({p.get('type')})" if ident else f"{p.tag} ({p.get('type')})"


def _bitmap_is_gray(filename: Path) -> bool | None:
    """True/False when the image file's channels are (not) all equal; None when unreadable."""
    try:
        import mitsuba as mi

        if mi.variant() is None:
            render.registration.register()
        arr = np.array(mi.Bitmap(str(filename)), dtype=np.float64)
    except Exception:
        return None
    if arr.ndim < 3 or arr.shape[2] == 1:
        return True
    rgb = arr[..., :3]
    return bool(np.all(np.abs(rgb - rgb[..., :1]) <= 1e-6 * max(1.0, float(np.abs(rgb).max()))))


def inspect_scene(scene: str | Path, **params) -> SceneInfo:
    """Read a scene file's colours, spectral data, delta BSDFs and integrator (no rendering).

    ``params`` override the scene's ``<default>`` values, as in :func:`render.load_scene`.
    ``<include>``\\ d files are inspected too.  Unused definitions count (a coloured BSDF that
    nothing references still makes the scene ``rgb``): the inspection errs towards more colour.
    """
    path = render.scene_path(scene)
    root = _parse(path)
    defaults = {d.get("name"): d.get("value") for d in root.iter("default") if d.get("name")}
    values = dict(defaults)
    values.update({k: str(v) for k, v in params.items() if v is not None})
    _substitute(root, values, path)
    info = SceneInfo(path=path, defaults=defaults)
    _scan(root, path, info, values)
    integ = root.find("integrator")
    if integ is not None:
        info.integrator = integ.get("type", "path")
        info.integrator_props = {c.get("name"): c.get("value") for c in integ
                                 if c.get("name") and c.get("value") is not None}
    return info


def _scan(root: ET.Element, path: Path, info: SceneInfo, values: dict[str, str]) -> None:
    parents = {c: p for p in root.iter() for c in p}
    for el in root.iter():
        where = _owner(parents, el)
        name = el.get("name", "")
        if el.tag == "include" and el.get("filename"):
            sub = (path.parent / el.get("filename")).resolve()
            sub_root = _parse(sub)
            _substitute(sub_root, values, sub)
            _scan(sub_root, sub, info, values)
        elif el.tag == "rgb":
            try:
                vals = _floats(el.get("value", ""))
            except ValueError:
                raise PhonglabError(f"{path}: <rgb name={name!r}> of {where} has value "
                                    f"{el.get('value')!r}; write three numbers like "
                                    f"\"0.5, 0.5, 0.5\".") from None
            if vals and not _is_gray(vals):
                info.colored.append(f"{where} {name} = ({el.get('value')})")
            else:
                info.gray_values += 1
        elif el.tag == "spectrum":
            kind, value = el.get("type"), el.get("value")
            if el.get("filename"):
                info.spectral.append(f"{where} {name} reads spectral file {el.get('filename')}")
            elif kind and kind not in ("uniform",):
                info.spectral.append(f"{where} {name} is a '{kind}' spectrum")
            elif value is not None and ":" in value:
                info.spectral.append(f"{where} {name} lists wavelengths ({value[:40]})")
            else:
                info.gray_values += 1
        elif el.tag == "texture" and el.get("type") == "bitmap":
            for c in el:
                if c.get("name") == "filename":
                    gray = _bitmap_is_gray(path.parent / c.get("value", ""))
                    if not gray:
                        info.colored.append(f"{where} bitmap {c.get('value')} "
                                            f"({'not gray' if gray is False else 'unreadable'})")
                    else:
                        info.gray_values += 1
        elif el.tag == "emitter" and el.get("type") in ("envmap",):
            for c in el:
                if c.get("name") == "filename":
                    gray = _bitmap_is_gray(path.parent / c.get("value", ""))
                    if not gray:
                        info.colored.append(f"{where} environment map {c.get('value')}")
        elif el.tag == "emitter" and el.get("type") in ("sunsky", "sky", "sun"):
            info.colored.append(f"{where}: a sky model is coloured")
        if el.tag == "bsdf":
            kind = el.get("type")
            info.bsdf_types.add(kind)
            if kind == "conductor":
                material = next((c.get("value") for c in el if c.get("name") == "material"),
                                "none")
                if material != "none":
                    info.spectral.append(f"{where} uses measured spectral IOR data "
                                         f"(material {material!r})")
            if kind in _DELTA_BSDFS:
                ident = el.get("id")
                info.delta_bsdfs.append(f"{kind} {ident!r}" if ident else kind)


# --------------------------------------------------------------------------------------------
# Variant
# --------------------------------------------------------------------------------------------

def available_backend() -> tuple[str, str]:
    """The best JIT backend that works on this machine, and why: cuda > llvm > scalar.

    ``cuda`` needs Mitsuba's ``cuda_*`` variants and a CUDA device Dr.Jit can initialise
    (``drjit.has_backend``); ``llvm`` needs a libLLVM Dr.Jit 1.5 can use (:mod:`phonglab.llvm`).
    """
    import drjit as dr
    import mitsuba as mi

    from . import llvm

    variants = set(mi.variants())
    cuda_why = "Mitsuba has no cuda_* variants"
    if any(v.startswith("cuda_") for v in variants):
        try:
            if dr.has_backend(dr.JitBackend.CUDA):
                return "cuda", "Dr.Jit found a CUDA device (cuda > llvm > scalar)"
            cuda_why = "no CUDA device or driver (drjit.has_backend(CUDA) is False)"
        except Exception as exc:  # pragma: no cover - depends on the driver
            cuda_why = f"CUDA failed to initialise ({exc})"
    choice = llvm.configure()
    if choice.usable and any(v.startswith("llvm_") for v in variants):
        try:
            if dr.has_backend(dr.JitBackend.LLVM):
                return "llvm", f"LLVM JIT usable; {cuda_why}"
        except Exception:  # pragma: no cover
            pass
    return "scalar", (f"no JIT backend: {cuda_why}; LLVM: {choice.reason} (scalar runs Python "
                      f"BSDFs about 150x slower)")


def variant_for(color: str, backend: str, polarized: bool = False) -> tuple[str, list[str]]:
    """The Mitsuba variant for a colour model and backend, stepping up when one is not built.

    Mitsuba builds no ``*_rgb_polarized`` and (here) no ``scalar_mono``: the next richer colour
    model is used then (mono -> rgb -> spectral), with a note.
    """
    import mitsuba as mi

    available = set(mi.variants())
    notes: list[str] = []
    order = ["mono", "rgb", "spectral"]
    for c in order[order.index(color):]:
        name = f"{backend}_ad_{c}" if backend != "scalar" else f"scalar_{c}"
        if polarized:
            name += "_polarized"
        if name in available:
            if c != color:
                notes.append(f"{color} needs {backend}_{color}{'_polarized' if polarized else ''}, "
                             f"which this Mitsuba lacks: using {name}")
            return name, notes
    raise PhonglabError(f"no Mitsuba variant for {color} on the {backend} backend"
                        f"{' with polarization' if polarized else ''} (have: "
                        f"{', '.join(sorted(available))}); install a Mitsuba build with one.")


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


@contextlib.contextmanager
def quiet_mitsuba():
    """Silence Mitsuba's warnings (mono's "film set to luminance") inside the block."""
    import mitsuba as mi

    logger = mi.logger()
    old = logger.log_level()
    logger.set_log_level(mi.LogLevel.Error)
    try:
        yield
    finally:
        logger.set_log_level(old)


def _path_integrator(depth: int, info: SceneInfo):
    import mitsuba as mi

    d: dict[str, Any] = {"type": "path", "max_depth": int(depth)}
    for key, cast in (("rr_depth", int), ("hide_emitters", lambda s: s.lower() == "true")):
        if key in info.integrator_props:
            d[key] = cast(info.integrator_props[key])
    return mi.load_dict(d)


def _render_passes(scene, integrator, spp_per_pass: int, passes: int, seed: int):
    """Images of ``passes`` independent passes (seed·1_000_003 + k), and their wall times."""
    import drjit as dr
    import mitsuba as mi

    images, times = [], []
    for k in range(passes):
        t0 = time.perf_counter()
        img = mi.render(scene, spp=spp_per_pass, seed=render.pass_seed(seed, k), integrator=integrator)
        dr.eval(img)
        arr = np.array(img, dtype=np.float64)
        times.append(time.perf_counter() - t0)
        images.append(arr if arr.ndim == 3 else arr[..., None])
    return np.stack(images), times


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
    """Per-pixel weights ≈ 1/(r + eps)² from P pass images of an unbiased estimate of r.

    With r̂ the pass mean and se² its squared standard error, the delta method gives
    E[1/(r̂ + eps)²] ≈ (1 + 3 se²/(r + eps)²)/(r + eps)², so dividing by that factor removes
    the second-order bias a noisy r̂ would add (dark, noisy pixels would otherwise dominate).
    """
    r = np.abs(passes_img.mean(axis=0)) + EPS
    se2 = passes_img.var(axis=0, ddof=1) / passes_img.shape[0]
    return 1.0 / (r * r) / (1.0 + 3.0 * se2 / (r * r))


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
        scene = render.load_scene(info.path, variant, **params)
    film = scene.sensors()[0].film()
    resolution = (int(film.size()[0]), int(film.size()[1]))
    scene_spp = int(scene.sensors()[0].sampler().sample_count())

    # 2. Pilot at full depth: the reference the depth bias is measured against.
    s = pilot_spp // pilot_passes
    full, _ = _render_passes(scene, _path_integrator(-1, info), s, pilot_passes, seed)
    # The weights 1/(r + eps)² come from an independent full-depth pilot (other seeds): taken
    # from `full` itself they would shrink exactly where a rare bright sample inflates the
    # variance (a caustic firefly raises both), and the noise would be underestimated.
    indep, _ = _render_passes(scene, _path_integrator(-1, info), s, pilot_passes, seed + 1)
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
                imgs, times = _render_passes(scene, _path_integrator(d, info), s,
                                             pilot_passes, seed)
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
    integrator = _path_integrator(depth, info)
    if depth not in timings:  # compile the kernel before timing
        _render_passes(scene, integrator, 1, 1, seed + 99)
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


# --------------------------------------------------------------------------------------------
# Errors and references
# --------------------------------------------------------------------------------------------

def to_luminance(image: np.ndarray) -> np.ndarray:
    """(H, W, 1) luminance of an (H, W, 3) linear Rec. 709 image (what mono renders)."""
    image = np.asarray(image, dtype=np.float64)
    if image.ndim == 3 and image.shape[2] == 3:
        return (image @ LUMINANCE)[..., None]
    return image if image.ndim == 3 else image[..., None]


def _match(image: np.ndarray, other: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    image = np.asarray(image, np.float64)
    other = np.asarray(other, np.float64)
    image = image if image.ndim == 3 else image[..., None]
    other = other if other.ndim == 3 else other[..., None]
    if image.shape[2] != other.shape[2]:
        image, other = to_luminance(image), to_luminance(other)
    if image.shape != other.shape:
        raise PhonglabError(f"cannot compare images of shapes {image.shape} and {other.shape}; "
                            f"render the reference at the same resolution.")
    return image, other


def noise_error(image: np.ndarray, stderr: np.ndarray) -> float:
    """√mean((stderr/(|image| + EPS))²): the relative noise of an image, from its passes."""
    image, stderr = _match(image, stderr)
    return math.sqrt(float(np.mean((stderr / (np.abs(image) + EPS)) ** 2)))


def achieved_error(image: np.ndarray, reference: np.ndarray,
                   reference_stderr: np.ndarray | None = None) -> float:
    """The relative RMSE of ``image`` against ``reference``, corrected for the reference's noise.

    ``relative_rmse(image, reference)²`` has expectation E² + mean((se_ref/(r + EPS))²) when
    the reference carries independent noise of standard error se_ref; that second term is
    subtracted (clamped at 0).  A mono image is compared with the luminance of an RGB reference.
    """
    image, reference = _match(image, reference)
    raw2 = render.relative_rmse(image, reference, eps=EPS) ** 2
    if reference_stderr is not None:
        _, se = _match(image, reference_stderr)
        raw2 -= float(np.mean((se / (np.abs(reference) + EPS)) ** 2))
    return math.sqrt(max(raw2, 0.0))


def reference_key(scene: str | Path, params: dict[str, Any] | None = None,
                  variant: str = "llvm_ad_rgb") -> str:
    """Cache key of a reference: scene file contents, parameters and variant."""
    path = render.scene_path(scene)
    h = hashlib.sha256(path.read_bytes())
    h.update(json.dumps(sorted((k, str(v)) for k, v in (params or {}).items())).encode())
    h.update(variant.encode())
    return f"{path.stem}-{h.hexdigest()[:12]}"


def reference_variant(scene: str | Path, params: dict[str, Any] | None = None) -> str:
    """rgb for a reference unless the scene carries spectral data (then spectral)."""
    backend, _ = available_backend()
    color = "spectral" if inspect_scene(scene, **(params or {})).color == "spectral" else "rgb"
    return variant_for(color, backend)[0]


def cached_reference(scene: str | Path, params: dict[str, Any] | None = None,
                     cache_dir: Path = CACHE_DIR):
    """(image, stderr, metadata) of a cached reference for the scene and params, or None."""
    try:
        variant = reference_variant(scene, params)
    except PhonglabError:
        return None
    path = Path(cache_dir) / "references" / (reference_key(scene, params, variant) + ".exr")
    se_path = path.with_name(path.stem + ".stderr.exr")
    if not (path.is_file() and se_path.is_file()):
        return None
    image, meta = exr.read(path)
    stderr, _ = exr.read(se_path)
    return image, stderr, meta


def make_reference(scene: str | Path, spp: int, params: dict[str, Any] | None = None,
                   passes: int = 16, seed: int = 12345, cache_dir: Path = CACHE_DIR,
                   progress: bool = False):
    """Render (or load from the cache) a converged reference: max_depth -1, ``spp`` samples.

    The reference is unbiased in depth (Russian roulette ends its paths) and carries a
    per-pixel standard error from ``passes`` passes, which :func:`achieved_error` subtracts.
    A cached one with at least ``spp`` samples is reused.  Returns (image, stderr, metadata).
    """
    params = dict(params or {})
    cached = cached_reference(scene, params, cache_dir)
    if cached is not None and int(cached[2].get("spp", 0)) >= spp:
        return cached
    variant = reference_variant(scene, params)
    info = inspect_scene(scene, **params)
    with quiet_mitsuba():
        loaded = render.load_scene(info.path, variant, **params)
    result = render.render_scene(loaded, spp, seed=seed, passes=passes, progress=progress,
                                 integrator=_path_integrator(-1, info))
    meta = {"scene": str(info.path), "scene_sha256": render.file_hash(info.path),
            "variant": variant, "spp": spp, "passes": passes, "seed": seed, "max_depth": -1,
            "params": {k: str(v) for k, v in params.items()},
            "render_seconds": round(result.seconds, 3)}
    path = Path(cache_dir) / "references" / (reference_key(scene, params, variant) + ".exr")
    exr.write(path, result.image, meta)
    exr.write(path.with_name(path.stem + ".stderr.exr"), result.stderr, meta)
    return result.image, result.stderr, meta


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
