r"""The deterministic topics: ``finite``, ``eval_pdf``, ``weight``, ``pdf``, ``component``.

Each is an identity that a correct BSDF satisfies lane by lane, so the tolerance is float32
round-off (:data:`phonglab.validate.roundoff.REL_TOL`), not statistics:

* ``finite``: eval, pdf, eval_pdf and sample (weight, pdf, wo) are finite and ≥ 0 (wo a unit
  vector where the weight is non-zero) for random directions on the whole sphere, the mirror
  and straight-through directions, grazing ones (cos θ_o = ±1e-4, 0), below-horizon ones, at
  every incidence cell (cos θ_i down to 1e-4 and 0), and the sample values 0 and 1 − ε.
* ``eval_pdf``: ``eval_pdf(wi, wo)`` equals ``(eval(wi, wo), pdf(wi, wo))``.
* ``weight``: every non-delta sample's weight equals eval/pdf at its wo (per sample: a weight
  right only on average biases any render whose light is not uniform) [mitsuba3#134, #1011].
* ``pdf``: ``bs.pdf`` equals ``pdf(wi, bs.wo)`` for non-delta samples.
* ``component``: ``sampled_component`` indexes a component whose flags contain
  ``sampled_type``; a context restricted to component k samples only k and evaluates only k;
  Σ_k eval_k = eval [PR#1951].  And the declaration, as far as it is observable from outside:
  ``flags()`` is the union of the components' flags (lobe bits; integrators branch on it,
  e.g. path.cpp:238 samples emitters only when ``flags()`` has a Smooth lobe); the samples of
  one component report one ``sampled_type`` (a component is one lobe: the component index is
  how a context isolates a lobe, and every Mitsuba 3.9.1 built-in keeps to it -- ``hair``'s
  one glossy component reports GlossyReflection|GlossyTransmission, one type -- except
  ``blendbsdf``, whose nested indices are the finding blendbsdf-component-ids); and a
  non-delta sample has a density: no direction is drawn by ≥ 1 % (and ≥ 8) of a cell's
  non-delta samples (an atom, which a continuous density draws with probability 0: a delta
  lobe labelled diffuse or glossy; χ² and normalization see it too where they look).

Both hemispheres are inputs: ``eval_pdf``, ``weight``, ``pdf`` and ``component`` draw ω_i
over the whole sphere (the incidence cells and their mirror images below the surface,
:func:`whole_sphere`).  And the side flags are a contract (``component``): a BSDF whose
``flags()`` declare FrontSide and not BackSide must return eval = 0, pdf = 0 and no sample
(weight 0) for every ω_i below the surface (:func:`front_side_row`); a two-sided BSDF
(``twosided``, or any with BackSide) legitimately has lobes there and is not held to it.

Non-finite values are the ``finite`` topic's alone: the other topics drop those lanes (and
count them in ``details``), so that one defect fails one topic.  In ``component`` a sample is
one with a weight ≠ 0 and finite (:func:`.lanes.drawn`): ``blendbsdf`` of ``roughconductor``
and ``roughdielectric`` at cos θ_i = 0 returns weight NaN (its finding blendbsdf-nan-weight,
blendbsdf.cpp:151, 0 × a NaN pdf) for a sample that roughdielectric rejected (its
``active &= cos_theta_i != 0.f``, roughdielectric.cpp:258, and weight ``& active``, :357)
and labelled GlossyTransmission, the type of any inactive lane (the select at :311-313), so
with type_mask = GlossyReflection 2460 of those NaN samples reported a lobe outside the mask.
"""

from __future__ import annotations

import mitsuba as mi
import numpy as np

from ...verdict import NOT_APPLICABLE
from ... import probe
from . import lanes
from ..roundoff import DRAWS, REL_TOL, perturb, refine, rel_diff, sensitivity
from .rows import BOXED, ROUND_OFF, bounded_row, max_finite, worst_lane
from .topics import Row

SAMPLE_NOTE = ("; edge sample values 0 and 1 − ε; a sample with non-zero weight must have a "
               "finite pdf ≥ 0 and a unit wo, a rejected one (weight 0, which integrators "
               "drop) may not: {} rejected samples carry NaN")


def finite(bsdf, opts) -> list[Row]:
    r = lanes.rng(opts.seed, "finite")
    wi, _ = lanes.incident(opts.cells(), opts.n_finite)
    wo = np.concatenate([lanes.sphere(r, len(wi)), *lanes.special_wo(wi)])
    wi_all = np.concatenate([wi] * (len(wo) // len(wi)))
    ev = probe.eval(bsdf, wi_all, wo)
    pd = probe.pdf(bsdf, wi_all, wo)
    ev2, pd2 = probe.eval_pdf(bsdf, wi_all, wo)
    u1, u2 = lanes.sample_values(r, len(wi))
    s = probe.sample(bsdf, wi, u1, u2)
    norm = np.linalg.norm(s.wo, axis=1)
    live = np.any(s.weight != 0, axis=1)
    checks = {
        "eval": (~np.isfinite(ev) | (ev < 0)).any(axis=1),
        "pdf": ~np.isfinite(pd) | (pd < 0),
        "eval_pdf": (~np.isfinite(ev2) | (ev2 < 0)).any(axis=1) | ~np.isfinite(pd2) | (pd2 < 0),
        "sample": ((~np.isfinite(s.weight) | (s.weight < 0)).any(axis=1)
                   | (live & (~np.isfinite(s.pdf) | (s.pdf < 0) | ~np.isfinite(s.wo).all(axis=1)
                              | (np.abs(norm - 1.0) > 1e-3)))),
    }
    # A rejected sample (weight 0) is not used by an integrator: NaN in its wo/pdf is noted only.
    rejected_nan = int(np.sum(~live & (~np.isfinite(s.pdf) | ~np.isfinite(s.wo).all(axis=1))))
    rows = []
    for name, bad in checks.items():
        w_in, w_out = (wi, s.wo) if name == "sample" else (wi_all, wo)
        inputs = {"wi": w_in, "wo": w_out}
        if name == "sample":
            inputs.update(sample1=u1, sample2=u2)
        details = {"lanes": int(bad.size), "bad": int(bad.sum())}
        if name == "sample":
            details["rejected_samples_with_nan"] = rejected_nan
        if bad.any():
            k = np.flatnonzero(bad)[:5]
            details["examples"] = [{"wi": w_in[i].tolist(), "wo": w_out[i].tolist()} for i in k]
            details["cos_theta_i"] = sorted({round(float(w_in[i, 2]), 6) for i in k})
        rows.append(bounded_row("finite", f"{name}: NaN/Inf/negative values", float(bad.sum()), 0.0,
                         f"count of lanes with a NaN, Inf or negative {name} result over "
                         f"random, mirror, grazing and below-horizon directions"
                         + (SAMPLE_NOTE.format(rejected_nan) if name == "sample" else ""),
                         details, lanes=(bad.astype(float), inputs)))
    return rows


def whole_sphere(wi: np.ndarray) -> np.ndarray:
    """``wi`` followed by its mirror images below the surface (z → −z; the cos θ_i = 0 lanes,
    on the horizon, once)."""
    below = wi[wi[:, 2] > 0] * np.array([1.0, 1.0, -1.0])
    return np.concatenate([wi, below])


def eval_pdf(bsdf, opts) -> list[Row]:
    r = lanes.rng(opts.seed, "eval_pdf")
    wi, _ = lanes.incident(opts.cells(), opts.n_finite)
    wo = lanes.sphere(r, len(wi))
    # the lanes below the surface come after the upper ones: their random wo from a stream
    # of their own, so the upper lanes are those of every earlier run
    wi = whole_sphere(wi)
    wo = np.concatenate([wo, lanes.sphere(lanes.rng(opts.seed, "eval_pdf", 1),
                                          len(wi) - len(wo))])
    ev, pd = probe.eval(bsdf, wi, wo), probe.pdf(bsdf, wi, wo)
    ev2, pd2 = probe.eval_pdf(bsdf, wi, wo)
    rel_e = np.max(rel_diff(ev2, ev), axis=1)
    rel_p = rel_diff(pd2, pd)
    return [
        bounded_row("eval_pdf", "eval_pdf value = eval", max_finite(rel_e), REL_TOL,
             f"max relative |eval_pdf[0] − eval| over random wo; {ROUND_OFF}",
             worst_lane(rel_e, wi, wo, {"eval": ev[:, 0], "eval_pdf": ev2[:, 0]}),
             lanes=(rel_e, {"wi": wi, "wo": wo})),
        bounded_row("eval_pdf", "eval_pdf pdf = pdf", max_finite(rel_p), REL_TOL,
             f"max relative |eval_pdf[1] − pdf| over random wo; {ROUND_OFF}",
             worst_lane(rel_p, wi, wo, {"pdf": pd, "eval_pdf": pd2}),
             lanes=(rel_p, {"wi": wi, "wo": wo})),
    ]


def _samples(bsdf, opts):
    """Random samples at every incidence cell (shared by ``weight`` and ``pdf``), and the
    sampler's own sensitivity: the same sample values at wi moved by 8 ulps (roundoff.perturb)."""
    wi, _ = lanes.incident(opts.cells(), opts.n_identity)
    r = lanes.rng(opts.seed, "weight")
    u1, u2 = r.random(len(wi)), r.random((len(wi), 2))
    n_up = len(wi)
    wi = whole_sphere(wi)              # the lanes below: sample values of a stream of their own
    r_below = lanes.rng(opts.seed, "weight", 1)
    u1 = np.concatenate([u1, r_below.random(len(wi) - n_up)])
    u2 = np.concatenate([u2, r_below.random((len(wi) - n_up, 2))])
    s = probe.sample(bsdf, wi, u1, u2)
    draws = [probe.sample(bsdf, perturb(wi, r), u1, u2) for _ in range(DRAWS)]
    sens_w = np.max([np.nan_to_num(np.max(rel_diff(s.weight, d.weight), axis=1), nan=0.0)
                     for d in draws], axis=0)
    sens_p = np.max([np.nan_to_num(rel_diff(s.pdf, d.pdf), nan=0.0) for d in draws], axis=0)
    return wi, s, sens_w, sens_p


def weight_and_pdf(bsdf, opts, topics) -> list[Row]:
    wi, s, sens_w, sens_p = _samples(bsdf, opts)
    drawn = (s.pdf > 0) & ~lanes.delta_mask(s.sampled_type) & np.all(np.isfinite(s.wo), axis=1)
    live = np.any(s.weight != 0, axis=1) & drawn
    n_delta = int(np.sum(lanes.delta_mask(s.sampled_type) & np.any(s.weight != 0, axis=1)))
    rows = []
    if not live.any() and drawn.any():
        # Every non-delta sample has weight 0, Mitsuba's mark of a rejected sample: a black
        # BSDF (eval 0 wherever it samples) has nothing to compare; one whose eval is not 0
        # there returns weights that are wrong, and those lanes are compared.
        black = not np.any(probe.eval(bsdf, wi[drawn], s.wo[drawn]))
        if not black:
            live = drawn
    if not live.any():
        if drawn.any():
            why = ("every non-delta sample has weight 0 and eval is 0 wherever sample() points: "
                   "a black BSDF, nothing to compare")
        elif n_delta or lanes.delta_only(bsdf):
            why = (f"no non-delta sample with non-zero weight ({n_delta} delta samples): "
                   f"nothing to compare for a purely delta BSDF")
        else:
            why = ("sample() returned no usable sample: every weight is 0 and no bs.pdf is "
                   "finite and > 0 (a non-finite pdf is the finite topic's)")
        # a black or purely delta BSDF has nothing to compare (not applicable); a BSDF that
        # returned no usable sample at all is not covered (core.not_covered)
        na = {NOT_APPLICABLE: True} if (drawn.any() or n_delta or lanes.delta_only(bsdf)) else {}
        return [Row(t, n, None, None, None, None, "skipped", why, {"delta_samples": n_delta, **na})
                for t, n in (("weight", "weight = eval/pdf"), ("pdf", "bs.pdf = pdf(bs.wo)"))
                if t in topics]
    wi, wo, w, bpdf = wi[live], s.wo[live], s.weight[live], s.pdf[live]
    sens_w, sens_p = sens_w[live], sens_p[live]
    ev, pd = probe.eval(bsdf, wi, wo), probe.pdf(bsdf, wi, wo)
    r = lanes.rng(opts.seed, "weight")
    note = f"{int(live.sum())} non-delta samples (delta ones excluded: {n_delta})"

    def ratio_of(a, b):
        e, p = probe.eval(bsdf, a, b), probe.pdf(bsdf, a, b)
        return np.where(p[:, None] > 0, e / np.where(p > 0, p, 1.0)[:, None], 0.0)

    if "weight" in topics:
        ratio = np.where(pd[:, None] > 0, ev / np.where(pd > 0, pd, 1.0)[:, None], 0.0)
        rel = np.max(rel_diff(w, ratio), axis=1)
        ex, box = refine(rel, sensitivity(ratio_of, wi, wo, r, ratio), sens_w, ratio_of, wi,
                         wo, ratio)
        rows.append(bounded_row("weight", "weight = eval/pdf per sample", max_finite(ex), 1.0,
                         f"relative |weight − eval/pdf(bs.wo)| per sample; {note}; {BOXED}",
                         {**worst_lane(ex, wi, wo, {"weight": w[:, 0], "eval_over_pdf": ratio[:, 0],
                                                "rel_diff": rel}), **box},
                         lanes=(ex, {"wi": wi, "wo": wo})))
    if "pdf" in topics:
        rel = rel_diff(bpdf, pd)
        def pdf_of(a, b):
            return probe.pdf(bsdf, a, b)

        ex, box = refine(rel, sensitivity(pdf_of, wi, wo, r, pd), sens_p, pdf_of, wi, wo, pd)
        rows.append(bounded_row("pdf", "bs.pdf = pdf(bs.wo)", max_finite(ex), 1.0,
                         f"relative |bs.pdf − pdf(wi, bs.wo)| per sample; {note}; {BOXED}",
                         {**worst_lane(ex, wi, wo, {"bs_pdf": bpdf, "pdf": pd, "rel_diff": rel}),
                          **box}, lanes=(ex, {"wi": wi, "wo": wo})))
    return rows


#: An atom: a direction drawn by at least this fraction of a cell's non-delta samples ...
ATOM_FRACTION = 0.01
#: ... and by at least this many of them (a narrow lobe repeats a float32 direction by chance).
ATOM_MIN = 8


def atoms(wo: np.ndarray, cell: np.ndarray) -> tuple[int, list]:
    """Samples whose exact direction is drawn by ≥ ATOM_FRACTION (and ≥ ATOM_MIN) of their
    cell's samples, and up to 3 such directions as (cell, wo, count)."""
    count, examples = 0, []
    for c in np.unique(cell):
        dirs, n = np.unique(wo[cell == c], axis=0, return_counts=True)
        heavy = n >= max(ATOM_MIN, ATOM_FRACTION * n.sum())
        count += int(n[heavy].sum())
        examples += [(int(c), d.tolist(), int(k)) for d, k in zip(dirs[heavy], n[heavy])]
    return count, examples[:3]


def _declaration_rows(bsdf, flags: list, s, live, cell) -> list[Row]:
    """flags() = ∪ flags(k); one sampled_type per component; non-delta samples have no atom."""
    lobe_bits = int(mi.BSDFFlags.All)
    union = 0
    for f in flags:
        union |= f & lobe_bits
    declared = int(bsdf.flags()) & lobe_bits
    comp, stype = s.sampled_component[live], s.sampled_type[live] & lobe_bits
    types = {int(k): sorted({int(t) for t in stype[comp == k]}) for k in np.unique(comp)}
    mixed = {k: t for k, t in types.items() if len(t) > 1}
    # a non-unit or non-finite wo is the finite topic's (it fails there), not an atom
    unit = np.abs(np.linalg.norm(np.nan_to_num(s.wo), axis=1) - 1.0) <= 1e-3
    smooth = live & ~lanes.delta_mask(s.sampled_type) & np.all(np.isfinite(s.wo), axis=1) & unit
    n_atom, examples = atoms(s.wo[smooth], cell[smooth])
    return [
        bounded_row("component", "flags() = union of flags(k)", float(declared != union), 0.0,
                    f"flags() lobe bits {declared:#x} against the union of the components' "
                    f"{union:#x} (integrators branch on flags(): path.cpp:238)",
                    {"flags": declared, "union": union}),
        bounded_row("component", "one sampled_type per component", float(len(mixed)), 0.0,
                    f"count of components whose samples report more than one sampled_type "
                    f"(lobe bits; a component is one lobe) over {int(live.sum())} samples",
                    {"types": {str(k): t for k, t in types.items()}}),
        bounded_row("component", "non-delta samples have a density (no atom)", float(n_atom),
                    0.0, f"count of non-delta samples whose exact wo is drawn by ≥ "
                    f"{ATOM_FRACTION:.0%} (and ≥ {ATOM_MIN}) of their cell's non-delta samples "
                    f"(a delta lobe labelled non-delta), over {int(smooth.sum())} samples",
                    {"atoms": examples}),
    ]


def front_side_row(bsdf, opts) -> Row | None:
    """A BSDF declaring FrontSide and not BackSide: eval, pdf and sample's weight are exactly 0
    for ω_i below the surface (the incidence cells mirrored, random ω_o on the sphere); None
    for any other.  Exact (a zero is a zero in float32); a non-finite value is the finite
    topic's and is left out, and a row with no finite eval, pdf or weight at all fails (it
    judged nothing)."""
    flags = int(bsdf.flags())
    if not flags & int(mi.BSDFFlags.FrontSide) or flags & int(mi.BSDFFlags.BackSide):
        return None
    name = "FrontSide only: eval = pdf = 0 and no sample for ω_i below"
    up, _ = lanes.incident(opts.cells(), opts.n_identity // 4)
    wi = up[up[:, 2] > 0] * np.array([1.0, 1.0, -1.0])
    r = lanes.rng(opts.seed, "component", 2)
    wo = lanes.sphere(r, len(wi))
    ev, pd = probe.eval(bsdf, wi, wo), probe.pdf(bsdf, wi, wo)
    s = probe.sample(bsdf, wi, r.random(len(wi)), r.random((len(wi), 2)))
    fin = {"eval": np.all(np.isfinite(ev), axis=1), "pdf": np.isfinite(pd),
           "sample": np.all(np.isfinite(s.weight), axis=1)}
    bad = {"eval": fin["eval"] & np.any(ev != 0, axis=1), "pdf": fin["pdf"] & (pd != 0),
           "sample": fin["sample"] & np.any(s.weight != 0, axis=1)}
    judged = {k: int(v.sum()) for k, v in fin.items()}
    per_lane = bad["eval"] | bad["pdf"] | bad["sample"]
    counts = {k: int(v.sum()) for k, v in bad.items()}
    details = {"lanes": int(len(wi)), "finite_lanes": judged, "nonzero": counts,
               "flags": flags}
    if per_lane.any():
        k = int(np.flatnonzero(per_lane)[0])
        details.update(worst_wi=wi[k].tolist(), worst_wo=wo[k].tolist(),
                       eval=float(ev[k, 0]), pdf=float(pd[k]))
    if max(judged.values()) == 0:
        return Row("component", name, None, 0.0, None, 0.0, "fail",
                   "no finite eval, pdf or sample weight below the surface to judge (the "
                   "finite topic's): nothing checked", details)
    unjudged = [k for k, v in judged.items() if not v]
    return bounded_row("component", name, float(per_lane.sum()), 0.0,
                       f"count of lanes with ω_i below the surface (cos θ_i < 0) where eval, "
                       f"pdf or sample's weight is not 0 ({counts['eval']}, {counts['pdf']}, "
                       f"{counts['sample']}), over {len(wi)} lanes: flags() {flags:#x} declare "
                       f"FrontSide lobes only, so an integrator (and MIS) must see nothing there"
                       + (f"; no finite {' or '.join(unjudged)} value there (the finite "
                          f"topic's), judged on the others" if unjudged else "")
                       + ("" if not per_lane.any() else
                          "; a cos θ_i > 0 test missing from "
                          + " and ".join(k for k, v in counts.items() if v)),
                       details, lanes=(per_lane.astype(float), {"wi": wi, "wo": wo}))


def component(bsdf, opts) -> list[Row]:
    wi, cell = lanes.incident(opts.cells(), opts.n_identity // 2)
    n_up = len(wi)
    wi = whole_sphere(wi)
    cell = np.concatenate([cell, cell[:n_up][wi[:n_up, 2] > 0] + len(opts.cells())])
    k_count = bsdf.component_count()
    flags = [int(bsdf.flags(k)) for k in range(k_count)]
    s = probe.sample_random(bsdf, wi, len(wi), seed=lanes.STREAMS.int_seed(opts.seed, "component"))
    live = lanes.drawn(s)
    comp, stype = s.sampled_component[live], s.sampled_type[live]
    in_range = (comp >= 0) & (comp < k_count)
    comp_flags = np.array(flags + [0])[np.where(in_range, comp, k_count)]
    lobe_bits = int(mi.BSDFFlags.All)
    bad = ~in_range | ((stype & lobe_bits) == 0) | ((stype & lobe_bits & ~comp_flags) != 0)
    rows = [bounded_row("component", "sampled_component/sampled_type agree with the flags",
                 float(bad.sum()), 0.0,
                 f"count of samples whose sampled_type lobe bits are not within "
                 f"flags(sampled_component) over {int(live.sum())} samples; "
                 f"components: {k_count}",
                 {"flags": flags, "bad": int(bad.sum()),
                  "nonfinite": int((~lanes.finite_sample(s)).sum()),
                  "examples": [{"component": int(c), "type": int(t)}
                               for c, t in zip(comp[bad][:5], stype[bad][:5])]},
                 lanes=(bad.astype(float), {"wi": wi[live], "component": comp, "type": stype}))]
    rows += _declaration_rows(bsdf, flags, s, live, cell)
    front = front_side_row(bsdf, opts)
    if front is not None:
        rows.append(front)
    if k_count < 2:
        return rows
    r = lanes.rng(opts.seed, "component")
    wo = lanes.sphere(r, len(wi))
    full = probe.eval(bsdf, wi, wo)
    total = np.zeros_like(full)
    wrong, nonfinite = [], 0
    inputs = {"wi": [], "requested": [], "component": [], "type": []}
    for k in range(k_count):
        ctx = probe.context(component=k)
        total += probe.eval(bsdf, wi, wo, ctx)
        sk = probe.sample_random(bsdf, wi, len(wi), seed=opts.seed + 7 * k + 1, ctx=ctx)
        wrong.append(lanes.drawn(sk) & (sk.sampled_component != k))
        nonfinite += int((~lanes.finite_sample(sk)).sum())
        for name, v in (("wi", wi), ("requested", np.full(len(wi), k)),
                        ("component", sk.sampled_component), ("type", sk.sampled_type)):
            inputs[name].append(v)
    wrong = np.concatenate(wrong)
    rows.append(bounded_row("component", "restricted context samples only its component",
                     float(wrong.sum()), 0.0,
                     f"count of samples from a context restricted to component k that "
                     f"report another component, over k = 0..{k_count - 1}",
                     {"bad": int(wrong.sum()), "flags": flags, "nonfinite": nonfinite},
                     lanes=(wrong.astype(float), {n: np.concatenate(v) for n, v in inputs.items()})))
    rel = np.max(rel_diff(total, full), axis=1)
    rows.append(bounded_row("component", "Σ_k eval(component k) = eval", max_finite(rel), REL_TOL,
                     f"max relative |Σ_k eval_k − eval| over random wo; {ROUND_OFF}",
                     worst_lane(rel, wi, wo), lanes=(rel, {"wi": wi, "wo": wo})))
    return rows + type_mask_rows(bsdf, opts, wi, wo, full, flags)


def type_mask_rows(bsdf, opts, wi, wo, full, flags) -> list[Row]:
    """``ctx.type_mask`` honoured: with the lobe bits of one kind of component as the mask (its
    ``flags(k)``), samples report only lobes within it, and the evals under masks that share no
    bit add up to the full eval (an integrator asks for the smooth lobes alone for next-event
    estimation: path.cpp masks its emitter sampling by ``BSDFFlags.Smooth``).  No rows when the
    components are all of one kind of lobe."""
    lobe_bits = int(mi.BSDFFlags.All)
    masks = sorted({f & lobe_bits for f in flags if f & lobe_bits})
    if len(masks) < 2:
        return []
    wrong, inputs, nonfinite = [], {"wi": [], "mask": [], "type": []}, 0
    total = np.zeros_like(full)
    disjoint = all(a & b == 0 for i, a in enumerate(masks) for b in masks[i + 1:])
    for j, mask in enumerate(masks):
        ctx = probe.context(type_mask=mi.BSDFFlags(mask))
        if disjoint:
            total += probe.eval(bsdf, wi, wo, ctx)
        sj = probe.sample_random(bsdf, wi, len(wi), seed=opts.seed + 11 * j + 5, ctx=ctx)
        wrong.append(lanes.drawn(sj) & ((sj.sampled_type & lobe_bits & ~mask) != 0))
        nonfinite += int((~lanes.finite_sample(sj)).sum())
        for name, v in (("wi", wi), ("mask", np.full(len(wi), mask)), ("type", sj.sampled_type)):
            inputs[name].append(v)
    wrong = np.concatenate(wrong)
    names = ", ".join(f"{m:#x}" for m in masks)
    rows = [bounded_row("component", "type_mask: samples only the lobes asked for",
                        float(wrong.sum()), 0.0,
                        f"count of samples from a context whose type_mask is one component's "
                        f"lobe bits ({names}) that report a lobe outside it",
                        {"bad": int(wrong.sum()), "masks": masks, "nonfinite": nonfinite},
                        lanes=(wrong.astype(float), {n: np.concatenate(v)
                                                     for n, v in inputs.items()}))]
    if disjoint:
        rel = np.max(rel_diff(total, full), axis=1)
        rows.append(bounded_row("component", "type_mask: Σ eval(mask) = eval", max_finite(rel),
                                REL_TOL, f"max relative |Σ_mask eval − eval| over the disjoint "
                                f"masks {names}, random wo; {ROUND_OFF}",
                                worst_lane(rel, wi, wo), lanes=(rel, {"wi": wi, "wo": wo})))
    return rows

