r"""The topics measured on the analytic scenes (:mod:`.scenes`): ``finite``, ``bias`` and
``convergence``.

``finite``: one render of every scene that applies (and of the grazing plane), each value of
the image finite and, for radiance, ≥ 0 (the box filter has no negative lobe).  Mitsuba's film
keeps a NaN sample (``ImageBlock::put`` only warns, src/render/imageblock.cpp:201-223), so a
NaN shows in the image; inside an integrator a NaN throughput may instead end its path
(``dr.any(β != 0)``-style tests), which only the image can tell.

``bias``: per scene, P passes of ``bias_spp`` samples per pixel, each pass with its own seed;
the statistic is the image mean (pixels and channels) and its standard error is the spread of
the P pass means, s/√P (no assumption on the pixels' correlation or on the per-sample
distribution).  The scene fails when |mean − L| > t_{P−1} · s/√P + floor, with t the Student
quantile at the Šidák level of the plugin's m statistical tests and floor the scene's stated
bound on its own value plus float32 accumulation (2⁻¹⁶ of L); a zero-variance estimator (the
enclosure at D = 1 is Le on every sample) is held to the floor alone.

``convergence``: the plane under the point light rendered at each spp of
``convergence_spp`` (independent seeds) against its exact per-pixel values.  MSE_k =
mean_pixels e², its standard error from the pixels' squared errors (independent pixels: box
filter), y_k = ½ ln MSE_k with σ_k = ½ SE_k/MSE_k; the weighted least-squares slope of y on
ln spp must be −½ within z·SE(slope), and so must the slope of the last two levels alone
(a floor -- a bias or a correlation between samples -- flattens the end first): two tests.
An estimator exact on every sample (MSE 0 at every level) passes.  Only the plane: a bias
defect (a missing 1/q, a double count) is ``bias``'s to report, and the plane has no second
bounce and no emitter a BSDF sample can hit, so it shows the noise alone.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import mitsuba as mi
import numpy as np

from ... import stats
from ...engine.render import render_scene
from . import scenes
from .config import seed
from . import setup as setup_
from .setup import Target
from ...verdict import NOT_APPLICABLE
from .topics import Row

#: float32 accumulation budget of an image mean, relative.
ROUND_OFF = 2.0 ** -16


def applies(target: Target, scene: scenes.Analytic):
    """(integrator, "") when ``scene`` applies to ``target``, else (None, why not)."""
    if target.aov:
        return None, "an AOV integrator returns channels that are not radiance: finite only"
    if scene.specular and target.splatting:
        return None, ("a light-tracing (adjoint) integrator cannot connect a pinhole camera "
                      "through a delta BSDF: no path of this estimator reaches the camera")
    return target.at_depth(scene.depth)


def inapplicable(target: Target, scene=None) -> dict:
    """The skip details of a scene that genuinely does not apply (an AOV integrator; glass for
    a light tracer: :func:`phonglab.validate.core.not_covered`), else {}: a scene skipped for
    the integrator's depth (one depth of its own judges the scenes of the others) is marked
    so too, but only when its depth is known -- an unmatched measurement covers nothing."""
    if target.aov or (scene is not None and scene.specular and target.splatting):
        return {NOT_APPLICABLE: True}
    if scene is not None and target.depth != "settable" and target.own_depth is not None:
        return {NOT_APPLICABLE: True}
    return {}


def bias_scenes(target: Target, opts) -> list:
    """[(scene, integrator or None, reason)] of the bias topic, in table order."""
    return [(s, *applies(target, s)) for s in scenes.analytic(opts.res, target.own_depth)]


#: The albedos the depth of an integrator that declares none is measured at, and the deepest
#: depth a measurement names (deeper paths carry ρ^64 of Le: below any stderr here).
MEASURE_RHOS = (0.5, 0.8)
DEPTH_MAX = 64
#: The seed stream of the depth measurement (scene numbers of the bias topic beyond its scenes).
MEASURE_SCENE = 100


@dataclass
class DepthFit:
    """The depth measurement of an integrator that declares none (:func:`measure_depth`)."""

    best: int | None             #: the integer depth that fits both albedos best (None: not finite)
    means: list                  #: the image mean at each albedo of :data:`MEASURE_RHOS`
    ses: list                    #: its standard error (the pass means' spread)
    passes: int
    verdict: list | None = None  #: per albedo (pass?, tolerance, t) once settled with m
    m: int | None = None

    @property
    def matched(self) -> bool:
        return self.best is not None and self.verdict is not None and all(
            ok for ok, _, _ in self.verdict)


def _pass_stats(target, build, integ, opts, k):
    res = render_scene(mi.load_dict(build(opts.res)), opts.bias_spp * opts.bias_passes,
                       seed=seed(opts.seed, "bias", k), passes=opts.bias_passes,
                       integrator=integ)
    means = np.asarray(res.pass_means, np.float64).mean(axis=1)
    return means, float(means.mean()), float(means.std(ddof=1) / math.sqrt(len(means)))


def measure_depth(target: Target, opts) -> DepthFit | None:
    """Measure the depth of an integrator that declares none (``target.depth == "measured"``;
    None for any other, or an AOV one): the closed emitting enclosure at each albedo ρ of
    :data:`MEASURE_RHOS`, P passes as ``bias`` renders them, gives the image mean L_ρ ± s_ρ;
    the depth is the integer D in [1, :data:`DEPTH_MAX`] minimising
    Σ_ρ ((L_ρ − Le (1 − ρ^D)/(1 − ρ)) / (s_ρ + floor_ρ))² (the smallest on a tie).  The fit
    uses no significance level, so it is made before the plugin's m is counted (m then counts
    the scenes judged at D); :func:`settle_depth` judges it.  Kept on the target; the target's
    depth is the best fit until it is settled."""
    if target.depth != "measured" or target.aov:
        return None
    if target.measurement is not None:
        return target.measurement
    means, ses, p = [], [], opts.bias_passes
    for i, rho in enumerate(MEASURE_RHOS):
        _, mean, se = _pass_stats(target, lambda r, rho=rho: scenes.enclosure(r, rho),
                                  target.judged, opts, MEASURE_SCENE + i)
        means.append(mean)
        ses.append(se)
    best = None
    if np.all(np.isfinite(means)) and np.all(np.isfinite(ses)):
        depths = np.arange(1, DEPTH_MAX + 1)
        chi2 = np.zeros(depths.size)
        for rho, mean, se in zip(MEASURE_RHOS, means, ses):
            v = np.array([scenes.enclosure_value(rho, int(d)) for d in depths])
            chi2 += ((mean - v) / (se + ROUND_OFF * v)) ** 2
        best = int(depths[int(np.argmin(chi2))])
    target.measurement = DepthFit(best, means, ses, p)
    target.fixed_depth = best
    return target.measurement


def settle_depth(target: Target, m: int) -> None:
    """Judge a depth measurement with the plugin's m: at each albedo |L_ρ − L_D(ρ)| ≤
    t_{P−1} s_ρ + 2⁻¹⁶ L_D(ρ) (two of the m tests).  When either fails, no integer depth
    explains the enclosure (a double count, a missing 1/q), the target has no depth, and every
    scene whose value depends on it is skipped; the ``bias`` topic's depth rows fail."""
    fit = target.measurement
    if fit is None or fit.verdict is not None:
        return
    t = stats.t_critical(fit.passes - 1, stats.ALPHA, m)
    fit.m = m
    fit.verdict = []
    for rho, mean, se in zip(MEASURE_RHOS, fit.means, fit.ses):
        if fit.best is None:
            fit.verdict.append((False, None, t))
            continue
        v = scenes.enclosure_value(rho, fit.best)
        tol = t * se + ROUND_OFF * v
        fit.verdict.append((bool(abs(mean - v) <= tol), tol, t))
    if fit.matched:
        target.depth_note = (f"its depth, measured by the enclosure at ρ = "
                             f"{' and '.join(map(str, MEASURE_RHOS))}, is {fit.best}")
    else:
        target.fixed_depth = None
        target.depth_note = ("its depth, measured by the enclosure at ρ = "
                             f"{' and '.join(map(str, MEASURE_RHOS))}, matches no integer depth "
                             f"(see the bias topic's depth rows). {setup_.DECLARE}")


def depth_rows(target: Target) -> list[Row]:
    """The ``bias`` rows of a depth measurement (none for an integrator with a depth)."""
    fit = target.measurement
    if fit is None:
        return []
    rows = []
    for (rho, mean, se), (ok, tol, t) in zip(zip(MEASURE_RHOS, fit.means, fit.ses), fit.verdict):
        name = f"depth measured: enclosure ρ={rho}"
        if fit.best is None:
            rows.append(Row("bias", name, mean, None, se, None, "fail",
                            "the enclosure's image mean is not finite: no depth can be measured",
                            {"measured_depth": None}))
            continue
        v = scenes.enclosure_value(rho, fit.best)
        why = (f"image mean of {fit.passes} passes × its bias spp against Le (1 − ρ^D)/(1 − ρ) "
               f"at the best-fitting integer depth D = {fit.best} of both albedos "
               f"({', '.join(map(str, MEASURE_RHOS))}); t_{fit.passes - 1} = {t:.2f} (Šidák, "
               f"m = {fit.m}) × the pass means' stderr")
        if not ok:
            others = {r: scenes.enclosure_value(r, fit.best) for r in MEASURE_RHOS}
            why = (f"matches no integer depth: the best fit D = {fit.best} predicts "
                   + ", ".join(f"{val:.5g} at ρ={r}" for r, val in others.items())
                   + " and measured " + ", ".join(f"{mm:.5g}" for mm in fit.means)
                   + " (a light counted twice, a missing weight?); " + why)
        rows.append(Row("bias", name, mean, v, se, tol, "pass" if ok else "fail", why,
                        {"measured_depth": fit.best, "means": fit.means, "stderr": fit.ses,
                         "albedos": list(MEASURE_RHOS)}))
    return rows


def convergence_applies(target: Target, opts):
    """(integrator or None, reason) of the convergence topic (the plane)."""
    plane = [s for s in scenes.analytic(opts.convergence_res) if s.depth is None][0]
    return applies(target, plane)


def _gray(img: np.ndarray) -> np.ndarray:
    return np.asarray(img, np.float64).mean(axis=-1)


def finite(target: Target, opts) -> list[Row]:
    rows = []
    cases = [(s.name, s.build, s.depth, s.specular)
             for s in scenes.analytic(opts.res, target.own_depth)]
    cases.append(("grazing plane (horizon at 1 mm)", scenes.grazing, None, False))
    for k, (name, build, depth, specular) in enumerate(cases):
        if target.aov:
            integ, why = target.integrator, ""
        elif specular and target.splatting:
            integ, why = None, "light tracing cannot see the glass (see bias)"
        else:
            integ, why = target.at_depth(depth, whole=True)
        if integ is None:
            rows.append(Row("finite", name, None, None, None, None, "skipped", why))
            continue
        res = render_scene(mi.load_dict(build(opts.res)), opts.finite_spp,
                           seed=seed(opts.seed, "finite", k), integrator=integ)
        img = res.image
        # radiance first (finite and >= 0), then the AOV channels (finite only)
        nc = 0 if target.aov else setup_.radiance_channels()
        nonfinite = int(np.count_nonzero(~np.isfinite(img)))
        negative = int(np.count_nonzero(img[..., :nc] < 0))
        bad = nonfinite + negative
        wrong = ~np.isfinite(img)
        wrong[..., :nc] |= img[..., :nc] < 0
        where = np.argwhere(wrong)
        rows.append(Row("finite", name, float(bad), 0.0, None, 0.0,
                        "pass" if bad == 0 else "fail",
                        f"{img.size} values of a {opts.finite_spp} spp render"
                        + _channels_text(target, img.shape[-1], nc)
                        + (f": {nonfinite} not finite, {negative} negative" if bad else ""),
                        {"non_finite": nonfinite, "negative": negative,
                         "radiance_channels": nc, "aov_channels": list(target.aovs),
                         "first_bad_pixel": where[0].tolist() if bad else None}))
    return rows


def _channels_text(target: Target, channels: int, nc: int) -> str:
    """Which channels of the image are which, for the ``finite`` row."""
    if target.aov:
        return " (AOV channels: finite only)"
    if channels > nc:
        names = ", ".join(target.aovs) or f"{channels - nc} more"
        return (f"; channels 0-{nc - 1} radiance (finite and ≥ 0), {nc}-{channels - 1} "
                f"AOVs {names} (finite only)")
    return ", finite and ≥ 0"


def bias(target: Target, opts, m: int) -> list[Row]:
    rows = depth_rows(target)
    for k, (scene, integ, why) in enumerate(bias_scenes(target, opts)):
        if integ is None:
            rows.append(Row("bias", scene.name, None, scene.expected, None, None, "skipped",
                            why, {"source": scene.source, **inapplicable(target, scene)}))
            continue
        res = render_scene(mi.load_dict(scene.build(opts.res)), opts.bias_spp * opts.bias_passes,
                           seed=seed(opts.seed, "bias", k), passes=opts.bias_passes,
                           integrator=integ)
        means = np.asarray(res.pass_means, np.float64).mean(axis=1)
        p = len(means)
        mean = float(means.mean())
        se = float(means.std(ddof=1) / math.sqrt(p))
        t = stats.t_critical(p - 1, stats.ALPHA, m)
        floor = scene.floor + ROUND_OFF * abs(scene.expected)
        tol = t * se + floor
        ok = bool(np.isfinite(mean) and abs(mean - scene.expected) <= tol)
        z = (mean - scene.expected) / se if se > 0 else None
        rows.append(Row("bias", scene.name, mean, scene.expected, se, tol,
                        "pass" if ok else "fail",
                        f"image mean of {p} passes × {opts.bias_spp} spp against {scene.source}; "
                        f"t_{p - 1} = {t:.2f} (Šidák, m = {m}) × the pass means' stderr"
                        + (f" + floor {floor:.2g}" if floor else ""),
                        {"source": scene.source, "t": t, "t_score": z, "passes": p,
                         "spp_per_pass": opts.bias_spp, "floor": floor,
                         "max_depth": scene.depth, "pass_means": means.tolist()}))
    return rows


def _slope(x, y, sigma):
    w = 1.0 / sigma ** 2
    xm = np.sum(w * x) / np.sum(w)
    sxx = np.sum(w * (x - xm) ** 2)
    b = np.sum(w * (x - xm) * (y - np.sum(w * y) / np.sum(w))) / sxx
    return float(b), float(math.sqrt(1.0 / sxx))


def convergence(target: Target, opts, m: int) -> list[Row]:
    integ, why = convergence_applies(target, opts)
    names = ("convergence: RMSE slope over all spp", "convergence: slope of the last two spp")
    if integ is None:
        return [Row("convergence", n, None, -0.5, None, None, "skipped", why,
                    inapplicable(target)) for n in names]
    res_ = opts.convergence_res
    scene = mi.load_dict(scenes.plane(res_))
    ref = scenes.plane_pixels(res_)
    mse, se_mse = [], []
    for k, spp in enumerate(opts.convergence_spp):
        img = render_scene(scene, spp, seed=seed(opts.seed, "convergence", k),
                           integrator=integ).image
        e2 = (_gray(img) - ref).ravel() ** 2
        mse.append(float(e2.mean()))
        se_mse.append(float(e2.std(ddof=1) / math.sqrt(e2.size)))
    mse, se_mse = np.array(mse), np.array(se_mse)
    x = np.log(np.asarray(opts.convergence_spp, np.float64))
    details = {"spp": list(opts.convergence_spp), "rmse": np.sqrt(mse).tolist(),
               "mse_stderr": se_mse.tolist(), "scene": "plane under a point light"}
    if not np.all(np.isfinite(mse)):
        return [Row("convergence", n, None, -0.5, None, None, "fail",
                    "an image held non-finite values (see finite)", details) for n in names]
    if np.all(mse == 0):
        return [Row("convergence", n, 0.0, -0.5, 0.0, 0.0, "pass",
                    "every pixel exact at every spp: a zero-variance estimator", details)
                for n in names]
    if np.any(mse == 0) or np.any(se_mse == 0):
        return [Row("convergence", n, None, -0.5, None, None, "fail",
                    "the error is 0 at some spp and not at others", details) for n in names]
    y = 0.5 * np.log(mse)
    sig = 0.5 * se_mse / mse
    z = stats.z_critical(stats.ALPHA, m)
    rows = []
    fits = (_slope(x, y, sig),
            ((y[-1] - y[-2]) / (x[-1] - x[-2]),
             math.sqrt(sig[-1] ** 2 + sig[-2] ** 2) / (x[-1] - x[-2])))
    for name, (b, se) in zip(names, fits):
        tol = z * se
        ok = bool(abs(b + 0.5) <= tol)
        rows.append(Row("convergence", name, float(b), -0.5, float(se), tol,
                        "pass" if ok else "fail",
                        f"log-log slope of the per-pixel RMSE against the exact pixels over "
                        f"spp {', '.join(map(str, opts.convergence_spp))}; z = {z:.2f} (Šidák, "
                        f"m = {m}) × the fit's stderr (from the pixels' squared errors)"
                        + ("" if ok else ": a floor or a wrong rate"),
                        {**details, "z": z}))
    return rows
