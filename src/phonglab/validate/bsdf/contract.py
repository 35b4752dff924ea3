r"""The ``eval_null_transmission`` and ``eval_diffuse_reflectance`` topics: the two BSDF
methods besides eval/pdf/sample that Mitsuba's integrators call, held to what ``sample`` and
``eval`` produce.

``eval_null_transmission(si)`` -- "the un-scattered transmission (BSDFFlags::Null) of the BSDF
for light arriving from direction w; the default implementation returns zero"
(include/mitsuba/render/bsdf.h:460-473, default src/render/bsdf.cpp:33-36).  ``volpath``
multiplies a shadow ray's transmittance by it at every surface it passes
(src/integrators/volpath.cpp:531), while a path that reaches the same surface continues
through ``sample``'s Null lobe: the two must agree, or lights seen through a cut-out are too
bright or too dark.  Checked: with a context of the Null lobe only
(``BSDFContext(type_mask=Null)``), the mean over N samples of weight · 1{sampled_type ∋ Null
and wo = −wi} equals eval_null_transmission(wi) (channel mean), to z·stderr + 2⁻¹⁰ relative
(+ 1e-6), z the Šidák critical value over the BSDF's statistical tests (each cell is one); and
every Null sample leaves along −wi (to 1e-4, the χ² topic's direction tolerance).  A plugin
that ignores the context samples every lobe, and the indicator keeps its Null part only, so
the same mean holds.  The built-ins do this: thindielectric.cpp:164-173 samples the Null lobe
alone (a Null-only context) with weight t = 1 − r' (r' = 2r/(1 + r)) and pdf 1, and
eval_null_transmission (:203-217) returns the same 1 − r'; mask.cpp:142-146 picks its Null
lobe with probability 1 − opacity and weight 1, eval_null_transmission (:219-223) is
1 − opacity·(1 − nested's); null.cpp:41-66 and :80-86 both give 1; blendbsdf.cpp:235-243
blends the nested values as its sample (:108-159) blends the lobes.  A BSDF without a Null lobe (its flags()
has no BSDFFlags::Null) must return 0 at every incidence (deterministic: ≤ 1e-6).

``eval_diffuse_reflectance(si)`` -- "approximates the total diffuse reflectance for a given
direction.  For some materials, an exact value can be computed inexpensively.  When this is not
possible, the value is approximated by evaluating the BSDF for a normal outgoing direction and
returning this value multiplied by pi" (bsdf.h:566-581; the default, bsdf.cpp:38-43, is
π·eval(ctx, si, (0, 0, 1))); the ``aov`` integrator's albedo (src/integrators/aov.cpp:83-84,
257: "depending on the material, this value might only be an approximation").  The value is
exact, and checked, where the diffuse reflectance is defined without approximation: at an
incidence where every component whose flags contain DiffuseReflection is Lambertian -- its
eval_k(ω_i, ω_o) / cos θ_o does not depend on ω_o over the upper hemisphere (to 2⁻¹⁰
relative, at the quadrature nodes with cos θ_o ≥ 1e-3) -- the diffuse reflectance is the
diffuse components' albedo

    Σ_k ∫_{H+} eval_k(ω_i, ω_o) dω_o    (a context restricted to component k),

which Mitsuba's own default also returns there for a BSDF that is only diffuse (π·f·cos 0).
Checked: eval_diffuse_reflectance (channel by channel) equals it to |Q(n) − Q(n/2)| +
2⁻¹⁰ relative + 1e-5 (:data:`.lobes.FLOOR`), Q by :mod:`.lobes` centred on the normal -- or
equals the documented approximation π·eval(wi, (0, 0, 1)) (to 2⁻¹⁰ relative + 1e-6), which a
BSDF that does not override the method inherits: then it passes, and the reason says at how
many cells and by how much that approximation differs from the diffuse albedo (a glossy lobe
at the normal adds to it: ``blendbsdf`` of ``diffuse`` and ``roughconductor`` reports 7.85
for an albedo of 0.35 at normal incidence, blendbsdf.cpp:228-232 blending roughconductor's
inherited default).  At an
incidence where a diffuse component is not Lambertian (a Fresnel-weighted lobe: plastic.cpp,
roughplastic.cpp return their diffuse_reflectance parameter, :362-365 and :504-507, while the
lobe reflects ρ·t_i·t_o/(η²(1 − ρ F_dr))/π; principled.cpp:839-842 returns base_color for a
Disney lobe with retro-reflection) Mitsuba documents the value as an approximation: those
cells are not held to it, their ratio is in ``details``.  A BSDF that declares no diffuse
reflection component is skipped.
"""

from __future__ import annotations

import math

import mitsuba as mi
import numpy as np

from ...verdict import NOT_APPLICABLE
from ... import probe, stats
from . import lanes, lobes
from ..roundoff import ABS_FLOOR, REL_TOL
from .sampling import DIRECTION_TOL
from .topics import Row

#: Smallest cos θ_o of the nodes where a lobe's eval / cos θ_o is compared (float32 eval
#: near the horizon is a few ulps of a tiny value: no test of its shape).
LAMBERT_MIN_COS = 1e-3


def has_null(bsdf) -> bool:
    """True when the BSDF declares a Null (un-scattered transmission) lobe."""
    return lanes.bsdf_has(bsdf, mi.BSDFFlags.Null)


def diffuse_components(bsdf) -> list[int]:
    """The indices of the components whose flags contain DiffuseReflection."""
    bit = int(mi.BSDFFlags.DiffuseReflection)
    return [k for k in range(bsdf.component_count()) if int(bsdf.flags(k)) & bit]


def _null_part(bsdf, cells: np.ndarray, opts):
    """Per cell: (mean, stderr) of weight · 1{Null sample along −wi} (channel mean) under a
    Null-only context, and the worst |wo + wi| of a Null sample with non-zero weight."""
    n = opts.null_samples
    wi, _ = lanes.incident(cells, n)
    r = lanes.rng(opts.seed, "eval_null_transmission")
    ctx = probe.context(type_mask=mi.BSDFFlags.Null)
    s = probe.sample(bsdf, wi, r.random(len(wi)), r.random((len(wi), 2)), ctx)
    w = s.weight.mean(axis=1)
    null = ((s.sampled_type & int(mi.BSDFFlags.Null)) != 0) & np.isfinite(w) & (w != 0)
    off = np.where(null, np.max(np.abs(s.wo + wi), axis=1), 0.0)
    off = np.nan_to_num(off, nan=np.inf)
    x = np.where(null & (off <= DIRECTION_TOL), w, 0.0).reshape(len(cells), n)
    return x.mean(axis=1), x.std(axis=1, ddof=1) / math.sqrt(n), off, int(null.sum())


def eval_null_transmission(bsdf, opts, m_tests: int) -> list[Row]:
    cells = opts.cells()
    wi = lanes.exact(probe.direction(cells[:, 0], cells[:, 1]))
    value = probe.eval_null_transmission(bsdf, wi).mean(axis=1)
    theta = np.degrees(cells[:, 0])
    if not has_null(bsdf):
        worst = float(np.max(np.abs(np.nan_to_num(value, nan=np.inf))))
        k = int(np.argmax(np.abs(np.nan_to_num(value, nan=np.inf))))
        return [Row("eval_null_transmission", "no Null lobe: eval_null_transmission = 0", worst,
                    0.0, None, ABS_FLOOR, "pass" if worst <= ABS_FLOOR else "fail",
                    f"flags() has no BSDFFlags::Null, so nothing passes un-scattered: max "
                    f"|eval_null_transmission| over {len(cells)} incidence cells (the default, "
                    f"bsdf.cpp:33-36, returns 0)",
                    {"theta_deg": theta.tolist(), "value": value.tolist(),
                     "worst_wi": wi[k].tolist()})]
    mean, se, off, n_null = _null_part(bsdf, cells, opts)
    z = stats.z_critical(stats.ALPHA, m_tests)
    band = z * se + REL_TOL * np.maximum(np.abs(value), np.abs(mean)) + ABS_FLOOR
    dev = np.abs(np.nan_to_num(value, nan=np.inf) - mean)
    bad = dev > band
    k = int(np.argmax(dev / band))
    where = ", ".join(f"θ_i = {theta[i]:.1f}° φ = {cells[i, 1]:.2f} ({value[i]:.5g} vs "
                      f"{mean[i]:.5g})" for i in np.flatnonzero(bad))
    worst_off = float(off.max()) if off.size else 0.0
    return [
        Row("eval_null_transmission", "eval_null_transmission = mean Null-sample weight",
            float(value[k]), float(mean[k]), float(se[k]), float(band[k]),
            "fail" if bad.any() else "pass",
            f"eval_null_transmission(wi) against the mean over {opts.null_samples} samples "
            f"(context: the Null lobe only) of weight · 1{{Null sample, wo = −wi}}, channel "
            f"mean, at {len(cells)} incidence cells; band z·stderr + 2^-10 relative + 1e-6, "
            f"z = {z:.3f} (Šidák over {m_tests} tests)"
            + (f"; DIFFERENT at {where}" if bad.any() else ""),
            {"theta_deg": theta.tolist(), "phi": cells[:, 1].tolist(), "value": value.tolist(),
             "sampled": mean.tolist(), "stderr": se.tolist(), "band": band.tolist(),
             "null_samples": n_null}),
        Row("eval_null_transmission", "Null samples leave along −wi", worst_off, 0.0, None,
            DIRECTION_TOL, "pass" if worst_off <= DIRECTION_TOL else "fail",
            f"max |wo + wi| over the {n_null} Null samples with non-zero weight (un-scattered "
            f"transmission continues the ray); tolerance {DIRECTION_TOL:g} (float32)",
            {"off_direction": int(np.sum(off > DIRECTION_TOL))}),
    ]


def _diffuse_albedo(bsdf, comps, cells, n):
    """Per cell and channel: Σ_k ∫ eval_k dω_o (upper hemisphere, rule centred on the normal),
    and whether every diffuse component is Lambertian there (eval_k / cos θ_o constant).

    A component that is 0 at some lit incidences and not at others depends on ω_i, so it is
    not Lambertian at the incidences where it vanishes either (a Lambertian lobe is constant
    in ω_i and ω_o alike): plastic at η < 1 totally reflects light beyond the critical angle
    at its coating, its diffuse term (1 − F(ω_i))… is 0 there, and Mitsuba documents
    eval_diffuse_reflectance as an approximation for such a lobe (bsdf.h:566-575).  A
    component that is 0 at every incidence (a black one) is Lambertian with albedo 0."""
    wo, w = lobes.nodes((0.0, 0.0, lobes.FALLBACK_WIDTH), None, n)
    wis = lanes.exact(probe.direction(cells[:, 0], cells[:, 1]))
    wi = np.repeat(wis, len(wo), axis=0)
    wo_all = np.tile(wo, (len(cells), 1))
    shaped = wo_all[:, 2] >= LAMBERT_MIN_COS
    total, lambert = 0.0, np.ones(len(cells), dtype=bool)
    for k in comps:
        ev = probe.eval(bsdf, wi, wo_all, probe.context(component=k))
        ev = np.where(np.isfinite(ev), ev, 0.0)
        c = ev.shape[1]
        total = total + np.einsum("mnc,n->mc", ev.reshape(len(cells), len(wo), c), w)
        g = (ev[shaped] / wo_all[shaped, 2:3]).reshape(len(cells), -1, c)
        ref = np.median(g, axis=1, keepdims=True)
        spread = np.max(np.abs(g - ref), axis=1) / np.maximum(np.abs(ref[:, 0]), ABS_FLOOR)
        vanishes = np.all(ev.reshape(len(cells), -1) == 0.0, axis=1)
        lambert &= np.all(spread <= REL_TOL, axis=1) & (~vanishes | vanishes.all())
    return total, lambert


def eval_diffuse_reflectance(bsdf, opts) -> list[Row]:
    topic, name = "eval_diffuse_reflectance", "eval_diffuse_reflectance = diffuse albedo"
    comps = diffuse_components(bsdf)
    if not comps:
        return [Row(topic, name, None, None, None, None, "skipped",
                    "no component declares DiffuseReflection: the value is Mitsuba's "
                    "approximation π·eval(wi, n) (bsdf.cpp:38-43), no exact diffuse "
                    "reflectance to hold it to", {NOT_APPLICABLE: True})]
    cells = opts.cells()
    cells = cells[np.cos(cells[:, 0]) > 1e-6]          # lit incidences: a reflectance is defined
    wi = lanes.exact(probe.direction(cells[:, 0], cells[:, 1]))
    value = probe.eval_diffuse_reflectance(bsdf, wi)
    a, lambert = _diffuse_albedo(bsdf, comps, cells, opts.energy_nodes)
    a_half, _ = _diffuse_albedo(bsdf, comps, cells, opts.energy_nodes // 2)
    band = (np.abs(a - a_half) + REL_TOL * np.maximum(np.abs(a), np.abs(value))
            + lobes.FLOOR)
    dev = np.max(np.abs(np.nan_to_num(value, nan=np.inf) - a) / band, axis=1)
    theta = np.degrees(cells[:, 0])
    details = {"theta_deg": theta.tolist(), "phi": cells[:, 1].tolist(),
               "value": value.mean(axis=1).tolist(), "diffuse_albedo": a.mean(axis=1).tolist(),
               "band": band.max(axis=1).tolist(), "lambertian": lambert.tolist(),
               "components": comps}
    if not lambert.any():
        ratio = value.mean(axis=1) / np.maximum(a.mean(axis=1), ABS_FLOOR)
        return [Row(topic, name, None, None, None, None, "skipped",
                    f"the diffuse component(s) {comps} are not Lambertian at any incidence "
                    f"(eval/cos θ_o varies with ω_o): Mitsuba documents the value as an "
                    f"approximation there (bsdf.h:566-575, aov.cpp:83-84); eval_diffuse_"
                    f"reflectance / diffuse albedo = {ratio.min():.3g} to {ratio.max():.3g}",
                    {**details, NOT_APPLICABLE: True})]
    default = math.pi * probe.eval(bsdf, wi, np.array([0.0, 0.0, 1.0]))
    approx = np.all(np.abs(value - default) <= REL_TOL * np.maximum(np.abs(value), np.abs(default))
                    + ABS_FLOOR, axis=1) & lambert & (dev > 1.0)
    details["default_approximation"] = default.mean(axis=1).tolist()
    dev = np.where(lambert & ~approx, dev, 0.0)
    bad = dev > 1.0
    note = (f"; {int(approx.sum())} cells return Mitsuba's documented approximation "
            f"π·eval(wi, n) (bsdf.cpp:38-43) instead, {value[approx].mean(axis=1).min():.4g} to "
            f"{value[approx].mean(axis=1).max():.4g} for a diffuse albedo of "
            f"{a[approx].mean(axis=1).min():.4g} to {a[approx].mean(axis=1).max():.4g}"
            if approx.any() else "")
    k = int(np.argmax(dev))
    where = ", ".join(f"θ_i = {theta[i]:.1f}° φ = {cells[i, 1]:.2f} "
                      f"({value[i].mean():.5g} vs {a[i].mean():.5g})" for i in np.flatnonzero(bad))
    return [Row(topic, name, float(value[k].mean()), float(a[k].mean()), None,
                float(band[k].max()), "fail" if bad.any() else "pass",
                f"eval_diffuse_reflectance(wi) against Σ_k ∫ eval_k dω_o over the diffuse "
                f"components {comps} (Gauss-Legendre, {opts.energy_nodes} nodes/panel), channel "
                f"by channel, at the {int(lambert.sum())} of {len(cells)} lit incidence cells "
                f"where they are Lambertian (elsewhere Mitsuba documents an approximation); "
                f"band |Q{opts.energy_nodes} − Q{opts.energy_nodes // 2}| + 2^-10 relative + "
                f"1e-5, or equal to π·eval(wi, n)" + note
                + (f"; DIFFERENT at {where}" if bad.any() else ""), details)]
