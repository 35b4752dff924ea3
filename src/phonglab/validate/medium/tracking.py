r"""The ``transmittance`` topic: the integrators' own tracking through the medium against
exp(−∫σ_t) by quadrature along the same rays.

Rays.  Rays of the probe (:func:`.lanes.probe`) that meet the medium's bounds, each ending at
a distance L past the start of its in-bounds part [a, b] chosen so that the optical depth
τ = ∫_a^L σ_t reaches one of :data:`TARGETS` (L = b when the whole in-bounds part is thinner):
T = exp(−τ) between 0.08 and 0.8, where a Monte Carlo estimate of K walks has a useful
relative error.

Reference.  τ by composite Gauss-Legendre quadrature over [a, L] (``quad_panels`` panels,
``quad_nodes`` k and 2k nodes each) of σ_t from ``get_scattering_coefficients``, queried as
the integrators query it (:func:`.lanes.coefficients`); its error bound is |τ_2k − τ_k|, and
T = exp(−τ_2k) per channel.

Estimators (the two tracking loops of src/integrators/volpath.cpp at v3.9.1, each run as
written there with ``Medium::sample_interaction`` and ``transmittance_eval_pdf``, the base
class's, as every integrator calls them; a channel per walk drawn as volpath.cpp:117-121
draws it; the spectral or grey branch as ``m_has_spectral_extinction`` says):

* ``delta tracking`` (volpath.cpp:205-259, the path's own free flight): a surface at L
  (intersected as volpath intersects it, including the ``m_is_homogeneous`` shortcut at line
  221 that shortens the ray to the sampled distance); a null collision with probability
  mean(σ_n/σ̄), weighted σ_n/P in the spectral branch; the walk reaching L counts its
  throughput, a real collision ends it with 0 (it would scatter: no longer transmitted);
* ``ratio tracking`` (volpath.cpp:468-517, a shadow ray's transmittance to an emitter at L):
  every collision null, weighted σ_n (spectral) or σ_n/σ̄ (grey), times tr/pdf of the chosen
  channel (491-495).

Both are unbiased estimators of T exactly when σ_t + σ_n = σ̄ and σ_n ≥ 0 (the ``majorant``
topic) and the flags are right (``flags``).  Each (ray, channel, estimator) is one test of
the kind's m statistical tests: |mean − T| ≤ z·se + 4·T·|τ_2k − τ_k| + 10⁻⁵, z the two-sided
normal quantile at the Šidák level of m (:func:`phonglab.stats.z_critical`), se the standard
error of the K walks' mean, 10⁻⁵ the float32 floor of a product of weights.  A walk still going
after ``tracking_steps`` collisions fails the row.
"""

from __future__ import annotations

import drjit as dr
import mitsuba as mi
import numpy as np

from ... import probe as probe_, stats
from . import lanes
from .config import rng
from .topics import Row

#: Optical depths the transmittance rays are cut at (cycled over the rays).
TARGETS = (0.25, 0.75, 1.5, 2.5)
#: Float32 floor of a tracking estimate (a product of float32 weights).
FLOOR = 1e-5
#: Candidate rays per transmittance ray: the optically thickest are kept.
CANDIDATES = 16
#: Below this many expected walks of the minority outcome, the Bernoulli bound is the error.
RARE = 30


def _short(x):
    """A number or an array as 6 significant digits (the ray records of the JSON)."""
    a = np.asarray(x, np.float64)
    return float(f"{float(a):.6g}") if a.ndim == 0 else [float(f"{v:.6g}") for v in a.ravel()]


def statistical_tests(opts) -> int:
    return opts.tracking_rays * 2 * lanes.channels()


def _gauss(a, b, panels: int, k: int):
    """Nodes (R, P·k) and weights of a composite Gauss-Legendre rule on [a, b] per ray."""
    x, w = np.polynomial.legendre.leggauss(k)
    edges = a[:, None] + (b - a)[:, None] * np.linspace(0.0, 1.0, panels + 1)[None, :]
    lo, hi = edges[:, :-1, None], edges[:, 1:, None]
    t = 0.5 * (lo + hi) + 0.5 * (hi - lo) * x
    wt = 0.5 * (hi - lo) * w
    return t.reshape(len(a), -1), wt.reshape(len(a), -1)


def optical_depth(medium, o, d, a, b, panels: int, k: int) -> np.ndarray:
    """(R, P, C): ∫ σ_t over each of P equal panels of [a, b] of each ray, k nodes per panel."""
    t, w = _gauss(a, b, panels, k)
    r = len(a)
    m = t.shape[1]
    oo = np.repeat(o, m, axis=0)
    dd = np.repeat(d, m, axis=0)
    st = lanes.coefficients(medium, oo, dd, t.ravel(), np.repeat(a, m))[2]
    st = st.reshape(r, m, -1)
    return (st * w[:, :, None]).reshape(r, panels, k, -1).sum(axis=2)


def choose(medium, p, opts, r):
    """The transmittance rays: (o, d, a, L, τ_k, τ_2k) (module docstring)."""
    idx = np.flatnonzero(p.inside)
    if not len(idx):
        return None
    idx = r.choice(idx, size=min(CANDIDATES * opts.tracking_rays, len(idx)), replace=False)
    k, panels = opts.quad_nodes, opts.quad_panels
    tau = optical_depth(medium, p.o[idx], p.d[idx], p.a[idx], p.b[idx], panels, k)
    total = np.nan_to_num(tau.max(axis=2).sum(axis=1), nan=-1.0)
    keep = np.argsort(-total, kind="stable")[:opts.tracking_rays]
    idx, tau = idx[keep], tau[keep]
    o, d, a, b = p.o[idx], p.d[idx], p.a[idx], p.b[idx]
    cum = np.concatenate([np.zeros((len(a), 1)), np.cumsum(tau.max(axis=2), axis=1)], axis=1)
    target = np.array([TARGETS[i % len(TARGETS)] for i in range(len(a))])
    L = b.copy()
    for i in range(len(a)):
        j = int(np.searchsorted(cum[i], target[i]))
        if 0 < j <= panels and np.isfinite(cum[i, j]):
            f = (target[i] - cum[i, j - 1]) / max(cum[i, j] - cum[i, j - 1], 1e-300)
            L[i] = a[i] + (b[i] - a[i]) * (j - 1 + f) / panels
    t1 = optical_depth(medium, o, d, a, L, panels, k).sum(axis=1)
    t2 = optical_depth(medium, o, d, a, L, panels, 2 * k).sum(axis=1)
    return o, d, a, L, t1, t2


def _spec(x, n) -> np.ndarray:
    return lanes.spectrum(x, n)


def delta_tracking(medium, o, d, L, channel, flags, r, max_steps):
    """volpath.cpp:205-259 with a surface at L and absorption at a real collision: each
    walk's weight (N, C) and how many walks were still going after ``max_steps``."""
    n, c = len(o), lanes.channels()
    org = np.array(o, np.float64)
    ray_maxt = np.full(n, np.inf)
    si_t = np.zeros(n)
    needs = np.ones(n, bool)
    traveled = np.zeros(n)
    thr = np.ones((n, c))
    result = np.zeros((n, c))
    active = np.ones(n, bool)
    spectral = flags["has_spectral_extinction"]
    for _ in range(max_steps):
        i = np.flatnonzero(active)
        if not len(i):
            break
        m = len(i)
        mei = lanes.sample(medium, org[i], d[i], ray_maxt[i], r.random(m), channel[i])
        t = probe_.to_numpy(mei.t, m)
        valid = np.isfinite(t)
        if flags["is_homogeneous"]:
            ray_maxt[i] = np.where(valid, t, ray_maxt[i])
        rem = L[i] - traveled[i]
        hit = np.where(rem <= ray_maxt[i], rem, np.inf)
        si_t[i] = np.where(needs[i], hit, si_t[i])
        needs[i] = False
        t = np.where(si_t[i] < t, np.inf, t)
        valid = np.isfinite(t)
        if spectral:
            mei.t = lanes.floats(t)
            si = dr.zeros(mi.SurfaceInteraction3f, m)
            si.t = lanes.floats(si_t[i])
            tr, pdf = lanes.view(medium).transmittance_eval_pdf(mei, si, mi.Bool(True))
            tr, pdf = _spec(tr, m), _spec(pdf, m)
            pc = pdf[np.arange(m), channel[i]]
            thr[i] *= np.where((pc > 0)[:, None], tr / np.where(pc > 0, pc, 1.0)[:, None], 0.0)
        sn, sm = _spec(mei.sigma_n, m), _spec(mei.combined_extinction, m)
        with np.errstate(divide="ignore", invalid="ignore"):
            p_null = np.mean(sn / sm, axis=1)
        null = valid & (r.random(m) < p_null)
        if spectral:
            with np.errstate(divide="ignore", invalid="ignore"):
                thr[i] = np.where(null[:, None], thr[i] * sn / p_null[:, None], thr[i])
        escaped = ~valid
        reached = escaped & np.isfinite(si_t[i])
        result[i[reached]] = thr[i[reached]]
        p = probe_.to_numpy(mei.p, m)
        org[i[null]] = p[null]
        si_t[i[null]] -= t[null]
        traveled[i[null]] += t[null]
        active[i] = null & np.any(thr[i] != 0, axis=1)
    return result, int(active.sum())


def ratio_tracking(medium, o, d, L, channel, flags, r, max_steps):
    """volpath.cpp:468-517 with no surface in the way: each walk's transmittance (N, C) and
    how many walks were still going after ``max_steps``."""
    n, c = len(o), lanes.channels()
    org = np.array(o, np.float64)
    traveled = np.zeros(n)
    tr = np.ones((n, c))
    active = np.ones(n, bool)
    spectral = flags["has_spectral_extinction"]
    for _ in range(max_steps):
        rem_all = L - traveled
        active &= rem_all > 0
        i = np.flatnonzero(active)
        if not len(i):
            break
        m = len(i)
        rem = rem_all[i]
        mei = lanes.sample(medium, org[i], d[i], rem, r.random(m), channel[i])
        t = probe_.to_numpy(mei.t, m)
        mint = probe_.to_numpy(mei.mint, m)
        sm = _spec(mei.combined_extinction, m)
        if spectral:
            tt = np.minimum(rem, t) - mint
            trv = np.exp(-tt[:, None] * sm)
            pdf = np.where((t > rem)[:, None], trv, trv * sm)
            pc = pdf[np.arange(m), channel[i]]
            tr[i] *= np.where((pc > 0)[:, None], trv / np.where(pc > 0, pc, 1.0)[:, None], 0.0)
        t = np.where(t > rem, np.inf, t)
        valid = np.isfinite(t)
        sn = _spec(mei.sigma_n, m)
        p = probe_.to_numpy(mei.p, m)
        org[i[valid]] = p[valid]
        traveled[i[valid]] += t[valid]
        with np.errstate(divide="ignore", invalid="ignore"):
            f = sn if spectral else sn / sm
        tr[i[valid]] *= f[valid]
        active[i] = valid & np.any(tr[i] != 0, axis=1)
    return tr, int(active.sum())


def transmittance(medium, opts, m_tests: int) -> list[Row]:
    r = rng(opts.seed, "transmittance")
    p = lanes.probe(medium, opts)
    names = ("delta tracking (volpath's free flight) = exp(−∫σ_t)",
             "ratio tracking (volpath's shadow rays) = exp(−∫σ_t)")
    chosen = choose(medium, p, opts, r)
    if chosen is None:
        return [Row("transmittance", name, None, None, None, None, "skipped",
                    "no probe ray meets the medium's bounds inside the probe box: nothing to "
                    "track", {}) for name in names]
    o, d, a, L, tau_k, tau_2k = chosen
    flags = lanes.flags(medium)
    c = lanes.channels()
    K = opts.tracking_lanes
    R = len(o)
    T = np.exp(-tau_2k)                                 # (R, C)
    quad = 4.0 * T * np.abs(tau_2k - tau_k)
    z = stats.z_critical(stats.ALPHA, m_tests)
    lanes_o, lanes_d, lanes_L = (np.repeat(x, K, axis=0) for x in (o, d, L))
    rows = []
    for name, walk in zip(names, (delta_tracking, ratio_tracking)):
        channel = np.minimum((r.random(R * K) * c).astype(np.int64), c - 1)
        w, stuck = walk(medium, lanes_o, lanes_d, lanes_L, channel, flags, r,
                        opts.tracking_steps)
        w = w.reshape(R, K, c)
        mean = w.mean(axis=1)
        se = w.std(axis=1, ddof=1) / np.sqrt(K)
        rare = K * np.minimum(T, 1.0 - T) < RARE
        se = np.where(rare, np.maximum(se, np.sqrt(T * (1.0 - T) / K)), se)
        tol = z * se + quad + FLOOR
        dev = np.where(np.isfinite(mean), np.abs(mean - T), np.inf)
        excess = dev / tol
        bad_ray = np.any(excess > 1.0, axis=1)
        ri, ci = np.unravel_index(int(np.argmax(excess)), excess.shape)
        records = [{"o": _short(o[i]), "d": _short(d[i]), "a": _short(a[i]), "L": _short(L[i]),
                    "tau": _short(tau_2k[i]), "tau_error": _short(np.abs(tau_2k[i] - tau_k[i])),
                    "T": _short(T[i]), "estimate": _short(mean[i]), "stderr": _short(se[i]),
                    "status": "fail" if bad_ray[i] else "pass"} for i in range(R)]
        ok = not bad_ray.any() and stuck == 0
        reason = (f"mean of {K} walks per ray against exp(−τ) at {R} rays × {c} channels "
                  f"(τ by Gauss-Legendre, {opts.quad_panels} panels × {opts.quad_nodes} and "
                  f"{2 * opts.quad_nodes} nodes), each a test at the Šidák level of the "
                  f"medium's {m_tests} statistical tests: |mean − T| ≤ {z:.2f}·se + "
                  f"4T|τ_2k − τ_k| + {FLOOR:g}; walks with has_spectral_extinction = "
                  f"{flags['has_spectral_extinction']}, is_homogeneous = "
                  f"{flags['is_homogeneous']}")
        if bad_ray.any():
            reason += f"; off at {int(bad_ray.sum())} of {R} rays"
        if stuck:
            reason += f"; {stuck} walks still going after {opts.tracking_steps} collisions"
        row = Row("transmittance", name, float(mean[ri, ci]), float(T[ri, ci]),
                  float(se[ri, ci]), float(tol[ri, ci]), "pass" if ok else "fail", reason,
                  {"rays": records, "z": z, "walks": K, "stuck": stuck,
                   "worst": {"ray": int(ri), "channel": int(ci)}})
        if not ok and bad_ray.any():
            row.failing_lanes = {"o": o[bad_ray], "d": d[bad_ray], "L": L[bad_ray]}
        rows.append(row)
    return rows
