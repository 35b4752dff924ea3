r"""Lobe-centred quadrature of a per-direction function of a BSDF over the sphere of ω_o.

The ``energy`` topic integrates ``eval`` (∫ f cos θ_o dω_o, the directional albedo) and the
``normalization`` topic integrates ``pdf`` (∫ pdf dω_o, the probability that ``sample`` returns
a direction with a density); both by :func:`phonglab.physics.quadrature.lobe_quadrature`,
composite Gauss-Legendre in a frame centred on the lobe, with the horizon a panel edge.

Placement.  :func:`layout` finds each incidence cell's reflected lobe (and transmitted one, for
a transmitting BSDF) from the BSDF's own samples: the centre is the mean direction of the 10 %
most probable samples -- the lobe's peak, wherever a normal map or a rotated anisotropy puts
it -- and the width the 10 % quantile of the samples' angles to it (by the chord of the
float64-normalised samples, :func:`phonglab.validate.sphere_bins.angle`: arccos of a float32
direction's dot product cannot tell angles below ~3e-4 rad, while a rough dielectric between
nearly equal indices has a lobe α|η − 1| ~ 10⁻⁶ rad wide; floored at :data:`MIN_WIDTH`).
A spike beside a broad lobe is not among the 10 % most probable samples alone, so neither
their mean nor the quantile sees it: principled with every parameter 1 at cos θ_i = 1e-4
puts ~1 % of its samples in a clearcoat spike ~7e-4 rad wide (pdf up to 1.6e7) beside a
GGX lobe whose width is 0.3 rad, and a rule of that width integrated ∫pdf to 0.8625 for
0.9004 counted (an independent Monte Carlo integral: 0.905 ± 0.0015).  So where the 1 % most
probable samples lie :data:`SPIKE` times closer together than the lobe's width, the rule is
centred on them, graded down to their width; its panels grow geometrically from there, so
the broad lobe is still covered.  Each rule covers the whole
circle around its centre (``symmetric=False``), so anisotropy and azimuth φ_i ≠ 0 are covered.
Only the panels depend on the samples: the value is Σ_k w_k g(ω_k), independent of ``sample``.

Lobes that ``sample`` rarely picks (``layout(components=True, extra=...)``, the
``normalization`` topic).  The mixture's most probable samples find the lobe that dominates
it, not a narrow one it picks with probability 10⁻⁴: a normalized Blinn-Phong lobe of
exponent 2000 at w_s = 2e-4 beside a Lambertian one (tests/authors/narrow_broad_mixture.py)
has ~0.4 of the 2048 placing samples, a rule placed from them is centred on the Lambertian
lobe (width 0.3 rad), and at cos θ_i ≤ 0.15 the narrow lobe falls between the nodes of all
three rules: ∫pdf 0.99980 = 1 − w_s with |Q16 − Q8| = 3e-7 against 1 counted.  So each non-delta
component is also sampled alone (``ctx.component = k``, :func:`_component_lobes`), and the
caller's own samples are grouped by (sampled_component, sampled_type) (:func:`group_lobes`,
for a plugin that ignores ``ctx.component``; a group needs :data:`MIN_GROUP` samples in a
hemisphere, and a lobe whose mass exceeds the normalization band z²/(√2 N) has ≈ z²/√2 ≈ 9 of
N).  Per hemisphere the rule is centred on the narrowest lobe and refined towards each other
one that its panels do not already resolve (:func:`arrange`;
:func:`phonglab.physics.quadrature.lobe_quadrature`'s ``refine``): every lobe has panels
graded to its own width, so the coarser rules resolve it too and their differences measure
convergence, not a lobe all of them miss.  A plugin that neither honours ``ctx.component``
nor labels its lobes' samples gives one group: its placement is the mixture's alone.

Supports that end short of the horizon (``layout(heights=...)``, the ``normalization``
topic).  The horizon is a panel edge, but a pdf may also jump to 0 along a circle
|ω_z| = h parallel to it: roughdielectric's transmitted pdf at grazing incidence ends at
|ω_z| = cos θ_i / η, the refraction through microfacets perpendicular to the surface, with
≈ 1.6 on the lobe's side (GGX α 0.3, η 1.504).  A panel running through that jump to the
horizon has an error that the coarser rules share: at cos θ_i = 1e-4, φ_i = 2.1, Q(n) for
n = 8, 12, 16, 32, 64, 96 was 1.0000595, 1.0000563, 1.0000510, 1.0000454, 1.0000404,
0.9999626 (the float64 formula at the same nodes within 2e-8 of each), against 1 counted
of 2¹⁹ samples, so |Q16 − Q8|, |Q16 − Q12| ≤ 2.2e-5 hid an error of 5.1e-5; at
cos θ_i = 0.01 the rules scattered by 1e-3.  So the smallest |ω_z| of each group of the
caller's counted samples in each hemisphere where ``pdf`` is 0 halfway between it and the
horizon (:func:`support_heights`) is an edge of that hemisphere's rule, per φ node where its
circle of α crosses it (``lobe_quadrature``'s ``heights``); a lobe that thins out towards
the horizon gets none (an edge where N samples happen to stop moved the nodes of
principled's clearcoat spike at cos θ_i = 1e-4, whose pdf changes 100-fold when ω_i's
norm moves by 8u, and widened that cell's band from 1.8e-3 to 2e-2).  An edge never costs accuracy (a smooth integrand is integrated panel by panel
as before), and one placed from samples lies at most the gap between the support's end and
the nearest of N samples beyond it, a sliver holding ~1/N of the samples' mass.  With it the
same cells read 0.9999954 at n = 16 (n = 8 .. 64 within 4e-6) and 0.9994235 against
0.9994125 ± 3.4e-5 counted.  The edges come from ``sample``, the integrand is ``pdf``: a pdf
with density beyond the sampled support is still integrated there, so Q exceeds P as it
should.

Error.  :func:`integrate` returns Q(n) per cell; ``energy`` estimates the error as
|Q(n) − Q(n/2)| (Gauss-Legendre converges fast, so Q(n) is far closer than that).
:func:`integrate_with_error` takes the larger difference to TWO coarser rules, n/2 and 3n/4
nodes per panel: one pair can agree by accident where neither has converged -- for
``roughconductor`` (GGX, α_u = 0.05, α_v = 0.4) at cos θ_i = 0.05, φ_i = 2.1 the quick rules
gave Q(5) = 0.992441 and Q(10) = 0.992460, while Q(8) = 0.982707 and Q(40) = 0.987551.
A lobe narrower than :data:`QUANTISED` has an error neither difference reveals, the float32
rounding of its nodes: :func:`integrate_rounded` averages rules on shifted nodes.
"""

from __future__ import annotations

import collections
import math

import mitsuba as mi
import numpy as np

from ... import probe, stats
from ...physics.quadrature import lobe_quadrature
from .. import sphere_bins
from . import lanes

#: Samples per cell that place the panels (only the layout depends on them).
LAYOUT_SAMPLES = 2048
#: Width of a lobe whose samples are too few to measure (a hemisphere-wide lobe).
FALLBACK_WIDTH = 0.5
#: A spike beside a broad lobe (principled's clearcoat, GTR1 α = 0.001, on a GGX lobe of
#: α 3.16 at grazing incidence): the :data:`SPIKE_SHARE` most probable samples, when the 10 %
#: quantile of their angles to their mean is :data:`SPIKE` times narrower than the lobe's
#: width, are the centre and width of the rule instead (module docstring).
SPIKE = 16.0
SPIKE_SHARE = 0.01

#: A lobe of one component (or of one group of samples with the same sampled_component and
#: sampled_type) is placed from at least this many live samples in a hemisphere
#: (:func:`group_lobes`).
MIN_GROUP = 8
#: A lobe whose centre lies within REACH of its own widths of a narrower lobe's centre is
#: resolved by that lobe's panels (at distance d from it they are at most d wide): no panels
#: of its own (:func:`arrange`).
REACH = 2.0
#: At most this many lobes refine one hemisphere's rule besides its centre (the narrowest kept).
MAX_REFINE = 4
#: At most this many support heights per hemisphere (:func:`support_heights`).
MAX_HEIGHTS = 4
#: At most this many components are sampled one at a time by :func:`layout`.
MAX_COMPONENTS = 8

#: Narrowest lobe width resolved: twice the float32 spacing 2^-24 of a unit vector's components.
MIN_WIDTH = 2.0 ** -23

#: A lobe narrower than this (rad) has its nodes moved by the float32 rounding of ω (spacing
#: 2^-24 per component) by more than 1e-4 of its width: :func:`integrate_rounded` applies.
QUANTISED = 2.0 ** -24 / 1e-4
#: Rules :func:`integrate_rounded` averages: the α panels scaled by 2^(j/COPIES), j < COPIES.
COPIES = 4

#: Float32 floor of a quadrature's band: a value summed over ~10⁴ nodes is good to ~1e-5 relative.
FLOOR = 1e-5

#: (polar angle of the centre, its azimuth, angular width) of one lobe, upper-hemisphere frame.
Lobe = tuple


def centre(wo: np.ndarray, pdf: np.ndarray, fallback: np.ndarray, minimum: int = 16,
           spike: bool = True) -> Lobe:
    """(polar angle, azimuth, width) of a lobe from its samples (upper-hemisphere frame); the
    ``fallback`` direction and :data:`FALLBACK_WIDTH` when there are fewer than ``minimum``.
    ``spike``: look for a spike among the samples (:data:`SPIKE`); not for the samples of one
    lobe (:func:`group_lobes`), whose most probable 1 % are its own peak."""
    if len(wo) < minimum:
        c, width = fallback, FALLBACK_WIDTH
    else:
        top = wo[pdf >= np.quantile(pdf, 0.9)]
        c = top.mean(axis=0)
        c = c / np.linalg.norm(c) if np.linalg.norm(c) > 1e-6 else fallback
        unit = wo / np.linalg.norm(wo, axis=1, keepdims=True)
        width = np.quantile(sphere_bins.angle(unit, c), 0.1)
        peak = unit[pdf >= np.quantile(pdf, 1.0 - SPIKE_SHARE)]
        c1 = peak.mean(axis=0)
        if spike and len(peak) >= 8 and np.linalg.norm(c1) > 1e-6:
            c1 = c1 / np.linalg.norm(c1)
            spike = np.quantile(sphere_bins.angle(peak, c1), 0.1)
            if spike * SPIKE < width:
                c, width = c1, spike
        width = float(np.clip(width, MIN_WIDTH, 1.0))
    return math.acos(float(np.clip(c[2], 0.0, 1.0))), math.atan2(c[1], c[0]), width


def _live(s: probe.Sample, sl=slice(None)) -> np.ndarray:
    """Samples that carry a density: weight ≠ 0, not a delta lobe, finite wo and pdf."""
    wo, pdf = s.wo[sl], s.pdf[sl]
    live = np.any(s.weight[sl] != 0, axis=1) & ~lanes.delta_mask(s.sampled_type[sl])
    return live & np.all(np.isfinite(wo), axis=1) & np.isfinite(pdf)


def group_lobes(wo: np.ndarray, pdf: np.ndarray, keys: np.ndarray,
                cap: int = LAYOUT_SAMPLES) -> tuple[list, list]:
    """(upper lobes, lower lobes in the mirrored frame) of live samples grouped by ``keys``
    (a component index, or sampled_component and sampled_type): each group's lobe in each
    hemisphere where it has :data:`MIN_GROUP` samples (the first ``cap`` of them: iid)."""
    up, down = [], []
    for key in np.unique(keys):
        group = keys == key
        for side, flip, out in ((wo[:, 2] > 0, 1.0, up), (wo[:, 2] < 0, -1.0, down)):
            idx = np.flatnonzero(group & side)[:cap]
            if len(idx) >= MIN_GROUP:
                out.append(centre(wo[idx] * np.array([1.0, 1.0, flip]), pdf[idx], None,
                                  minimum=MIN_GROUP, spike=False))
    return up, down


def support_heights(bsdf, wi: np.ndarray, wo: np.ndarray, keys: np.ndarray) -> tuple[tuple, tuple]:
    """(upper, lower) heights |ω_z| where the support of live samples ``wo`` (drawn at
    incidence ``wi``) ends short of the horizon: per group of ``keys`` and hemisphere with
    :data:`MIN_GROUP` samples, the smallest |ω_z| of its samples, kept where ``pdf`` is 0 at
    half that height (same azimuth): a lobe that thins out towards the horizon (its smallest
    |ω_z| only where N samples happen to stop) gets no edge.  At most :data:`MAX_HEIGHTS`
    per hemisphere, the largest (module docstring: a rough dielectric's transmitted pdf at
    grazing incidence)."""
    found, probes = [], []
    labels, rest = [], keys
    while len(rest):                   # one pass per lobe: no sort of 10⁵-10⁶ keys
        labels.append(rest[0])
        rest = rest[rest != rest[0]]
    height = np.abs(wo[:, 2])
    for sign, side in ((1.0, wo[:, 2] > 0), (-1.0, wo[:, 2] < 0)):
        for key in labels:
            idx = np.flatnonzero(side & (keys == key))
            if len(idx) < MIN_GROUP:
                continue
            d = wo[idx[np.argmin(height[idx])]].astype(np.float64)
            h, flat = abs(float(d[2])), math.hypot(float(d[0]), float(d[1]))
            if h > 0 and flat > 0:
                below = math.sqrt(1.0 - (h / 2) ** 2) / flat
                found.append((sign, h))
                probes.append([d[0] * below, d[1] * below, sign * h / 2])
    if not found:
        return (), ()
    empty = probe.pdf(bsdf, np.repeat(wi[None], len(probes), 0), np.array(probes)) == 0
    out = ({h for (sign, h), e in zip(found, empty) if e and sign > 0},
           {h for (sign, h), e in zip(found, empty) if e and sign < 0})
    return tuple(sorted(out[0])[-MAX_HEIGHTS:]), tuple(sorted(out[1])[-MAX_HEIGHTS:])


def _direction(lobe: Lobe) -> np.ndarray:
    return probe.direction(lobe[0], lobe[1])


def arrange(main: Lobe, others) -> tuple[Lobe, tuple]:
    """(centre, refinements) of one hemisphere's rule from its lobes: the rule is centred on
    the narrowest, and every other lobe whose centre lies farther than :data:`REACH` of its
    own widths from each narrower lobe kept refines it (at most :data:`MAX_REFINE`)."""
    lobes = sorted({main, *others}, key=lambda lobe: lobe[2])
    kept = [lobes[0]]
    for lobe in lobes[1:]:
        if all(sphere_bins.angle(_direction(lobe)[None], _direction(k))[0] > REACH * lobe[2]
               for k in kept):
            kept.append(lobe)
    return kept[0], tuple(kept[1:MAX_REFINE + 1])


def _component_lobes(bsdf, wi: np.ndarray, cells: np.ndarray, n: int, seed: int) -> list:
    """Per cell: (upper lobes, lower lobes) of each non-delta component sampled alone
    (``ctx.component = k``), n samples per cell and component: a lobe that ``sample`` picks
    with probability 10⁻⁴ is placed as well as one it picks half the time.  A plugin that
    ignores ``ctx.component`` gives its mixture again (no harm); one whose restricted
    ``sample`` raises gives nothing here (the ``component`` topic reports it)."""
    delta = int(mi.BSDFFlags.Delta) | int(mi.BSDFFlags.Delta1D)
    count = bsdf.component_count()
    ks = [k for k in range(min(count, MAX_COMPONENTS)) if not int(bsdf.flags(k)) & delta]
    out = [([], []) for _ in cells]
    if count < 2 or not ks:
        return out
    for k in ks:
        try:
            s = probe.sample_random(bsdf, wi, len(wi), seed=seed + 1 + k,
                                    ctx=probe.context(component=k))
        except Exception:        # noqa: BLE001 -- placement only; the component topic judges it
            continue
        for j in range(len(cells)):
            sl = slice(j * n, (j + 1) * n)
            live = _live(s, sl)
            up, down = group_lobes(s.wo[sl][live], s.pdf[sl][live],
                                   np.zeros(int(live.sum()), dtype=np.int64))
            out[j][0].extend(up)
            out[j][1].extend(down)
    return out


def layout(bsdf, cells: np.ndarray, seed: int, whole_sphere: bool = False,
           samples: int = LAYOUT_SAMPLES, components: bool = False, extra=None,
           heights=None) -> list:
    """Per (θ_i, φ_i) cell: (reflected lobe, transmitted lobe or None), or, where further
    lobes refine the rules, (reflected, transmitted, (refine_r, refine_t)) (:func:`arrange`),
    or, where the support may end at given heights, (reflected, transmitted, (refine_r,
    refine_t), (heights_r, heights_t)).

    The transmitted lobe is placed for a transmitting BSDF, and with ``whole_sphere`` for every
    BSDF (then the lower hemisphere of a reflection-only BSDF gets the mirror-centred fallback:
    whatever its integrand is there, it is integrated too).  ``seed``, ``samples``: of the
    placing samples (per cell).  ``components``: also place each component's lobe from
    samples of that component alone (:func:`_component_lobes`).  ``extra``: per cell, further
    (upper lobes, lower lobes), e.g. :func:`group_lobes` of the caller's own samples.
    ``heights``: per cell, (upper, lower) values of |ω_z| where the support may end, each an
    edge of that hemisphere's rule (:func:`support_heights` of the caller's own samples).
    """
    out = []
    transmits = lanes.bsdf_has(bsdf, mi.BSDFFlags.Transmission) or whole_sphere
    n = samples
    wi, _ = lanes.incident(cells, n)
    s = probe.sample_random(bsdf, wi, len(wi), seed=seed)
    more = [([], []) for _ in cells]
    if components:
        per = max(256, n // 4)
        wi_c, _ = lanes.incident(cells, per)
        more = _component_lobes(bsdf, wi_c, cells, per, seed)
    for k, (theta, phi) in enumerate(cells):
        sl = slice(k * n, (k + 1) * n)
        wo, pdf = s.wo[sl], s.pdf[sl]
        live = _live(s, sl)
        mirror = probe.direction(theta, phi + math.pi)
        up = live & (wo[:, 2] > 0)
        reflected = centre(wo[up], pdf[up], mirror)
        transmitted = None
        if transmits:
            down = live & (wo[:, 2] < 0)
            transmitted = centre(wo[down] * np.array([1.0, 1.0, -1.0]), pdf[down], mirror)
        upper = more[k][0] + (list(extra[k][0]) if extra is not None else [])
        lower = more[k][1] + (list(extra[k][1]) if extra is not None else [])
        reflected, refine_r = arrange(reflected, upper) if upper else (reflected, ())
        refine_t = ()
        if transmitted is not None and lower:
            transmitted, refine_t = arrange(transmitted, lower)
        ends = tuple(map(tuple, heights[k])) if heights is not None else ((), ())
        if ends[0] or ends[1]:
            out.append((reflected, transmitted, (refine_r, refine_t), ends))
        elif refine_r or refine_t:
            out.append((reflected, transmitted, (refine_r, refine_t)))
        else:
            out.append((reflected, transmitted))
    return out


def parts_of(entry) -> tuple:
    """(reflected, transmitted, refine_r, refine_t, heights_r, heights_t) of a :func:`layout`
    entry."""
    refine = entry[2] if len(entry) > 2 else ((), ())
    heights = entry[3] if len(entry) > 3 else ((), ())
    return entry[0], entry[1], refine[0], refine[1], heights[0], heights[1]


#: Bytes of hemisphere rules :func:`hemisphere_rule` keeps, least recently used dropped first.
#: A validation asks for the same rule from several topics, levels, cells and sweep points
#: (1766 asked for, 501 distinct, 0.8 MB median and 12 MB at most, over the BSDF defect,
#: contract and mixture tests); 64 MB keeps 73 % of the repeats (128 MB: 84 %, and a
#: roughplastic run's peak memory 573 -> 700 MB).
RULES_BYTES = 64 << 20
_rules: collections.OrderedDict = collections.OrderedDict()


def hemisphere_rule(lobe: Lobe, n: int, refine: tuple = (),
                    heights: tuple = ()) -> tuple[np.ndarray, np.ndarray]:
    """``lobe_quadrature``'s rule of the upper hemisphere about ``lobe`` (polar angle,
    azimuth, width), graded also towards ``refine`` and with edges at ``heights``: built once
    and kept while it is among the last :data:`RULES_BYTES` (read-only arrays)."""
    key = (tuple(map(float, lobe)), int(n), refine, heights)
    rule = _rules.get(key)
    if rule is not None:
        _rules.move_to_end(key)
        return rule
    wo, w = lobe_quadrature(lobe[0], lobe[2], n, azimuth=lobe[1], symmetric=False,
                            refine=refine, heights=heights)
    wo.flags.writeable = w.flags.writeable = False
    _rules[key] = rule = (wo, w)
    held = sum(a.nbytes + b.nbytes for a, b in _rules.values())
    while held > RULES_BYTES and len(_rules) > 1:
        a, b = _rules.popitem(last=False)[1]
        held -= a.nbytes + b.nbytes
    return rule


def nodes(lobe_r: Lobe, lobe_t: Lobe | None, n: int, refine_r=(), refine_t=(), heights_r=(),
          heights_t=()) -> tuple[np.ndarray, np.ndarray]:
    """Unit directions and weights: the upper hemisphere around ``lobe_r``, and the lower one
    (the same rule mirrored) around ``lobe_t`` when given; each graded also towards its
    ``refine_*`` lobes (``lobe_quadrature``'s ``refine``) and with edges at its
    ``heights_*`` (|ω_z| where the support may end, :func:`support_heights`)."""
    wo, w = hemisphere_rule(lobe_r, n, tuple(refine_r), tuple(heights_r))
    if lobe_t is not None:
        wt, ww = hemisphere_rule(lobe_t, n, tuple(refine_t), tuple(heights_t))
        wo, w = np.concatenate([wo, wt * np.array([1.0, 1.0, -1.0])]), np.concatenate([w, ww])
    return wo / np.linalg.norm(wo, axis=1, keepdims=True), w


def integrate(fn, cells: np.ndarray, lobes: list, n: int,
              memo: dict | None = None) -> list[tuple[float, int]]:
    """Q_n = Σ_k w_k fn(ω_i, ω_k) per cell, and its count of non-finite nodes (left out).

    ``fn(wi (M, 3), wo (M, 3)) -> (M,)`` is called once for all cells' nodes (one kernel).
    ``memo``: a dict keeping the nodes built here for later calls on the same lobes and ``n``
    (a topic that integrates several functions by one rule builds its nodes once).
    """
    memo = {} if memo is None else memo
    parts = []
    for entry in lobes:
        key = (tuple(entry), n)
        if key not in memo:
            memo[key] = nodes(*parts_of(entry)[:2], n, *parts_of(entry)[2:])
        parts.append(memo[key])
    wis = lanes.exact(probe.direction(cells[:, 0], cells[:, 1]))
    wi = np.concatenate([np.repeat(w[None], len(p[0]), 0) for w, p in zip(wis, parts)])
    values = fn(wi, np.concatenate([p[0] for p in parts]))
    out, start = [], 0
    for _, w in parts:
        v = values[start:start + len(w)]
        start += len(w)
        ok = np.isfinite(v)
        out.append((float(np.sum(w[ok] * v[ok])), int((~ok).sum())))
    return out


def integrate_with_error(fn, cells: np.ndarray, lobes: list, n: int,
                         memo: dict | None = None) -> tuple:
    """(Q(n) (M,), error (M,), non-finite nodes) per cell: error = max(|Q(n) − Q(n/2)|,
    |Q(n) − Q(3n/4)|), the module docstring says why two coarser rules.  ``memo``: as
    :func:`integrate`'s."""
    q = integrate(fn, cells, lobes, n, memo)
    value = np.array([v for v, _ in q])
    err = np.zeros_like(value)
    for m in sorted({max(1, n // 2), max(1, (3 * n) // 4)} - {n}):
        coarse = np.array([v for v, _ in integrate(fn, cells, lobes, m, memo)])
        err = np.maximum(err, np.abs(value - coarse))
    return value, err, sum(c for _, c in q)


def quantised(lobe_r: Lobe, lobe_t: Lobe | None, *_refine) -> bool:
    """Whether a cell's narrower lobe is below :data:`QUANTISED` (see :func:`integrate_rounded`;
    a rule's refinements are never narrower than its centre, :func:`arrange`)."""
    return min(lobe_r[2], lobe_t[2] if lobe_t is not None else math.inf) < QUANTISED


def integrate_rounded(fn, cells: np.ndarray, lobes: list, n: int,
                      first: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """(mean, its standard error) per cell of :data:`COPIES` rules of n nodes per panel whose
    α panels are scaled by 2^(j/COPIES), j = 0 .. COPIES − 1.

    For a lobe a few float32 spacings of ω wide (as narrow as α|η − 1| ~ 10⁻⁶ rad: a rough
    dielectric between nearly equal indices) ``fn`` sees each node at its float32 rounding, a
    shift of up to 2^-25 per component, i.e. a few % of the lobe's width: Q(n) then carries an
    error like a random sum over the nodes in the lobe, which |Q(n) − Q(n/2)| need not reveal
    (the coarser rule's rounding errors are as large and independent).  Scaled panels put the
    nodes elsewhere on the float32 grid, so the rules' values scatter about the integral by
    that error: their mean and its standard error s/√COPIES estimate it, the caller turns the
    latter into a band with Student's t (COPIES − 1 degrees of freedom).
    ``first``: Q_0 (the rule of ``lobes`` itself) when already computed.
    """
    q = [np.array([v for v, _ in integrate(fn, cells, lobes, n)]) if first is None else first]
    for j in range(1, COPIES):
        s = 2.0 ** (j / COPIES)
        def grow(lobe, s=s):
            return None if lobe is None else (lobe[0], lobe[1], lobe[2] * s)

        scaled = []
        for entry in lobes:
            r, t, rr, rt, hr, ht = parts_of(entry)
            scaled.append((grow(r), grow(t), (tuple(map(grow, rr)), tuple(map(grow, rt))),
                           (hr, ht)))
        q.append(np.array([v for v, _ in integrate(fn, cells, scaled, n)]))
    q = np.array(q)
    return q.mean(axis=0), q.std(axis=0, ddof=1) / math.sqrt(COPIES)


def with_rounding(fn, cells: np.ndarray, layout: list, n: int, value: np.ndarray,
                  err: np.ndarray, m_tests: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(value, error, narrow) per cell: Q(n) and its error where the cell's lobe is wider than
    :data:`QUANTISED`; where it is narrower (``narrow``), the mean of :func:`integrate_rounded`
    and the larger of the given error and t·s/√COPIES (Student's t at the Šidák level of
    ``m_tests`` tests, COPIES − 1 degrees of freedom).  ``value``: Q(n) of ``layout``."""
    narrow = np.array([quantised(*parts_of(entry)) for entry in layout], dtype=bool)
    value, err = np.array(value, dtype=np.float64), np.array(err, dtype=np.float64)
    if narrow.any():
        mean, se = integrate_rounded(fn, cells[narrow], [p for p, k in zip(layout, narrow) if k],
                                     n, first=value[narrow])
        t = stats.t_critical(COPIES - 1, stats.ALPHA, m_tests)
        value[narrow], err[narrow] = mean, np.maximum(err[narrow], t * se)
    return value, err, narrow
