r"""Fitting phong (or lambert) to a target BSDF: the start from the folk rules, L-BFGS-B on the AD gradient.

The start: p from the Phong-lobe folk rule p = (1/α² − 1)/2 (:mod:`phonglab.physics.roughness`
derives it) when the target has a roughness (``alpha`` of the rough plugins, ``roughness``² of
``principled``, ``exponent`` of a phong), else the best of a logarithmic grid of exponents;
k_s and k_d from the target's glossy and diffuse albedo at normal incidence (its glossy and
diffuse lobes evaluated separately, with a ``BSDFContext`` type mask), scaled down together
when they sum above 1.

Optimizer: scipy's L-BFGS-B on the box of :mod:`.objective` (the box maps onto the
energy-conserving region, and L-BFGS-B evaluates only inside its bounds), with the
gradient from Dr.Jit's AD.  A non-finite loss or gradient is an error, never a result.
"""

from __future__ import annotations

import math
import time
from dataclasses import asdict, dataclass, field

import mitsuba as mi
import numpy as np
from scipy.optimize import minimize

from .. import probe
from ..errors import PhonglabError
from ..physics.quadrature import lobe_width
from ..physics.roughness import beckmann_alpha, phong_exponent
from ..settings import load_plugin
from .objective import (MODELS, P_MAX, PHONG, Directions, Model, Objective, fit_directions,
                        luminance_eval, report_directions)

#: Incidence angles [deg] of the per-angle report (normal and grazing included).
REPORT_DEG = (0.0, 15.0, 30.0, 45.0, 60.0, 70.0, 80.0, 85.0)
#: The grazing angle of the table.
GRAZING_DEG = 80.0
#: Exponents tried when the target has no roughness to start from.
START_GRID = (1.0, 3.0, 10.0, 30.0, 100.0, 300.0, 1000.0)


# ----------------------------------------------------------------------------- the target
def load_target(name, params: dict | None = None):
    """The target BSDF ``{"type": name, **params}`` (``name`` may also be a ``mi.load_dict``
    dict or an XML file, :func:`phonglab.settings.load_plugin`); one sentence when Mitsuba
    refuses it."""
    return load_plugin(name, params, kind=mi.BSDF, word="BSDF",
                       hint="name a registered BSDF (e.g. roughconductor, roughplastic, "
                            "principled, plastic, phong) and parameters it takes").plugin


def has_delta(bsdf) -> bool:
    """Whether the BSDF has a delta (mirror/glass) lobe, which ``eval`` never sees."""
    return bool(bsdf.flags() & mi.BSDFFlags.Delta)


def target_alpha(bsdf) -> float | None:
    """The target's roughness α when it has one (rough plugins, principled, phong), else None."""
    params = mi.traverse(bsdf)
    for key in ("alpha", "alpha.value", "alpha_u.value", "alpha_u"):
        if key in params:
            return float(np.asarray(params[key]).ravel()[0])
    if "roughness.value" in params:
        return max(1e-3, float(np.asarray(params["roughness.value"]).ravel()[0]) ** 2)
    if "exponent" in params:   # a phong: α whose folk-rule exponent is this one
        p = float(np.asarray(params["exponent"]).ravel()[0])
        return beckmann_alpha(p)
    return None


def lobe_albedos(bsdf) -> tuple[float, float]:
    """(diffuse, glossy) albedo at normal incidence, luminance, each lobe alone."""
    out = []
    for mask in (mi.BSDFFlags.DiffuseReflection, mi.BSDFFlags.GlossyReflection):
        ctx = probe.context(type_mask=mask)
        dirs = report_directions([0.0], lobe_width(100.0))
        out.append(float(dirs.per_incidence(luminance_eval(bsdf, dirs, ctx))[0]))
    return out[0], out[1]


# ----------------------------------------------------------------------------- the result
@dataclass
class FitResult:
    """Everything ``phonglab fit`` prints and writes (``asdict`` gives its JSON)."""

    target: str
    target_params: dict
    model: str
    labels: list
    start: list                 #: physical parameters at the start
    fitted: list                #: physical parameters fitted
    start_rule: str
    alpha: float | None
    rel_l2: float               #: (E²/T²)^½ of the fitted model
    rel_l2_start: float
    worst: dict                 #: the node with the largest |Δg|
    report_deg: list
    residual: list              #: r(θ_i) per report angle
    albedo_fit: list
    albedo_target: list
    iterations: int
    evaluations: int
    seconds: float
    nodes: int
    delta_lobe: bool
    notes: list = field(default_factory=list)

    def as_dict(self) -> dict:
        return asdict(self)


def _worst(dirs: Directions, fit: np.ndarray, target: np.ndarray) -> dict:
    k = int(np.argmax(np.abs(fit - target)))
    wo = dirs.wo[k]
    return {"theta_i_deg": float(np.degrees(dirs.theta_i[dirs.row[k]])),
            "theta_o_deg": float(np.degrees(np.arccos(np.clip(wo[2], -1, 1)))),
            "phi_o_deg": float(np.degrees(np.arctan2(wo[1], wo[0]))),
            "fit": float(fit[k]), "target": float(target[k])}


def _relative(num: np.ndarray, den: np.ndarray) -> np.ndarray:
    """(num/den)^½, 0 where both vanish and inf where only den does (never NaN)."""
    safe = np.where(den > 0, den, 1.0)
    return np.where(den > 0, np.sqrt(num / safe), np.where(num > 0, np.inf, 0.0))


def _start(model: Model, bsdf, objective: Objective, alpha: float | None) -> tuple[np.ndarray, str]:
    """Variables x0 from the folk rule and the lobe albedos (see the module docstring)."""
    kd, ks = lobe_albedos(bsdf)
    if kd + ks > 1.0:
        kd, ks = kd / (kd + ks), ks / (kd + ks)
    if model is not PHONG:
        return model.variables((min(1.0, kd + ks),)), "k_d = albedo at normal incidence"
    if alpha is not None:
        p0 = min(max(phong_exponent(alpha), 1.0), 1e3)
        return model.variables((kd, ks, p0)), f"p = (1/α² − 1)/2 with α = {alpha:g}"
    candidates = [model.variables((kd, ks, p)) for p in START_GRID]
    losses = [objective.loss(x) for x in candidates]
    best = int(np.argmin(losses))
    return candidates[best], f"p = {START_GRID[best]:g}, best of the grid {START_GRID}"


def _check(value: float, grad: np.ndarray, x: np.ndarray) -> None:
    if not (np.isfinite(value) and np.all(np.isfinite(grad))):
        raise FloatingPointError(f"non-finite loss {value} or gradient {grad} at x = {x}")


def minimize_objective(objective: Objective, x0: np.ndarray, maxiter: int = 200):
    """L-BFGS-B from x0 on the AD gradient; returns scipy's OptimizeResult."""
    def fun(x):
        value, grad = objective.loss_and_grad(x)
        _check(value, grad, x)
        return value, grad

    return minimize(fun, x0, jac=True, method="L-BFGS-B", bounds=objective.model.bounds,
                    options={"maxiter": maxiter, "ftol": 1e-12, "gtol": 1e-9})


def fit(target: str, params: dict | None = None, model: str = "phong", maxiter: int = 200,
        start=None) -> FitResult:
    """Fit ``model`` to the BSDF ``{"type": target, **params}`` (the active variant's plugins).

    ``start``: physical parameters ((k_d, k_s, p) or (k_d,)) to start from instead of the
    folk rule.
    """
    if model not in MODELS:
        raise PhonglabError(f"unknown model {model!r}; choose one of {', '.join(MODELS)}")
    t0 = time.perf_counter()
    m = MODELS[model]
    bsdf = load_target(target, params)
    alpha = target_alpha(bsdf)
    if alpha is not None and not 0.0 < alpha <= 1.0:     # before the folk rule divides by it
        raise PhonglabError(f"the target's roughness alpha = {alpha:g} is outside (0, 1]; "
                            f"give e.g. --set alpha=0.2")
    width = lobe_width(phong_exponent(alpha) if alpha is not None else 30.0)
    dirs = fit_directions(width)
    g_t = luminance_eval(bsdf, dirs)
    if not np.all(np.isfinite(g_t)) or np.min(g_t) < 0:
        raise PhonglabError(f"{target} returns negative or non-finite values of f cos θ at some "
                            f"directions; check its parameters")
    if not np.sum(dirs.weight * g_t ** 2) > 0:
        raise PhonglabError(f"{target} reflects nothing that eval can see (a pure delta or "
                            f"transmissive BSDF); fit a rough one, e.g. roughconductor")
    objective = Objective(m, dirs, g_t)
    if start is None:
        x0, rule = _start(m, bsdf, objective, alpha)
    else:
        x0, rule = m.variables(tuple(float(v) for v in start)), "given"
    res = minimize_objective(objective, x0, maxiter)
    x = np.clip(res.x, *np.array(m.bounds).T)
    g_m = objective.values(x)
    report = report_directions(REPORT_DEG, width)
    rep_t = luminance_eval(bsdf, report)
    rep_m = Objective(m, report, rep_t).values(x)
    residual = _relative(report.per_incidence((rep_m - rep_t) ** 2),
                         report.per_incidence(rep_t ** 2))
    notes = []
    if has_delta(bsdf):
        notes.append(f"{target} has a delta lobe (a smooth coating or mirror) that eval never "
                     f"sees: the fit is to its non-delta part only")
    if model == "phong" and x[2] >= m.bounds[2][1] - 1e-9:
        notes.append(f"p reached its upper bound {P_MAX:g}: the target's lobe is sharper than "
                     f"the fit allows")
    if res.status == 1:
        notes.append(f"L-BFGS-B stopped after {res.nit} iterations (--maxiter) before converging")
    return FitResult(
        target=target, target_params=dict(params or {}), model=model, labels=list(m.labels),
        start=[float(v) for v in m.physical(x0)], fitted=[float(v) for v in m.physical(x)],
        start_rule=rule, alpha=alpha, rel_l2=math.sqrt(max(float(res.fun), 0.0)),
        rel_l2_start=math.sqrt(objective.loss(x0)), worst=_worst(dirs, g_m, g_t),
        report_deg=list(REPORT_DEG), residual=[float(v) for v in residual],
        albedo_fit=[float(v) for v in report.per_incidence(rep_m)],
        albedo_target=[float(v) for v in report.per_incidence(rep_t)],
        iterations=int(res.nit), evaluations=int(res.nfev),
        seconds=time.perf_counter() - t0, nodes=len(dirs.w_o), delta_lobe=has_delta(bsdf),
        notes=notes)


def format_result(r: FitResult) -> str:
    """The text report: parameters, residual, worst direction, albedo against θ_i."""
    setting = ", ".join(f"{k}={v}" for k, v in r.target_params.items())
    lines = [f"fit {r.model} to {r.target}" + (f" ({setting})" if setting else "")
             + f": {r.nodes} direction pairs, {r.iterations} L-BFGS-B iterations, "
             f"{r.evaluations} AD evaluations, {r.seconds:.2f} s",
             f"  start   ({r.start_rule}): "
             + ", ".join(f"{k} = {v:.4g}" for k, v in zip(r.labels, r.start))
             + f"  (relative L2 {r.rel_l2_start:.4f})",
             "  fitted  " + ", ".join(f"{k} = {v:.4g}" for k, v in zip(r.labels, r.fitted))
             + (f"  (k_d + k_s = {r.fitted[0] + r.fitted[1]:.4f})" if r.model == "phong" else ""),
             f"  residual: relative L2 {r.rel_l2:.4f} (of f cos θ_i cos θ_o in luminance, over "
             f"both hemispheres)"]
    w = r.worst
    lines.append(f"  worst direction: θ_i = {w['theta_i_deg']:.1f}°, θ_o = {w['theta_o_deg']:.1f}°, "
                 f"φ_o = {w['phi_o_deg']:.1f}°: fit {w['fit']:.4g} vs target {w['target']:.4g} "
                 f"(f cos θ_o)")
    lines.append("  θ_i [deg]   residual r(θ_i)   albedo fit   albedo target   difference")
    for t, res, af, at in zip(r.report_deg, r.residual, r.albedo_fit, r.albedo_target):
        lines.append(f"  {t:8.1f}   {res:15.4f}   {af:10.4f}   {at:13.4f}   {af - at:+10.4f}")
    lines.extend(f"  note: {n}" for n in r.notes)
    return "\n".join(lines)
