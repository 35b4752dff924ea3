r"""Speed against accuracy: the sweeps behind ``phonglab bench`` and BENCHMARKS.md.

What is measured (every row is written to CSV the moment it is finished; a
re-run skips rows already present, so an interrupted bench resumes):

* ``estimators`` — the five reflection-equation estimators of
  :mod:`phonglab.estimators` on two problems (modified Phong k_d = 0.5, k_s = 0.3,
  p = 100, θ_i = 30°, under a constant light and under a 3° disk light at the mirror
  direction): for each N, the RMSE against the exact value over S seeds, the pooled
  per-sample variance, and the steady-state wall time of one N-sample estimate.
* ``stability`` — every estimator × exponent p ∈ {0, 1, 10, 10², 10³, 10⁴, 10⁵} ×
  θ_i ∈ {0°, 30°, 60°, 80°, 89°, 89.9°} × {constant, 1° disk} light, pure specular
  lobe (k_d = 0, k_s = 1), at a fixed budget of N = 2¹⁴ samples per estimate.
  Verdict "breaks down" when NaN/Inf appear, the relative RMSE exceeds
  :data:`BREAKDOWN_REL_RMSE`, or an error of more than :data:`BIAS_FLOOR` is not
  explained by the estimator's own standard error (|z| > z_crit: bias, or a "silent"
  failure where no sample found the light and the reported standard error is 0).
* ``renders`` — the Cornell box (``scenes_xml/cornell_phong.xml``, 32 px): RMSE
  against a cached high-sample reference versus spp and time for ``lambert`` vs
  ``diffuse`` (every surface of that BSDF) and ``phong`` vs ``plastic`` vs
  ``roughplastic`` boxes (walls ``diffuse``; the look match is in :func:`cornell_xml`).
* ``variants`` — ``llvm_ad_rgb`` against ``scalar_rgb`` on a 16 px Cornell box
  (``cuda_ad_rgb`` when Dr.Jit finds a CUDA device; skipped with a note otherwise).
* ``ratios`` — render-time ratios lambert/diffuse, phong/plastic, phong/roughplastic on
  the same scene, spp and variant: A/B pairs in alternating order (ABBA), the median
  of the per-pair ratios (drift and other processes cancel within a pair).
* ``jit`` — JIT compile time separately from steady state: the first call's wall time,
  Dr.Jit's own codegen + LLVM backend time of that call (kernel history), and a cold
  compile measured in a subprocess whose kernel cache (``$HOME/.drjit``) is empty.

Steady state = median of repeats after a warm-up call.  Charts (matplotlib, Agg):
error against time on log-log axes, one curve per method, the Pareto front marked;
the stability heatmaps.  :func:`write_markdown` turns the CSVs into BENCHMARKS.md.
"""

from __future__ import annotations

import csv
import hashlib
import json
import math
import os
import platform
import re
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Iterable

import numpy as np

from ..physics.estimators import METHODS, Problem, ReflectionEstimators, exact_value
from ..scenes import REPO_ROOT
from ..errors import PhonglabError

DEFAULT_CACHE = REPO_ROOT / ".bench_cache"
DEFAULT_OUT = Path("out") / "bench"

#: Relative RMSE at the stability budget past which an estimator "breaks down".
BREAKDOWN_REL_RMSE = 0.10
#: Per-sample relative standard deviation below which a strategy counts as near-zero-variance.
NEAR_ZERO_REL_SD = 0.05
#: Smallest relative bias that counts as a failure when it is statistically significant.
BIAS_FLOOR = 0.01
STABILITY_N = 1 << 14
STABILITY_EXPONENTS = (0.0, 1.0, 10.0, 100.0, 1e3, 1e4, 1e5)
STABILITY_ANGLES = (0.0, 30.0, 60.0, 80.0, 89.0, 89.9)
STABILITY_LIGHTS = {"constant": dict(light="constant"), "disk 1deg": dict(light="disk", half_angle=1.0)}

#: The two estimator problems of the error-versus-time charts.
ESTIMATOR_SCENES = {
    "env p=100": Problem(bsdf="phong", diffuse_reflectance=0.5, specular_reflectance=0.3,
                         exponent=100.0, theta_i=30.0, light="constant"),
    "disk3 p=100": Problem(bsdf="phong", diffuse_reflectance=0.5, specular_reflectance=0.3,
                           exponent=100.0, theta_i=30.0, light="disk", half_angle=3.0),
}

RESULT_FIELDS = ["group", "method", "scene", "variant", "samples", "seeds", "wall_time_s",
                 "first_call_s", "rmse", "rel_mse", "var_n", "nan_count", "reference"]
STABILITY_FIELDS = ["light", "method", "exponent", "theta_i", "samples", "seeds", "exact", "mean",
                    "rel_rmse", "rel_stderr", "var_n", "bias_z", "nan_count", "inf_count",
                    "seconds", "verdict", "reason"]
RATIO_FIELDS = ["comparison", "a", "b", "pair", "scene", "variant", "spp", "t_a", "t_b", "ratio"]
COST_FIELDS = ["scene", "method", "round", "samples", "seconds"]
JIT_FIELDS = ["group", "method", "scene", "variant", "first_call_s", "steady_s", "compile_ms",
              "kernels", "cache_hits", "cold_compile_ms"]


@dataclass(frozen=True)
class Config:
    """Sizes of one bench run (``quick`` keeps it under 3 minutes on 2 cores)."""

    quick: bool = False

    @property
    def estimator_ns(self) -> list[int]:
        return [2 ** k for k in (range(6, 19, 2) if self.quick else range(6, 21))]

    @property
    def estimator_seeds(self) -> int:
        return 16 if self.quick else 32

    @property
    def repeats(self) -> int:
        return 3 if self.quick else 5

    @property
    def cost_rounds(self) -> int:
        return 5 if self.quick else 15

    @property
    def stability_seeds(self) -> int:
        return 8 if self.quick else 16

    @property
    def render_spps(self) -> list[int]:
        return [1, 4, 16, 64] if self.quick else [1, 2, 4, 8, 16, 32, 64, 128, 256]

    @property
    def reference_spp(self) -> int:
        return 2048 if self.quick else 8192

    @property
    def variant_spps(self) -> list[int]:
        return [4, 16] if self.quick else [4, 16, 64]

    @property
    def ratio_pairs(self) -> int:
        return 5 if self.quick else 15

    @property
    def ratio_spp(self) -> int:
        return 64 if self.quick else 256


# --------------------------------------------------------------------------------------------
# CSV logs that resume
# --------------------------------------------------------------------------------------------

class CsvLog:
    """A CSV file written row by row (flushed), that knows which keys it already holds."""

    def __init__(self, path: Path, fields: list[str], key: tuple[str, ...]):
        self.path, self.fields, self.key = Path(path), fields, key
        self.rows: list[dict[str, str]] = []
        if self.path.is_file():
            with self.path.open(newline="") as f:
                reader = csv.DictReader(f)
                if reader.fieldnames != fields:
                    raise PhonglabError(f"{self.path} has columns {reader.fieldnames}, expected "
                                        f"{fields}; delete it or run with --fresh")
                self.rows = list(reader)
        self._keys = {self._key(r) for r in self.rows}

    def _key(self, row: dict) -> tuple[str, ...]:
        return tuple(_fmt(row[k]) for k in self.key)

    def has(self, **key) -> bool:
        return tuple(_fmt(key[k]) for k in self.key) in self._keys

    def add(self, row: dict[str, Any]) -> None:
        row = {k: _fmt(row.get(k, "")) for k in self.fields}
        new = not self.path.is_file()
        self.path.parent.mkdir(parents=True, exist_ok=True)
        with self.path.open("a", newline="") as f:
            writer = csv.DictWriter(f, fieldnames=self.fields)
            if new:
                writer.writeheader()
            writer.writerow(row)
            f.flush()
            os.fsync(f.fileno())
        self.rows.append(row)
        self._keys.add(self._key(row))


def _fmt(value: Any) -> str:
    if isinstance(value, float):
        return repr(value) if math.isfinite(value) else str(value)
    if isinstance(value, (np.floating,)):
        return _fmt(float(value))
    if isinstance(value, (np.integer,)):
        return str(int(value))
    return str(value)


def _f(row: dict, key: str) -> float:
    try:
        return float(row[key])
    except (KeyError, TypeError, ValueError):
        return float("nan")


def _progress(total: int, desc: str, enabled: bool):
    from tqdm import tqdm

    return tqdm(total=total, desc=desc, unit="row", disable=not enabled, leave=False,
                dynamic_ncols=True)


# --------------------------------------------------------------------------------------------
# Machine
# --------------------------------------------------------------------------------------------

def machine_info() -> dict[str, Any]:
    """CPU model (from /proc/cpuinfo), cores, load, versions, GPU presence."""
    import drjit as dr
    import mitsuba as mi

    from .. import __version__

    cpu = platform.processor() or platform.machine()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.lower().startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    try:
        load = os.getloadavg()
    except OSError:
        load = (float("nan"),) * 3
    return {
        "cpu": cpu, "cores": os.cpu_count(),
        "load_average_1_5_15": [round(x, 2) for x in load],
        "python": platform.python_version(), "platform": platform.platform(),
        "mitsuba": mi.__version__, "drjit": dr.__version__, "phonglab": __version__,
        "llvm": ".".join(map(str, dr.detail.llvm_version())) if dr.has_backend(dr.JitBackend.LLVM) else None,
        "cuda_device": bool(dr.has_backend(dr.JitBackend.CUDA)),
        "date_utc": time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()),
    }
# --------------------------------------------------------------------------------------------
# Cornell-box renders: scene variants, cached references, error against them
# --------------------------------------------------------------------------------------------

#: Box materials a render comparison can swap in (the walls take ``wall=``).
BOX_TYPES = ("phong", "lambert", "diffuse", "plastic", "roughplastic")
_GLOSSY_BLOCK = re.compile(r'<bsdf type="phong" id="glossy">.*?</bsdf>', re.S)


def beckmann_alpha(exponent: float) -> float:
    r"""Beckmann roughness whose highlight matches the modified-Phong lobe cos^p α.

    Around the mirror direction the outgoing angle is twice the half-vector angle θ_h,
    so cos^p α ≈ exp(−p α²/2) = exp(−2p θ_h²); Beckmann's D ∝ exp(−tan²θ_h/α_b²) ≈
    exp(−θ_h²/α_b²) gives α_b = 1/√(2p) (Walter et al. 2007, eq. 33 with the Phong
    microfacet exponent 4p: α_b = √(2/(4p + 2)), used here).
    """
    return math.sqrt(2.0 / (4.0 * exponent + 2.0))


def cornell_xml(boxes: str = "phong", exponent: float = 30.0, rfilter: str = "box") -> str:
    """The text of ``scenes_xml/cornell_phong.xml`` with its two boxes made of ``boxes``.

    ``rfilter`` replaces the scene's Gaussian reconstruction filter (``"gaussian"`` keeps
    it).  The convergence measurements use ``box``: with a wider filter each pixel is a
    ratio estimator Σ w_k L_k / Σ w_k whose O(1/spp) bias and random weights make the
    RMSE fall faster than spp^−½ at low spp (measured slope −0.56 over 1–64 spp); with
    the box filter every sample lands in exactly one pixel with weight 1, so a pixel is
    a plain mean of its spp samples.

    The look match for the built-ins (stated, not claimed equal BRDFs): ``diffuse`` /
    ``lambert`` boxes take ρ = k_d = 0.5; ``plastic`` takes diffuse_reflectance 0.5 and its
    default smooth dielectric coating (IOR 1.49: a mirror highlight with Fresnel
    reflectance 4 % at normal incidence instead of phong's k_s = 0.3 glossy lobe);
    ``roughplastic`` the same coating with a Beckmann roughness :func:`beckmann_alpha`
    matching the highlight width of phong's exponent.
    """
    from ..scenes import scene_path

    text = scene_path("cornell_phong").read_text()
    if boxes not in BOX_TYPES:
        raise PhonglabError(f"unknown box material {boxes!r}; use one of {', '.join(BOX_TYPES)}")
    if boxes == "phong":
        block = None
    elif boxes in ("lambert", "diffuse"):
        block = (f'<bsdf type="{boxes}" id="glossy"><rgb name="reflectance" value="0.5, 0.5, 0.5"/>'
                 f'</bsdf>')
    elif boxes == "plastic":
        block = ('<bsdf type="plastic" id="glossy">'
                 '<rgb name="diffuse_reflectance" value="0.5, 0.5, 0.5"/></bsdf>')
    else:
        block = ('<bsdf type="roughplastic" id="glossy"><string name="distribution" value="beckmann"/>'
                 f'<float name="alpha" value="{beckmann_alpha(exponent):.6f}"/>'
                 '<rgb name="diffuse_reflectance" value="0.5, 0.5, 0.5"/></bsdf>')
    if rfilter != "gaussian":
        text, count = re.subn(r'<rfilter type="gaussian"\s*/>', f'<rfilter type="{rfilter}"/>', text)
        if count != 1:
            raise PhonglabError("scenes_xml/cornell_phong.xml no longer has its gaussian <rfilter>; "
                                "update phonglab.bench.cornell_xml")
    if block is not None:
        text, count = _GLOSSY_BLOCK.subn(block, text)
        if count != 1:
            raise PhonglabError("scenes_xml/cornell_phong.xml no longer has its "
                                "<bsdf type=\"phong\" id=\"glossy\"> block; update phonglab.bench")
    return text


@dataclass(frozen=True)
class CornellSpec:
    """A Cornell-box render set-up: materials, resolution, path depth."""

    walls: str = "lambert"
    boxes: str = "phong"
    res: int = 32
    max_depth: int = 8
    exponent: float = 30.0
    rfilter: str = "box"

    @property
    def label(self) -> str:
        return (f"cornell {self.res}px walls={self.walls} boxes={self.boxes} depth={self.max_depth} "
                f"{self.rfilter} filter")

    def xml(self) -> str:
        return cornell_xml(self.boxes, self.exponent, self.rfilter)

    def load(self, variant: str | None = None):
        import mitsuba as mi

        from .. import registration

        registration.register(variant)
        try:
            xml = self.xml()
            params = dict(res=str(self.res), wall=self.walls, max_depth=str(self.max_depth))
            if '"$exponent"' in xml:          # only phong boxes use it; Mitsuba rejects unused ones
                params["exponent"] = str(self.exponent)
            return mi.load_string(xml, **params)
        except Exception as exc:
            raise PhonglabError(f"cannot load the Cornell box ({self.label}): {exc}") from exc

    def key(self, variant: str, spp: int) -> str:
        import mitsuba as mi

        h = hashlib.sha256()
        for part in (self.xml(), repr(self), variant, str(spp), mi.__version__):
            h.update(part.encode())
        return h.hexdigest()[:16]


def render_image(scene, spp: int, seed: int) -> tuple[np.ndarray, float]:
    """(image (H, W, C) float64, wall seconds) of one ``mi.render`` call, fully evaluated."""
    import drjit as dr
    import mitsuba as mi

    t0 = time.perf_counter()
    img = mi.render(scene, spp=spp, seed=seed)
    dr.eval(img)
    arr = np.array(img, dtype=np.float64)
    return arr, time.perf_counter() - t0


def reference(spec: CornellSpec, spp: int = 4096, variant: str = "llvm_ad_rgb",
              cache: Path | None = None, passes: int = 16) -> tuple[np.ndarray, np.ndarray]:
    """High-sample reference image and its per-pixel standard error, cached as EXR.

    The cache key hashes the scene text, the spec, the variant, spp and Mitsuba's
    version; a missing cache (a clean clone) is generated here.  Passes use seeds
    far from the ones the sweeps use (seed = 10⁶ + k).
    """
    from .. import exr
    from ..render import render_scene

    cache = Path(cache or DEFAULT_CACHE)
    key = spec.key(variant, spp)
    img_path, err_path = cache / f"ref-{key}.exr", cache / f"ref-{key}.stderr.exr"
    if img_path.is_file() and err_path.is_file():
        img, _ = exr.read(img_path)
        err, _ = exr.read(err_path)
        return img.astype(np.float64), err.astype(np.float64)
    scene = spec.load(variant)
    result = render_scene(scene, spp, seed=1_000_000, passes=passes)
    meta = {"scene": spec.label, "spp": spp, "passes": passes, "variant": variant}
    exr.write(img_path, result.image, meta)
    exr.write(err_path, result.stderr, meta)
    return result.image.astype(np.float64), result.stderr.astype(np.float64)


def image_errors(image: np.ndarray, ref: np.ndarray, ref_err: np.ndarray) -> dict[str, float]:
    """RMSE and relative MSE of ``image`` against a noisy reference, reference noise removed.

    E[(x − r)²] = MSE_true + Var[r] per pixel, so MSE = mean((x − r)² − se_r²).
    relMSE = mean(((x − r)² − se_r²) / (r² + 10⁻²)) (the ε guards black pixels).
    NaN/Inf pixels are counted and left out of both.
    """
    image = np.asarray(image, np.float64)
    finite = np.isfinite(image)
    d2 = np.where(finite, (image - ref) ** 2 - ref_err ** 2, 0.0)
    n = max(int(finite.sum()), 1)
    mse = float(d2.sum() / n)
    rel = float(np.sum(d2 / (ref * ref + 1e-2)) / n)
    return {"rmse": math.sqrt(max(mse, 0.0)), "rel_mse": rel, "nan_count": int((~finite).sum()),
            "mse": mse}


# --------------------------------------------------------------------------------------------
# Sweeps
# --------------------------------------------------------------------------------------------

def sweep_estimators(out: Path, cfg: Config, progress: bool = True) -> None:
    """Error and steady-state time of each estimator against N, on :data:`ESTIMATOR_SCENES`."""
    from .. import registration

    registration.register("llvm_ad_rgb")
    log = CsvLog(out / "results.csv", RESULT_FIELDS, ("group", "method", "scene", "variant", "samples"))
    jit = CsvLog(out / "jit.csv", JIT_FIELDS, ("group", "method", "scene", "variant"))
    ns, seeds = cfg.estimator_ns, cfg.estimator_seeds
    est = ReflectionEstimators(next(iter(ESTIMATOR_SCENES.values())))
    bar = _progress(len(ESTIMATOR_SCENES) * len(METHODS) * len(ns), "estimators", progress)
    for scene, problem in ESTIMATOR_SCENES.items():
        est.set(problem)
        mu = exact_value(problem)
        for method in METHODS:
            # Warm-up: the first call traces and compiles (or loads from the kernel cache).
            first = est.run(method, ns[0], seed=99)
            steady_first = float(np.median([est.run(method, ns[0], seed=98 - r).seconds
                                             for r in range(cfg.repeats)]))
            if not jit.has(group="estimator", method=method, scene=scene, variant="llvm_ad_rgb"):
                jit.add(dict(group="estimator", method=method, scene=scene, variant="llvm_ad_rgb",
                             first_call_s=first.seconds, steady_s=steady_first,
                             compile_ms=first.compile_ms, kernels=first.kernels,
                             cache_hits=first.cache_hits))
            for k, n in enumerate(ns):
                bar.update()
                if log.has(group="estimator", method=method, scene=scene, variant="llvm_ad_rgb",
                           samples=n):
                    continue
                times = [est.run(method, n, seed=5000 + r).seconds for r in range(cfg.repeats)]
                e = est.run(method, n, seed=10_000 + k, batches=seeds)
                mse = float(np.mean((e.values - mu) ** 2))
                log.add(dict(group="estimator", method=method, scene=scene, variant="llvm_ad_rgb",
                             samples=n, seeds=seeds, wall_time_s=float(np.median(times)),
                             first_call_s=first.seconds, rmse=math.sqrt(mse), rel_mse=mse / mu ** 2,
                             var_n=float(np.mean(e.stderr ** 2)) * n,
                             nan_count=e.nan_count + e.inf_count, reference=mu))
    bar.close()
    # Cost per estimate at the largest N, methods interleaved (rotated order each round) so
    # that load from other processes falls on all of them alike; the median per method is
    # what the efficiency (σ²·t) comparison uses.
    cost = CsvLog(out / "cost.csv", COST_FIELDS, ("scene", "method", "round"))
    n = ns[-1]
    for scene, problem in ESTIMATOR_SCENES.items():
        est.set(problem)
        for r in range(cfg.cost_rounds):
            order = METHODS[r % len(METHODS):] + METHODS[:r % len(METHODS)]
            for method in order:
                if not cost.has(scene=scene, method=method, round=r):
                    cost.add(dict(scene=scene, method=method, round=r, samples=n,
                                  seconds=est.run(method, n, seed=70_000 + r).seconds))


def stability_verdict(rel_rmse: float, rel_bias: float, bias_z: float, nonfinite: int,
                      z_crit: float) -> tuple[str, str]:
    """("ok" | "breaks down", reason) by the rule stated in the module docstring.

    A significant bias (|z| > z_crit) counts only when it is at least
    :data:`BIAS_FLOOR` relative: below that it is float32 rounding of a near-zero-variance
    estimate (z is huge because the standard error is ~10⁻⁸), not a failure.
    """
    if nonfinite:
        return "breaks down", f"{nonfinite} NaN/Inf samples"
    if not math.isfinite(bias_z) and abs(rel_bias) > BIAS_FLOOR:
        return "breaks down", "silent: wrong estimate with zero reported stderr (no sample hit)"
    if abs(bias_z) > z_crit and abs(rel_bias) > BIAS_FLOOR:
        return "breaks down", (f"unexplained error: bias {rel_bias:+.2g} at |z| = {abs(bias_z):.3g} "
                               f"> {z_crit:.1f}")
    if not rel_rmse <= BREAKDOWN_REL_RMSE:
        return "breaks down", f"noise: rel RMSE {rel_rmse:.2g} > {BREAKDOWN_REL_RMSE:g}"
    return "ok", ""


def stability_z_crit() -> float:
    """Two-sided normal quantile at ALPHA = 0.01, Šidák-corrected over every stability cell."""
    from scipy import stats

    cells = len(STABILITY_LIGHTS) * len(METHODS) * len(STABILITY_EXPONENTS) * len(STABILITY_ANGLES)
    a = 1.0 - (1.0 - 0.01) ** (1.0 / cells)
    return float(stats.norm.isf(a / 2))


def sweep_stability(out: Path, cfg: Config, progress: bool = True) -> None:
    """The stability map: each estimator × p × θ_i × light at N = :data:`STABILITY_N` samples."""
    from .. import registration

    registration.register("llvm_ad_rgb")
    log = CsvLog(out / "stability.csv", STABILITY_FIELDS, ("light", "method", "exponent", "theta_i"))
    z_crit = stability_z_crit()
    seeds, n = cfg.stability_seeds, STABILITY_N
    base = dict(bsdf="phong", diffuse_reflectance=0.0, specular_reflectance=1.0)
    est = ReflectionEstimators(Problem(**base))
    for method in METHODS:            # warm-up: compile every estimator before timing cells
        for light in STABILITY_LIGHTS.values():
            est.set(Problem(**base, **light))
            est.run(method, n, seed=1)
    cells = [(lt, m, p, t) for lt in STABILITY_LIGHTS for m in METHODS
             for p in STABILITY_EXPONENTS for t in STABILITY_ANGLES]
    bar = _progress(len(cells), "stability", progress)
    for i, (light, method, p, theta) in enumerate(cells):
        bar.update()
        if log.has(light=light, method=method, exponent=p, theta_i=theta):
            continue
        problem = Problem(**base, **STABILITY_LIGHTS[light], exponent=p, theta_i=theta)
        est.set(problem)
        mu = exact_value(problem)
        e = est.run(method, n, seed=20_000 + i, batches=seeds)
        finite = np.isfinite(e.values)
        err = e.values - mu
        rel_rmse = float(math.sqrt(np.mean(err ** 2)) / mu) if finite.all() else float("nan")
        se_mean = math.sqrt(float(np.mean(e.stderr ** 2)) / seeds)
        mean_err = float(np.mean(err))
        if se_mean > 0:
            z = mean_err / se_mean
        else:
            z = 0.0 if abs(mean_err) <= 1e-6 * abs(mu) else float("inf")
        verdict, reason = stability_verdict(rel_rmse, mean_err / mu, z, e.nan_count + e.inf_count,
                                            z_crit)
        log.add(dict(light=light, method=method, exponent=p, theta_i=theta, samples=n, seeds=seeds,
                     exact=mu, mean=float(np.mean(e.values)), rel_rmse=rel_rmse,
                     rel_stderr=float(np.sqrt(np.mean(e.stderr ** 2))) / mu,
                     var_n=float(np.mean(e.stderr ** 2)) * n, bias_z=z,
                     nan_count=e.nan_count, inf_count=e.inf_count, seconds=e.seconds / seeds,
                     verdict=verdict, reason=reason))
    bar.close()


#: Render comparisons: scene name → {method: CornellSpec}; the reference spec of each method.
def render_setups(res: int = 32) -> dict[str, dict[str, tuple[CornellSpec, CornellSpec]]]:
    diffuse_ref = CornellSpec(walls="diffuse", boxes="diffuse", res=res)
    return {
        "cornell-diffuse": {m: (CornellSpec(walls=m, boxes=m, res=res), diffuse_ref)
                            for m in ("lambert", "diffuse")},
        "cornell-glossy": {m: (CornellSpec(walls="diffuse", boxes=m, res=res),
                               CornellSpec(walls="diffuse", boxes=m, res=res))
                           for m in ("phong", "plastic", "roughplastic")},
    }


def _render_jit(scene, spp: int, seed: int) -> tuple[float, float, int, int]:
    """(seconds, compile ms, kernels, cache hits) of one render (kernel history on)."""
    import drjit as dr

    from ..physics.estimators import kernel_stats

    dr.set_flag(dr.JitFlag.KernelHistory, True)
    dr.kernel_history()
    _, seconds = render_image(scene, spp, seed)
    ms, kernels, hits = kernel_stats()
    return seconds, ms, kernels, hits


def sweep_renders(out: Path, cfg: Config, cache: Path, progress: bool = True) -> None:
    """RMSE against the reference and steady time against spp, per BSDF, on the Cornell box."""
    from .. import registration

    variant = "llvm_ad_rgb"
    registration.register(variant)
    log = CsvLog(out / "results.csv", RESULT_FIELDS, ("group", "method", "scene", "variant", "samples"))
    jit = CsvLog(out / "jit.csv", JIT_FIELDS, ("group", "method", "scene", "variant"))
    setups = render_setups()
    total = sum(len(v) for v in setups.values()) * len(cfg.render_spps)
    bar = _progress(total, "renders", progress)
    for scene_name, methods in setups.items():
        for method, (spec, ref_spec) in methods.items():
            ref, ref_err = reference(ref_spec, cfg.reference_spp, variant, cache)
            scene = spec.load(variant)
            first, ms, kernels, hits = _render_jit(scene, 1, seed=7)
            steady = float(np.median([render_image(scene, 1, seed=8 + r)[1] for r in range(cfg.repeats)]))
            if not jit.has(group="render", method=method, scene=scene_name, variant=variant):
                jit.add(dict(group="render", method=method, scene=scene_name, variant=variant,
                             first_call_s=first, steady_s=steady, compile_ms=ms, kernels=kernels,
                             cache_hits=hits))
            for spp in cfg.render_spps:
                bar.update()
                if log.has(group="render", method=method, scene=scene_name, variant=variant,
                           samples=spp):
                    continue
                times, errs = [], []
                for r in range(cfg.repeats):
                    img, t = render_image(scene, spp, seed=100 * spp + r)
                    times.append(t)
                    errs.append(image_errors(img, ref, ref_err))
                mse = float(np.mean([e["mse"] for e in errs]))
                log.add(dict(group="render", method=method, scene=f"{scene_name}",
                             variant=variant, samples=spp, seeds=cfg.repeats,
                             wall_time_s=float(np.median(times)), first_call_s=first,
                             rmse=math.sqrt(max(mse, 0.0)),
                             rel_mse=float(np.mean([e["rel_mse"] for e in errs])), var_n="",
                             nan_count=sum(e["nan_count"] for e in errs),
                             reference=f"{ref_spec.boxes} {cfg.reference_spp} spp"))
    bar.close()


def sweep_variants(out: Path, cfg: Config, cache: Path, progress: bool = True) -> list[str]:
    """llvm_ad_rgb against scalar_rgb (and cuda_ad_rgb with a GPU) on a 16 px Cornell box.

    Returns notes (e.g. why cuda_ad_rgb was skipped).
    """
    import drjit as dr

    from .. import registration

    notes = []
    variants = ["llvm_ad_rgb", "scalar_rgb"]
    if dr.has_backend(dr.JitBackend.CUDA):
        variants.append("cuda_ad_rgb")
    else:
        notes.append("cuda_ad_rgb skipped: Dr.Jit found no CUDA device on this machine.")
    log = CsvLog(out / "results.csv", RESULT_FIELDS, ("group", "method", "scene", "variant", "samples"))
    jit = CsvLog(out / "jit.csv", JIT_FIELDS, ("group", "method", "scene", "variant"))
    ref_spec = CornellSpec(walls="diffuse", boxes="diffuse", res=VARIANT_RES)
    ref, ref_err = reference(ref_spec, cfg.reference_spp, "llvm_ad_rgb", cache)
    bar = _progress(len(variants) * 2 * len(cfg.variant_spps), "variants", progress)
    try:
        for variant in variants:
            registration.register(variant)
            for method in ("lambert", "diffuse"):
                scene = CornellSpec(walls=method, boxes=method, res=VARIANT_RES).load(variant)
                first = render_image(scene, 1, seed=7)[1]
                steady = float(np.median([render_image(scene, 1, seed=8 + r)[1] for r in range(cfg.repeats)]))
                if not jit.has(group="variant", method=method, scene="cornell-16px", variant=variant):
                    jit.add(dict(group="variant", method=method, scene="cornell-16px", variant=variant,
                                 first_call_s=first, steady_s=steady))
                for spp in cfg.variant_spps:
                    bar.update()
                    if log.has(group="variant", method=method, scene="cornell-16px", variant=variant,
                               samples=spp):
                        continue
                    times, errs = [], []
                    for r in range(cfg.repeats):
                        img, t = render_image(scene, spp, seed=100 * spp + r)
                        times.append(t)
                        errs.append(image_errors(img, ref, ref_err))
                    mse = float(np.mean([e["mse"] for e in errs]))
                    log.add(dict(group="variant", method=method, scene="cornell-16px", variant=variant,
                                 samples=spp, seeds=cfg.repeats, wall_time_s=float(np.median(times)),
                                 first_call_s=first, rmse=math.sqrt(max(mse, 0.0)),
                                 rel_mse=float(np.mean([e["rel_mse"] for e in errs])), var_n="",
                                 nan_count=sum(e["nan_count"] for e in errs),
                                 reference=f"diffuse {cfg.reference_spp} spp llvm_ad_rgb"))
    finally:
        registration.register("llvm_ad_rgb")
        bar.close()
    return notes


#: (comparison, A, B, scene builder) of the render-time targets.
RATIO_COMPARISONS = (
    ("lambert/diffuse", "lambert", "diffuse", "all surfaces"),
    ("phong/plastic", "phong", "plastic", "boxes (walls diffuse)"),
    ("phong/roughplastic", "phong", "roughplastic", "boxes (walls diffuse)"),
)
RATIO_RES = 64
VARIANT_RES = 16


def _ratio_spec(method: str, which: str) -> CornellSpec:
    if which == "all surfaces":
        return CornellSpec(walls=method, boxes=method, res=RATIO_RES)
    return CornellSpec(walls="diffuse", boxes=method, res=RATIO_RES)


def sweep_ratios(out: Path, cfg: Config, progress: bool = True) -> None:
    """Alternating A/B render timings (ABBA order) for the render-time targets."""
    from .. import registration

    variant = "llvm_ad_rgb"
    registration.register(variant)
    log = CsvLog(out / "ratios.csv", RATIO_FIELDS, ("comparison", "pair"))
    spp = cfg.ratio_spp
    bar = _progress(len(RATIO_COMPARISONS) * cfg.ratio_pairs, "ratios", progress)
    for name, a, b, which in RATIO_COMPARISONS:
        scenes = {m: _ratio_spec(m, which).load(variant) for m in (a, b)}
        for m in (a, b):                  # warm-up (JIT) excluded from the pairs
            render_image(scenes[m], spp, seed=1)
        for pair in range(cfg.ratio_pairs):
            bar.update()
            if log.has(comparison=name, pair=pair):
                continue
            order = (a, b) if pair % 2 == 0 else (b, a)
            t = {m: render_image(scenes[m], spp, seed=1000 + pair)[1] for m in order}
            log.add(dict(comparison=name, a=a, b=b, pair=pair, scene=f"cornell {RATIO_RES}px {which}",
                         variant=variant, spp=spp, t_a=t[a], t_b=t[b], ratio=t[a] / t[b]))
    bar.close()


_COLD_PROBE = r"""
import json, sys, phonglab, drjit as dr
from phonglab import bench
from phonglab.physics.estimators import ReflectionEstimators, kernel_stats
phonglab.register("llvm_ad_rgb")
out = {}
for scene_name, methods in bench.render_setups(res=8).items():
    for method, (spec, _) in methods.items():
        s = spec.load("llvm_ad_rgb")
        _, ms, kernels, hits = bench._render_jit(s, 1, 7)
        out["render/" + method] = ms
est = ReflectionEstimators(bench.ESTIMATOR_SCENES["disk3 p=100"])
for m in ("uniform", "cosine", "bsdf", "light", "mis"):
    out["estimator/" + m] = est.run(m, 256, seed=1).compile_ms
print("COLD" + json.dumps(out))
"""


def sweep_cold_compile(out: Path, progress: bool = True) -> None:
    """Cold JIT compile times: a subprocess with an empty Dr.Jit kernel cache ($HOME/.drjit)."""
    path = out / "jit.csv"
    log = CsvLog(path, JIT_FIELDS, ("group", "method", "scene", "variant"))
    if log.rows and all(r["cold_compile_ms"] for r in log.rows if r["group"] in ("render", "estimator")):
        return
    with tempfile.TemporaryDirectory(prefix="phonglab-cold-") as home:
        env = dict(os.environ, HOME=home, MPLCONFIGDIR=home)
        proc = subprocess.run([sys.executable, "-c", _COLD_PROBE], env=env, capture_output=True,
                              text=True, timeout=600)
    line = next((ln for ln in proc.stdout.splitlines() if ln.startswith("COLD")), None)
    if proc.returncode != 0 or line is None:
        raise PhonglabError(f"the cold-compile probe failed (exit {proc.returncode}): "
                            f"{proc.stderr.strip().splitlines()[-1:] or proc.stdout[-300:]}")
    cold = json.loads(line[4:])
    rows = log.rows
    for r in rows:
        key = f"{r['group']}/{r['method']}"
        if key in cold:
            r["cold_compile_ms"] = _fmt(float(cold[key]))
    with path.open("w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=JIT_FIELDS)
        writer.writeheader()
        writer.writerows(rows)


# --------------------------------------------------------------------------------------------
# Charts
# --------------------------------------------------------------------------------------------

def pareto_front(points: Iterable[tuple[float, float]]) -> list[tuple[float, float]]:
    """Points (time, error) not dominated by another (no other is both faster and more accurate),
    sorted by time."""
    pts = sorted({(t, e) for t, e in points if math.isfinite(t) and math.isfinite(e) and e > 0})
    front, best = [], math.inf
    for t, e in pts:
        if e < best:
            front.append((t, e))
            best = e
    return front


def _plt():
    import matplotlib

    matplotlib.use("Agg", force=True)
    import matplotlib.pyplot as plt

    return plt


def _error_time_axes(ax, curves: dict[str, list[tuple[float, float, int]]], title: str,
                     ylabel: str, xlabel: str = "steady-state wall time per estimate [s]") -> None:
    allpts = []
    for label, pts in curves.items():
        pts = sorted(p for p in pts if math.isfinite(p[0]) and math.isfinite(p[1]) and p[1] > 0)
        if not pts:
            continue
        t, e, n = zip(*pts)
        ax.plot(t, e, "o-", ms=3.5, lw=1.2, label=label)
        ax.annotate(f"{n[-1]}", (t[-1], e[-1]), fontsize=6, xytext=(3, 0),
                    textcoords="offset points")
        allpts += [(a, b) for a, b, _ in pts]
    front = pareto_front(allpts)
    if front:
        ft, fe = zip(*front)
        ax.step(ft, fe, where="post", color="k", lw=0.8, ls="--", alpha=0.7, label="Pareto front")
        ax.plot(ft, fe, "o", mfc="none", mec="k", ms=7, mew=1.0)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.set_title(title, fontsize=9)
    ax.grid(True, which="both", alpha=0.25)
    ax.legend(fontsize=7)


def chart_error_time(out: Path, figdir: Path) -> list[Path]:
    """error-vs-time PNGs: estimators (one panel per problem), renders, variants."""
    plt = _plt()
    rows = CsvLog(out / "results.csv", RESULT_FIELDS, ("group", "method", "scene", "variant",
                                                        "samples")).rows
    written = []
    groups = [("estimator", "estimators.png", "relative RMSE", True),
              ("render", "renders.png", "RMSE vs reference", False),
              ("variant", "variants.png", "RMSE vs reference", False)]
    for group, name, ylabel, relative in groups:
        sel = [r for r in rows if r["group"] == group]
        if not sel:
            continue
        scenes = sorted({r["scene"] for r in sel})
        fig, axes = plt.subplots(1, len(scenes), figsize=(5.2 * len(scenes), 4.2), squeeze=False)
        for ax, scene in zip(axes[0], scenes):
            curves: dict[str, list] = {}
            for r in sel:
                if r["scene"] != scene:
                    continue
                err = _f(r, "rmse") / (_f(r, "reference") if relative else 1.0)
                label = r["method"] if group != "variant" else f"{r['method']} {r['variant']}"
                curves.setdefault(label, []).append((_f(r, "wall_time_s"), err, int(r["samples"])))
            _error_time_axes(ax, curves, scene, ylabel,
                             "steady-state wall time per estimate [s]" if group == "estimator"
                             else "steady-state wall time per render [s] (median of repeats)")
        fig.suptitle({"estimator": "Reflection-equation estimators: error against time "
                                   "(labels: N at the last point)",
                      "render": "Cornell box 32 px renders: error against time (labels: spp)",
                      "variant": "llvm_ad_rgb vs scalar_rgb, Cornell box 16 px (labels: spp)"}[group],
                     fontsize=10)
        fig.tight_layout()
        path = figdir / name
        fig.savefig(path, dpi=110)
        plt.close(fig)
        written.append(path)
    return written


def chart_stability(out: Path, figdir: Path) -> Path | None:
    """Heatmap per estimator (columns) and light (rows): log10 relative RMSE, ✗ = breaks down."""
    plt = _plt()
    rows = CsvLog(out / "stability.csv", STABILITY_FIELDS, ("light", "method", "exponent",
                                                             "theta_i")).rows
    if not rows:
        return None
    lights = list(STABILITY_LIGHTS)
    fig, axes = plt.subplots(len(lights), len(METHODS), figsize=(3.1 * len(METHODS), 2.9 * len(lights)),
                             squeeze=False)
    im = None
    for i, light in enumerate(lights):
        for j, method in enumerate(METHODS):
            ax = axes[i][j]
            grid = np.full((len(STABILITY_ANGLES), len(STABILITY_EXPONENTS)), np.nan)
            bad = np.zeros_like(grid, dtype=bool)
            for r in rows:
                if r["light"] != light or r["method"] != method:
                    continue
                a = STABILITY_ANGLES.index(float(r["theta_i"]))
                p = STABILITY_EXPONENTS.index(float(r["exponent"]))
                v = _f(r, "rel_rmse")
                grid[a, p] = math.log10(v) if v > 0 else -7.0
                bad[a, p] = r["verdict"] != "ok"
            im = ax.imshow(np.clip(grid, -5, 1), origin="lower", cmap="viridis", vmin=-5, vmax=1,
                           aspect="auto")
            for a in range(grid.shape[0]):
                for p in range(grid.shape[1]):
                    if bad[a, p]:
                        ax.text(p, a, "✗", ha="center", va="center", color="red", fontsize=10,
                                fontweight="bold")
            ax.set_xticks(range(len(STABILITY_EXPONENTS)),
                          [f"{p:g}" for p in STABILITY_EXPONENTS], fontsize=6, rotation=45)
            ax.set_yticks(range(len(STABILITY_ANGLES)), [f"{t:g}" for t in STABILITY_ANGLES],
                          fontsize=6)
            ax.set_title(f"{method} — {light}", fontsize=8)
            if i == len(lights) - 1:
                ax.set_xlabel("exponent p", fontsize=7)
            if j == 0:
                ax.set_ylabel("θ_i [deg]", fontsize=7)
    fig.subplots_adjust(hspace=0.45, wspace=0.3)
    fig.colorbar(im, ax=axes, shrink=0.8, label="log10 relative RMSE (N = 2^14)")
    fig.suptitle(f"Stability map: pure-specular phong, N = {STABILITY_N} samples; "
                 f"✗ = breaks down (rel. RMSE > {BREAKDOWN_REL_RMSE:g}, NaN/Inf, or unexplained error)",
                 fontsize=9)
    path = figdir / "stability.png"
    fig.savefig(path, dpi=110, bbox_inches="tight")
    plt.close(fig)
    return path


# --------------------------------------------------------------------------------------------
# Targets and the report
# --------------------------------------------------------------------------------------------

def ratio_summary(rows: list[dict]) -> dict[str, dict[str, float]]:
    """Per comparison: median, quartiles and count of the A/B pair ratios."""
    out = {}
    for name, *_ in RATIO_COMPARISONS:
        r = np.array([_f(x, "ratio") for x in rows if x["comparison"] == name])
        if r.size:
            out[name] = {"median": float(np.median(r)), "q1": float(np.percentile(r, 25)),
                         "q3": float(np.percentile(r, 75)), "pairs": int(r.size),
                         "t_a": float(np.median([_f(x, "t_a") for x in rows if x["comparison"] == name])),
                         "t_b": float(np.median([_f(x, "t_b") for x in rows if x["comparison"] == name]))}
    return out


def efficiency_ratios(rows: list[dict], cost_rows: list[dict] | None = None) -> dict[str, dict[str, float]]:
    """Time to reach equal error, relative: (σ²·t per sample) of uniform over that of bsdf, per
    estimator problem, at the largest N (σ² = N·mean(stderr²); t = median of the interleaved
    cost rounds in cost.csv / N, else the row's steady time / N).

    For an unbiased estimator the error after time T is √(σ² t/T), so the time to reach a
    given error is proportional to σ²·t: the ratio is how much sooner BSDF sampling gets there.
    """
    out = {}
    med: dict[tuple[str, str], float] = {}
    for r in cost_rows or []:
        med.setdefault((r["scene"], r["method"]), []).append(_f(r, "seconds") / int(r["samples"]))
    med = {k: float(np.median(v)) for k, v in med.items()}
    est = [r for r in rows if r["group"] == "estimator"]
    for scene in sorted({r["scene"] for r in est}):
        last = {}
        for r in est:
            if r["scene"] == scene and (r["method"] not in last or int(r["samples"]) > int(last[r["method"]]["samples"])):
                last[r["method"]] = r
        cost = {m: _f(r, "var_n") * med.get((scene, m), _f(r, "wall_time_s") / int(r["samples"]))
                for m, r in last.items()}
        if "uniform" in cost and "bsdf" in cost and cost["bsdf"] > 0:
            out[scene] = {"uniform_over_bsdf": cost["uniform"] / cost["bsdf"],
                          "samples": int(last["bsdf"]["samples"]), **{f"cost_{m}": c for m, c in cost.items()}}
    return out


def mis_ratios(stab: list[dict], results: list[dict]) -> dict[str, Any]:
    """MIS error over the better of bsdf/light sampling, at equal time and at equal samples.

    Equal time: √(σ²_mis t_mis / min(σ²_b t_b, σ²_l t_l)); equal samples: √(σ²_mis / min(σ²_b, σ²_l)),
    σ² the per-sample-equivalent variance N·mean(stderr²).  Stability cells where the better
    strategy itself breaks down (its variance estimate cannot be trusted) are left out.
    "Near-zero-variance" cells, where the better strategy's relative per-sample standard
    deviation is below :data:`NEAR_ZERO_REL_SD`, are reported apart: Veach's bound on MIS
    (balance/power heuristic variance ≤ best variance + (1/min nᵢ − 1/Σnᵢ) μ²) is additive in
    μ², so against an almost zero-variance strategy no fixed split can stay within a factor.
    """
    cells: dict[tuple, dict[str, dict]] = {}
    for r in stab:
        cells.setdefault((r["light"], r["exponent"], r["theta_i"]), {})[r["method"]] = r
    # Cost per estimate hardly depends on p or θ_i: one median per (light, method) is far less
    # noisy than a single timed launch per cell on a shared machine.
    cost = {}
    for r in stab:
        cost.setdefault((r["light"], r["method"]), []).append(_f(r, "seconds"))
    t = {k: float(np.median(v)) for k, v in cost.items()}
    found: list[tuple[float, float, tuple, bool, float]] = []
    for key, m in cells.items():
        if not all(k in m for k in ("mis", "bsdf", "light")):
            continue
        light = key[0]
        best = min(("bsdf", "light"), key=lambda k: _f(m[k], "var_n") * t[(light, k)])
        if m[best]["verdict"] != "ok" or _f(m[best], "var_n") <= 0:
            continue
        rt = math.sqrt(_f(m["mis"], "var_n") * t[(light, "mis")] /
                       (_f(m[best], "var_n") * t[(light, best)]))
        best_var = min(x for x in (_f(m["bsdf"], "var_n"), _f(m["light"], "var_n")) if x > 0)
        rn = math.sqrt(_f(m["mis"], "var_n") / best_var)
        # N pairs (2N samples) against N samples of the better strategy: var_pair = var_n / 2.
        rp = math.sqrt(_f(m["mis"], "var_n") / 2.0 / best_var)
        near_zero = math.sqrt(_f(m[best], "var_n")) / _f(m[best], "exact") < NEAR_ZERO_REL_SD
        found.append((rt, rn, key, near_zero, rp))

    def worst(sel, idx):
        return max(sel, key=lambda x: x[idx]) if sel else (math.nan, math.nan, None, False, math.nan)

    regular = [x for x in found if not x[3]]
    wt, wn, wr, wp = worst(found, 0), worst(found, 1), worst(regular, 0), worst(regular, 4)
    return {"pairs_regular_max": wp[4], "pairs_regular_cell": wp[2],
            "time_per_estimate": {f"{k[0]}/{k[1]}": v for k, v in t.items()},
            "equal_time_max": wt[0], "equal_time_cell": wt[2],
            "equal_samples_max": wn[1], "equal_samples_cell": wn[2],
            "regular_time_max": wr[0], "regular_time_cell": wr[2],
            "equal_time_median": float(np.median([x[0] for x in found])) if found else float("nan"),
            "within_1_2": sum(x[0] <= 1.2 for x in found), "cells": len(found),
            "near_zero_cells": len(found) - len(regular)}


def loglog_slope(rows: list[dict], group: str, scene: str, method: str, variant: str = "llvm_ad_rgb",
                 min_samples: int = 1) -> float:
    pts = [(int(r["samples"]), _f(r, "rmse")) for r in rows
           if r["group"] == group and r["scene"] == scene and r["method"] == method
           and r["variant"] == variant and int(r["samples"]) >= min_samples and _f(r, "rmse") > 0]
    if len(pts) < 3:
        return float("nan")
    n, e = zip(*sorted(pts))
    return float(np.polyfit(np.log(n), np.log(e), 1)[0])


def _met(ok: bool | None) -> str:
    return "n/a" if ok is None else ("**met**" if ok else "**not met**")


def _g(x: float, digits: int = 3) -> str:
    return "n/a" if x is None or not math.isfinite(x) else f"{x:.{digits}g}"


def write_markdown(out: Path, md_path: Path, quick_run: Path | None = None) -> Path:
    """BENCHMARKS.md from the CSVs, run.json and PNGs in ``out`` (every number generated)."""
    out = Path(out)
    md_path = Path(md_path)
    run = json.loads((out / "run.json").read_text()) if (out / "run.json").is_file() else {}
    machine = run.get("machine", {})
    results = CsvLog(out / "results.csv", RESULT_FIELDS, ("group", "method", "scene", "variant", "samples")).rows
    stab = CsvLog(out / "stability.csv", STABILITY_FIELDS, ("light", "method", "exponent", "theta_i")).rows
    ratios = CsvLog(out / "ratios.csv", RATIO_FIELDS, ("comparison", "pair")).rows
    jit = CsvLog(out / "jit.csv", JIT_FIELDS, ("group", "method", "scene", "variant")).rows
    quick = json.loads(Path(quick_run).read_text()) if quick_run and Path(quick_run).is_file() else (
        run if run.get("mode") == "quick" else None)
    rel = os.path.relpath(out, md_path.parent)

    rs = ratio_summary(ratios)
    cost_rows = CsvLog(out / "cost.csv", COST_FIELDS, ("scene", "method", "round")).rows
    eff = efficiency_ratios(results, cost_rows)
    mis = mis_ratios(stab, results)
    L: list[str] = []
    add = L.append
    add("# BENCHMARKS: speed against accuracy\n")
    add("Generated by `make bench` (`phonglab bench --quick --fresh --out out/bench-quick`, timed, "
        f"then `phonglab bench --fresh --out {rel} --markdown BENCHMARKS.md --quick-run "
        f"out/bench-quick/run.json`). Every number below "
        f"comes from the CSV files in [`{rel}/`]({rel}/); do not edit by hand.\n")
    # -- machine
    add("## Machine\n")
    add("| | |\n|---|---|")
    for k in ("cpu", "cores", "platform", "python", "mitsuba", "drjit", "llvm", "phonglab", "date_utc"):
        if k in machine:
            add(f"| {k} | {machine[k]} |")
    add(f"| variant | llvm_ad_rgb (scalar_rgb for the variant comparison) |")
    add(f"| CUDA device | {'yes' if machine.get('cuda_device') else 'none (cuda_ad_rgb skipped)'} |")
    la0, la1 = run.get("load_before"), run.get("load_after")
    add(f"| load average (1 min) before / after | {la0} / {la1} |")
    add(f"| bench wall time | {_g(run.get('seconds', float('nan')), 4)} s ({run.get('mode', '?')} mode) |\n")
    cores = machine.get("cores") or 1
    if la0 is not None and max(la0, la1 or 0) > 0.5 * cores:
        add(f"> **Note:** these figures were measured while other processes shared the {cores} cores "
            f"(1-minute load average {la0} before, {la1} after the run). Ratios come from alternating "
            f"A/B runs and medians, which cancel most of that, but absolute times are inflated; "
            f"re-run `make bench` on a quiet machine for clean figures.\n")
    for note in run.get("notes", []):
        add(f"> {note}\n")
    # -- targets
    add("## Targets (issue 4)\n")
    add("| target | measured | verdict |\n|---|---|---|")
    for name, limit in (("lambert/diffuse", 1.05), ("phong/plastic", 1.25)):
        s = rs.get(name)
        if s:
            add(f"| `{name.split('/')[0]}` render time ≤ {limit}× `{name.split('/')[1]}` | "
                f"{s['median']:.3f}× (median of {s['pairs']} ABBA pairs, IQR {s['q1']:.3f}–{s['q3']:.3f}) | "
                f"{_met(s['median'] <= limit)} |")
    for scene, e in eff.items():
        add(f"| p = 100, BSDF IS reaches uniform's error ≥ 20× faster ({scene}) | "
            f"{e['uniform_over_bsdf']:.3g}× (σ²·t per sample; σ² from N = {e['samples']} × S seeds, "
            f"t the median of interleaved timing rounds) | "
            f"{_met(e['uniform_over_bsdf'] >= 20)} |")
    if mis["cells"]:
        def at(cell):
            return f"light={cell[0]}, p={float(cell[1]):g}, θ_i={cell[2]}°" if cell else "n/a"

        add(f"| MIS ≤ 1.2× worse than the better of BSDF/light sampling (equal time, all "
            f"{mis['cells']} stability cells where the better one works) | max "
            f"{mis['equal_time_max']:.3g}× at {at(mis['equal_time_cell'])}; median "
            f"{mis['equal_time_median']:.3g}×; {mis['within_1_2']}/{mis['cells']} cells within 1.2× | "
            f"{_met(mis['equal_time_max'] <= 1.2)} |")
        add(f"| (same, leaving out the {mis['near_zero_cells']} cells where the better strategy is "
            f"near-zero-variance, rel. σ per sample < {NEAR_ZERO_REL_SD:g}) | max "
            f"{_g(mis['regular_time_max'])}× at {at(mis['regular_time_cell'])} | "
            f"{_met(mis['regular_time_max'] <= 1.2) if math.isfinite(mis['regular_time_max']) else 'n/a'} |")
        add(f"| (same, equal sample count: N/2 + N/2 vs N) | max {mis['equal_samples_max']:.3g}× at "
            f"{at(mis['equal_samples_cell'])} | {_met(mis['equal_samples_max'] <= 1.2)} |")
        add(f"| (same, N pairs = 2N samples vs N samples, cells without a near-zero-variance "
            f"strategy) | max {_g(mis['pairs_regular_max'])}× at {at(mis['pairs_regular_cell'])} | "
            f"{_met(mis['pairs_regular_max'] <= 1.2) if math.isfinite(mis['pairs_regular_max']) else 'n/a'} |")
    if quick:
        whole = quick.get("process_seconds") or quick["seconds"]
        add(f"| `phonglab bench --quick` < 3 min on 2 cores | {whole:.1f} s on "
            f"{quick.get('machine', {}).get('cores', '?')} cores, process start to finish "
            f"(sweeps {quick['seconds']:.1f} s; 1-min load average {quick.get('load_before')} at "
            f"its start) | {_met(whole < 180)} |")
    add("")
    if eff:
        add("**BSDF versus uniform sampling.** The constant light isolates what the target is about, "
            "the lobe: there BSDF sampling's variance is that of eval/pdf over the lobe alone. Under "
            "the 3° disk light both strategies are limited by how often a sample finds the light "
            "(light sampling and MIS are orders of magnitude better than either, see the estimator "
            "table), so the BSDF/uniform ratio there measures the light's size as much as the lobe.\n")
    if mis["cells"]:
        add("**Why MIS misses the 1.2× target.** The estimator draws one BSDF and one light sample per "
            "pair (N/2 + N/2) and weights them with the power heuristic. Veach's bound for the balance "
            "heuristic (thesis, Thm. 9.2; the power heuristic obeys one of the same form) is "
            "*additive*: Var[MIS] ≤ the variance of any one strategy + (1/min nᵢ − 1/Σnᵢ)·μ². Where one strategy is (nearly) zero-variance — BSDF sampling of "
            "a lobe that lies entirely inside the disk (p ≥ 10⁴ at small θ_i), light sampling of a "
            "wide lobe under a tiny light — MIS still spends half of its samples on the other "
            "strategy and keeps that μ²-sized term, so the ratio to the best single strategy is "
            "unbounded (the max above); with a 1:1 split at equal sample count a strategy that "
            "dominates alone already makes MIS √2 ≈ 1.41× worse, and each pair costs one BSDF "
            "sample, one light sample and two pdf evaluations. What MIS does deliver is "
            "robustness: it is the only estimator that never breaks down in the stability map "
            "below, while each of its two strategies fails in a different region.\n")
    # -- ratios
    if rs:
        add("## Render-time ratios (same scene, spp and variant)\n")
        add(f"Cornell box {RATIO_RES} px, llvm_ad_rgb; each pair renders A and B back to back, "
            f"in alternating order (ABBA); the ratio is the median of the per-pair ratios.\n")
        add("| comparison | swapped | spp | median t_A [s] | median t_B [s] | ratio (median) | IQR | pairs |")
        add("|---|---|---|---|---|---|---|---|")
        for name, a, b, which in RATIO_COMPARISONS:
            s = rs.get(name)
            if s:
                spp = next(r["spp"] for r in ratios if r["comparison"] == name)
                add(f"| {name} | {which} | {spp} | {s['t_a']:.4f} | {s['t_b']:.4f} | {s['median']:.3f} | "
                    f"{s['q1']:.3f}–{s['q3']:.3f} | {s['pairs']} |")
        add("\nLook match: `phong` (k_d = 0.5, k_s = 0.3, p = 30) against `plastic` (diffuse 0.5, "
            "smooth coating IOR 1.49: a mirror highlight carrying ~4 % Fresnel reflectance) and "
            f"`roughplastic` (same coating, Beckmann α = √(2/(4p+2)) = {beckmann_alpha(30):.3f}, "
            "the microfacet roughness whose highlight width matches cos^p α). These are not the "
            "same BRDF: the comparison is of cost at a similar look, not of images.\n")
    # -- estimators
    est = [r for r in results if r["group"] == "estimator"]
    if est:
        add("## Estimators of the reflection equation\n")
        add(f"![error against time]({rel}/estimators.png)\n")
        add("Problems: " + "; ".join(f"**{k}** = {v.label}" for k, v in ESTIMATOR_SCENES.items()) +
            ". Error = RMSE over S seeds against the exact value (quadrature), relative; time = "
            "median of single N-sample estimates after a warm-up call. Dashed: the Pareto front.\n")
        add("| problem | method | N | rel. RMSE | σ² per sample | time [ms] | σ²·t [rel. to bsdf] | slope log RMSE / log N |")
        add("|---|---|---|---|---|---|---|---|")
        for scene in sorted({r["scene"] for r in est}):
            nmax = max(int(r["samples"]) for r in est if r["scene"] == scene)
            e = eff.get(scene, {})
            for m in METHODS:
                r = next((r for r in est if r["scene"] == scene and r["method"] == m
                          and int(r["samples"]) == nmax), None)
                if r is None:
                    continue
                cost = e.get(f"cost_{m}", float("nan")) / e.get("cost_bsdf", float("nan"))
                add(f"| {scene} | {m} | {nmax} | {_g(_f(r, 'rmse') / _f(r, 'reference'))} | "
                    f"{_g(_f(r, 'var_n'))} | {_g(1e3 * _f(r, 'wall_time_s'))} | {_g(cost)} | "
                    f"{_g(loglog_slope(results, 'estimator', scene, m), 3)} |")
        add("")
    # -- jit
    if jit:
        add("## JIT compile time versus steady state\n")
        add("First call = trace + compile (or kernel-cache load) + run; compile = Dr.Jit's codegen + "
            "LLVM backend time of that call from its kernel history (a disk-cache hit costs only "
            "codegen); cold = the same in a fresh process with an empty kernel cache "
            "(`$HOME/.drjit`). Steady = median of repeats after warm-up, smallest size (N = 64 "
            "samples, or 1 spp). The render kernels were already built by the reference renders "
            "of the same scene in this process, so their in-process first call is a cache hit; "
            "the cold column is their compile cost.\n")
        add("| group | method | scene | variant | first call [s] | steady [s] | compile [ms] | cache hits / kernels | cold compile [ms] |")
        add("|---|---|---|---|---|---|---|---|---|")
        for r in jit:
            add(f"| {r['group']} | {r['method']} | {r['scene']} | {r['variant']} | {_g(_f(r, 'first_call_s'))} | "
                f"{_g(_f(r, 'steady_s'))} | {_g(_f(r, 'compile_ms'))} | {r['cache_hits'] or '-'} / {r['kernels'] or '-'} | "
                f"{_g(_f(r, 'cold_compile_ms'))} |")
        add("")
    # -- renders
    ren = [r for r in results if r["group"] == "render"]
    if ren:
        add("## Full renders: Cornell box\n")
        add(f"![render error against time]({rel}/renders.png)\n")
        add("RMSE against a high-sample reference (cached in `.bench_cache/`; its own per-pixel "
            "variance is subtracted), mean over repeats; `lambert` and `diffuse` share the "
            "`diffuse` reference, so a bias in either would show as a floor.\n")
        add("| scene | method | spp range | slope log RMSE / log spp | RMSE at max spp | time at max spp [s] | NaN |")
        add("|---|---|---|---|---|---|---|")
        for scene in sorted({r["scene"] for r in ren}):
            for m in sorted({r["method"] for r in ren if r["scene"] == scene}):
                rr = sorted((r for r in ren if r["scene"] == scene and r["method"] == m),
                            key=lambda r: int(r["samples"]))
                add(f"| {scene} | {m} | {rr[0]['samples']}–{rr[-1]['samples']} | "
                    f"{_g(loglog_slope(results, 'render', scene, m))} | {_g(_f(rr[-1], 'rmse'))} | "
                    f"{_g(_f(rr[-1], 'wall_time_s'))} | {sum(int(r['nan_count']) for r in rr)} |")
        add("")
    var = [r for r in results if r["group"] == "variant"]
    if var:
        add("## Variants: llvm_ad_rgb against scalar_rgb\n")
        add(f"![variants]({rel}/variants.png)\n")
        add(f"Cornell box at {VARIANT_RES} px (scalar variants call Python plugins once per ray: keep it tiny).\n")
        add("| method | spp | llvm_ad_rgb [s] | scalar_rgb [s] | scalar / llvm | RMSE llvm | RMSE scalar |")
        add("|---|---|---|---|---|---|---|")
        for m in ("lambert", "diffuse"):
            for spp in sorted({int(r["samples"]) for r in var}):
                a = next((r for r in var if r["method"] == m and int(r["samples"]) == spp and r["variant"] == "llvm_ad_rgb"), None)
                b = next((r for r in var if r["method"] == m and int(r["samples"]) == spp and r["variant"] == "scalar_rgb"), None)
                if a and b:
                    add(f"| {m} | {spp} | {_g(_f(a, 'wall_time_s'))} | {_g(_f(b, 'wall_time_s'))} | "
                        f"{_g(_f(b, 'wall_time_s') / _f(a, 'wall_time_s'))} | {_g(_f(a, 'rmse'))} | {_g(_f(b, 'rmse'))} |")
        add("")
    # -- stability
    if stab:
        add("## Stability map\n")
        add(f"![stability map]({rel}/stability.png)\n")
        add(f"Pure specular phong (k_d = 0, k_s = 1) so that the exponent alone shapes the lobe; "
            f"N = {STABILITY_N} samples per estimate, {stab[0]['seeds']} seeds per cell; lights: a "
            f"constant environment (L ≡ 1) and a 1° disk (Ω = {2 * math.pi * (1 - math.cos(math.radians(1))):.3g} sr) "
            f"centred on the mirror direction. Verdict **breaks down** when any sample is NaN/Inf, "
            f"when the relative RMSE exceeds {BREAKDOWN_REL_RMSE:g} (≥ 100× more samples needed for 1 %), "
            f"or when the error is not explained by the estimator's own standard error "
            f"(|z| > {stability_z_crit():.2f}, the two-sided 1 % level Šidák-corrected over all cells; "
            f"z = ∞ is a *silent* failure: no sample reached the light, so estimate and reported "
            f"error are both 0).\n")
        add("| light | estimator | breaks down in | worst cell (rel. RMSE) | NaN/Inf |")
        add("|---|---|---|---|---|")
        for light in STABILITY_LIGHTS:
            for m in METHODS:
                cells = [r for r in stab if r["light"] == light and r["method"] == m]
                bad = [r for r in cells if r["verdict"] != "ok"]
                worst = max(cells, key=lambda r: _f(r, "rel_rmse") if math.isfinite(_f(r, "rel_rmse")) else 1e300)
                ps = sorted({float(r["exponent"]) for r in bad})
                add(f"| {light} | {m} | {len(bad)}/{len(cells)} cells" +
                    (f" (p ∈ {{{', '.join(f'{p:g}' for p in ps)}}})" if ps else "") +
                    f" | p={float(worst['exponent']):g}, θ_i={worst['theta_i']}°: {_g(_f(worst, 'rel_rmse'))} "
                    f"({worst['reason'] or 'ok'}) | {sum(int(r['nan_count']) + int(r['inf_count']) for r in cells)} |")
        add("")
        add(stability_explanations(stab))
    planner_json = out / "planner.json"
    if planner_json.is_file():
        from ..planner import benchmark_table

        rows = json.loads(planner_json.read_text())
        add("\n## Planner: planned against the default configuration (issue 6)\n")
        add("`scripts/planner_bench.py` (run by `make bench`): per scene, the default configuration "
            "(llvm_ad_rgb, max_depth 8, the scene's spp) and its relative RMSE E against a converged "
            "reference; then `planner.plan(scene, target_error=E)`, both rendered alternately "
            "(kernels compiled beforehand), median times. Efficiency ratio = (t·E²)_default / "
            "(t·E²)_planned, the time ratio at exactly equal error. How the planner decides: "
            "[docs/planner.md](docs/planner.md).\n")
        add(benchmark_table(rows))
        add("")
    add(f"\n## Reproduce\n\n```\nmake bench            # full run (about {_g(run.get('seconds', float('nan')) / 60, 2)} min here) + this file\n"
        f".venv/bin/phonglab bench --quick --out out/bench-quick   # the < 3 min smoke run\n```\n")
    md_path.write_text("\n".join(L) + "\n")
    return md_path


def _cell(stab, light, method, p, theta):
    return next((r for r in stab if r["light"] == light and r["method"] == method
                 and float(r["exponent"]) == p and float(r["theta_i"]) == theta), None)


def stability_explanations(stab: list[dict]) -> str:
    """Why each failure happens, with the predicted relative RMSE next to the measured one."""
    n = STABILITY_N
    omega = 2 * math.pi * (1 - math.cos(math.radians(1.0)))
    lines = ["### Why the failures happen\n",
             "Predictions are for θ_i = 0 (where the lobe is whole) and are compared with the measured cell.\n"]

    def measured(light, m, p, t=0.0):
        r = _cell(stab, light, m, p, t)
        return (f"measured {_g(_f(r, 'rel_rmse'))} ({r['verdict']})" if r else "not measured")

    # Uniform sampling of a normalized cos^p lobe: E[X²]/E[X]² = (p+2)²/(2p+1) ≈ p/2.
    lines.append("* **Uniform hemisphere sampling at high p (constant light).** X = 2π f cos θ_o; for the "
                 "normalized lobe E[X²]/E[X]² = (p+2)²/(2p+1) ≈ p/2, so the relative RMSE is "
                 "√((p+2)²/((2p+1)N)) and crosses 0.1 at p ≈ 0.02 N ≈ 330. " +
                 "; ".join(f"p = {p:g}: predicted {_g(math.sqrt(((p + 2) ** 2 / (2 * p + 1) - 1) / n))}, "
                           f"{measured('constant', 'uniform', p)}" for p in (100.0, 1e3, 1e4)) + ". "
                 "Cosine-weighted sampling fails the same way (it ignores the lobe), and the constant "
                 "light's own sampling (uniform sphere) is twice as bad: E[X²]/E[X]² ≈ p.")
    lines.append("* **Uniform / cosine sampling with a tiny light.** Only a fraction 1 − cos δ = "
                 f"{1 - math.cos(math.radians(1)):.3g} of uniform hemisphere samples reach the 1° disk: "
                 f"{n * (1 - math.cos(math.radians(1))):.2g} hits expected in N = {n}, whatever p is. "
                 f"The estimate is a handful of spikes (or 0, a silent failure). "
                 f"Measured at p = 0: {measured('disk 1deg', 'uniform', 0.0)}.")
    lines.append("* **BSDF sampling with a tiny light at low p.** A lobe sample lands in the disk with "
                 f"probability ≈ Ω (p+1)/(2π) while the lobe is wider than the disk (Ω = {omega:.3g} sr), so "
                 "the relative RMSE ≈ 1/√(N Ω (p+1)/(2π)): " +
                 "; ".join(f"p = {p:g}: predicted {_g(1 / math.sqrt(n * omega * (p + 1) / (2 * math.pi)))}, "
                           f"{measured('disk 1deg', 'bsdf', p)}" for p in (0.0, 10.0, 100.0)) + ". "
                 "Once the lobe is narrower than the disk (p ≳ 2/δ² ≈ 6600) every sample hits it.")
    lines.append("* **Light sampling with a sharp lobe.** A uniform sample in the cone finds a lobe narrower "
                 "than the cone rarely: E[X²]/E[X]² ≈ Ω (p+2)²/(2π(2p+1)) ≈ Ω p/(4π). With the 1° disk this "
                 "stays small up to p = 10⁵ (predicted "
                 f"{_g(math.sqrt(omega * (1e5 + 2) ** 2 / (2 * math.pi * (2e5 + 1)) / n))}, "
                 f"{measured('disk 1deg', 'light', 1e5)}); under the constant light the 'light' "
                 "strategy is uniform sphere sampling and breaks down as uniform does.")
    lines.append("* **Grazing incidence (θ_i → 89.9°).** The mirror direction lies 0.1° above the horizon: "
                 "half of the lobe (and of the disk) is below it and is clipped by cos θ_o ≤ 0. Sampling "
                 "strategies that ignore the horizon waste those samples; the exact value shrinks, so "
                 "relative errors grow.")
    nonfinite = sum(int(r["nan_count"]) + int(r["inf_count"]) for r in stab)
    lines.append(f"* **Float overflow/underflow of cos^p and its normalisation.** None observed: "
                 f"{nonfinite} NaN/Inf samples over all {len(stab)} cells. (p+2)/(2π) ≤ 1.6·10⁴ and the pdf "
                 "squared in the power heuristic ≤ 2.6·10⁸ are far from float32's 3.4·10³⁸; cos^p α "
                 "underflows to 0 only where the true value is < 10⁻³⁸ (harmless), and the plugin draws "
                 "1 − cos α through expm1 so p = 10⁵ keeps sin α accurate. float32 does limit "
                 "the lobe's resolution: cos α near 1 is quantized in steps of 2⁻²⁴ ≈ 6·10⁻⁸, i.e. "
                 "relative steps p·6·10⁻⁸ ≈ 0.6 % in cos^p α at p = 10⁵; the bias test (|z|) above would "
                 "flag it where it matters at this budget. float32 does matter for the *light*: the "
                 "kernel holds cos δ in float32, and for δ = 1° that rounding alone changes the "
                 "disk's solid angle 2π(1 − cos δ) by about 10⁻⁴ relative. Light sampling and MIS "
                 "are precise enough here (relative standard errors 10⁻⁷–10⁻⁶) to see it as a bias "
                 "with |z| in the hundreds, so the exact values are computed for the float32 cone "
                 "(the light the kernel actually renders); a renderer that describes small lights "
                 "by cos δ in float32 carries that 10⁻⁴ error in their power.")
    return "\n".join(lines) + "\n"


# --------------------------------------------------------------------------------------------
# Entry point
# --------------------------------------------------------------------------------------------

PARTS = ("estimators", "stability", "renders", "variants", "ratios", "jit")


def _process_age() -> float | None:
    """Seconds since this process started (interpreter start-up and imports included), Linux."""
    try:
        start_ticks = int(Path("/proc/self/stat").read_text().rsplit(")", 1)[1].split()[19])
        uptime = float(Path("/proc/uptime").read_text().split()[0])
        return round(uptime - start_ticks / os.sysconf("SC_CLK_TCK"), 2)
    except (OSError, ValueError, IndexError):
        return None


def run_bench(out: Path = DEFAULT_OUT, quick: bool = False, fresh: bool = False,
              markdown: Path | None = None, parts: Iterable[str] = PARTS,
              cache: Path | None = None, progress: bool = True,
              quick_run: Path | None = None, log: Callable[[str], None] = print) -> dict[str, Any]:
    """Run the sweeps into ``out`` (CSV + PNG), then optionally write ``markdown``.

    Returns the run record also written to ``out/run.json``.
    """
    out = Path(out)
    cache = Path(cache or DEFAULT_CACHE)
    parts = list(parts)
    unknown = [p for p in parts if p not in PARTS]
    if unknown:
        raise PhonglabError(f"unknown bench part(s) {', '.join(unknown)}; choose from {', '.join(PARTS)}")
    out.mkdir(parents=True, exist_ok=True)
    if fresh:
        for name in ("results.csv", "stability.csv", "ratios.csv", "jit.csv", "cost.csv", "run.json"):
            (out / name).unlink(missing_ok=True)
    cfg = Config(quick=quick)
    from .. import registration

    registration.register("llvm_ad_rgb")
    load_before = round(os.getloadavg()[0], 2)
    t0 = time.perf_counter()
    notes: list[str] = []
    timings: dict[str, float] = {}
    steps = [("estimators", lambda: sweep_estimators(out, cfg, progress)),
             ("stability", lambda: sweep_stability(out, cfg, progress)),
             ("renders", lambda: sweep_renders(out, cfg, cache, progress)),
             ("variants", lambda: notes.extend(sweep_variants(out, cfg, cache, progress))),
             ("ratios", lambda: sweep_ratios(out, cfg, progress)),
             ("jit", lambda: sweep_cold_compile(out, progress))]
    for name, fn in steps:
        if name in parts:
            ts = time.perf_counter()
            fn()
            timings[name] = round(time.perf_counter() - ts, 2)
            log(f"bench: {name} done in {timings[name]:.1f} s")
    figdir = out
    charts = [str(p) for p in chart_error_time(out, figdir)]
    s = chart_stability(out, figdir)
    if s:
        charts.append(str(s))
    seconds = time.perf_counter() - t0
    record = {"mode": "quick" if quick else "full", "seconds": round(seconds, 2),
              "process_seconds": _process_age(), "parts": timings,
              "machine": machine_info(), "load_before": load_before,
              "load_after": round(os.getloadavg()[0], 2), "notes": notes, "charts": charts,
              "command": "phonglab bench" + (" --quick" if quick else "") + f" --out {out}"}
    previous = out / "run.json"
    if previous.is_file() and not fresh and set(parts) != set(PARTS):
        # A partial re-run (resume, or --only) adds to the record of the run it continues.
        old = json.loads(previous.read_text())
        record["notes"] = sorted(set(old.get("notes", [])) | set(notes))
        record["seconds"] = round(old.get("seconds", 0.0) + seconds, 2)
        record["parts"] = {**old.get("parts", {}), **timings}
        record["load_before"] = old.get("load_before", load_before)
        record["process_seconds"] = None
        record["mode"] = old.get("mode", record["mode"])
    (out / "run.json").write_text(json.dumps(record, indent=2) + "\n")
    if markdown:
        write_markdown(out, Path(markdown), quick_run)
        log(f"bench: wrote {markdown}")
    return record
