r"""Mitsuba 3.9.1's built-in integrators (and phonglab's ``whitted``) as conformance cases:
:data:`CATALOGUE`, the integrator table of ``make conformance``
(docs/conformance-integrators.md), with the documented behaviours behind failing rows
(:data:`FINDINGS`, matched by their rows) and the plugins left out (:data:`LEFT_OUT`).

Each case is a ``mi.load_dict`` spec validated by
:func:`phonglab.validate.validate_integrator` (rebuilt per scene at the
scene's depth where it takes ``max_depth``, :mod:`.setup`).
"""

from __future__ import annotations

from ..conformance import Catalogue, Finding, KindCase, ValidatorIssue, with_known

POLARIZED = "llvm_ad_spectral_polarized"

_PLANE = "plane under a point light"
_SLOPES = ("convergence: RMSE slope over all spp", "convergence: slope of the last two spp")

#: Documented behaviours behind failing rows of the integrator table.
FINDINGS: tuple[Finding, ...] = (
    Finding("prb_basic-no-emitter-sampling", "bias", ("prb_basic",),
            "src/python/python/ad/integrators/prb_basic.py:28",
            "prb_basic is the 'basic Path Replay Backpropagation-style integrator *without* "
            "next event estimation' (its docstring): light reaches the camera only where a "
            "BSDF-sampled ray hits an emitter, so a point light (a delta emitter no ray can "
            "hit) contributes nothing; a render of a scene lit by point, spot or directional "
            "lights is black",
            "image mean 0.0000 on a diffuse plane under a point light (reproducer; path 0.2826)",
            "path's image; the table's plane: 0.424923 (rho I Omega/(pi A))",
            "tests/repro/prb_basic_point_light.py", bug=False,
            excerpt="Basic Path Replay Backpropagation-style integrator *without* next event",
            rows=(_PLANE,)),
    Finding("prb_basic-no-emitter-sampling-convergence", "convergence", ("prb_basic",),
            "src/python/python/ad/integrators/prb_basic.py:28",
            "the same: the plane's image is 0 at every spp, a constant error (slope 0)",
            "slope 0", "-1/2", "tests/repro/prb_basic_point_light.py", bug=False,
            excerpt="Basic Path Replay Backpropagation-style integrator *without* next event",
            rows=_SLOPES),
    Finding("volpathmis-roulette-mis", "bias", ("volpathmis",),
            "src/integrators/volpathmis.cpp:240",
            "in an iteration where Russian roulette runs (depth > rr_depth, line 238) a "
            "surviving path's p_over_f is multiplied by the survival probability q (lines "
            "239-240), but p_over_f_nee, the next-event strategy's pdf/f of the same path, was "
            "copied from p_over_f at the last real scattering (line 437; line 339 in a medium) "
            "and keeps no q.  An emitter hit by a BSDF- or phase-sampled ray then adds "
            "emitted / (p_over_f + p_over_f_nee) (lines 393-397, 657-671), f / (q p_bsdf + "
            "p_nee) instead of the balance heuristic's f / (q (p_bsdf + p_nee)).  Only those "
            "hits are under-weighted, and only in roulette iterations: next-event estimation "
            "keeps its weight p_nee / (p_nee + p_bsdf) (lines 410-415), so the two weights sum "
            "to less than one; hits by camera rays and specular chains take mis_weight(p_over_f) "
            "alone (count_direct, line 384); no iteration up to rr_depth is affected, and "
            "an emitter hit is handled only while depth < max_depth (line 244), so the bias "
            "needs rr_depth <= max_depth - 2; volpath is not affected.  In the closed "
            "enclosure of albedo 0.8 (Le = 2, max_depth 64, every pixel sees 10) the image is "
            "-2.1 % with the default rr_depth 5 (the table's row: 9.791 ± 0.004) and -3.3 % "
            "with rr_depth 1",
            "the enclosure of albedo 0.8, max_depth 64 (reproducer): 9.6742 ± 0.0352 for 10 at "
            "rr_depth 1, 9.9991 ± 0.0024 at rr_depth 1000 (roulette off)",
            "Le (1 - rho^D)/(1 - rho) = 10", "tests/repro/volpathmis_rr_mis.py",
            excerpt="update_weights(p_over_f, dr::detach(q), 1.0f, channel, perform_rr);",
            rows=("enclosure ρ=0.8 D=64",), at=(("rr_depth", (1, 62)),)),
    Finding("direct-delta-emitter-samples", "bias", ("direct",),
            "src/integrators/direct.cpp:180",
            "the emitter strategy's weight is dr::select(ds.delta, 1, mis_weight(...) * "
            "m_weight_lum) (lines 180-181): the 1/emitter_samples factor m_weight_lum (line "
            "109) multiplies the MIS weight of area lights only, so a delta light (point, "
            "spot, directional) adds its whole contribution once per emitter sample: the "
            "image is emitter_samples times the exact one (mitsuba3 issue #1861, fix "
            "proposed in PR #1863)",
            "image mean 0.2826 at emitter_samples 1, 1.1303 at 4: ratio 4.000 (reproducer: a "
            "diffuse plane under a point light)",
            "the same image at every emitter_samples (ratio 1); the table's plane: 0.424923 "
            "(rho I Omega/(pi A))",
            "tests/repro/direct_delta_emitter_samples.py",
            excerpt="Float mis = dr::select(ds.delta, Float(1.f), mis_weight(",
            rows=(_PLANE,),
            at=(("emitter_samples", (2, 1e9)),)),
    Finding("direct-delta-emitter-samples-convergence", "convergence", ("direct",),
            "src/integrators/direct.cpp:180",
            "the same: the plane's image converges to emitter_samples times the exact value, "
            "so its error against the exact pixels stops falling (slope 0)",
            "slope 0", "-1/2", "tests/repro/direct_delta_emitter_samples.py",
            excerpt="Float mis = dr::select(ds.delta, Float(1.f), mis_weight(",
            rows=_SLOPES,
            at=(("emitter_samples", (2, 1e9)),)),
    Finding("volpathmis-roulette-mis-shallow", "bias", ("volpathmis",),
            "src/integrators/volpathmis.cpp:240",
            "the same roulette MIS weight (volpathmis-roulette-mis): with rr_depth 1 roulette "
            "runs from the second iteration (depth > rr_depth, line 238), so the emitter hits "
            "of the third vertex are under-weighted and a depth-3 scene shows it; from rr_depth "
            "2 on no iteration of a depth-3 path both runs roulette and counts an emitter hit "
            "(depth < max_depth, line 244) and the row passes",
            "the enclosure of albedo 0.5, max_depth 3 (reproducer): 3.3676 ± 0.0012 for 3.5 at "
            "rr_depth 1, 3.5000 ± 0.0007 at rr_depth 2",
            "Le (1 - rho^D)/(1 - rho) = 3.5", "tests/repro/volpathmis_rr_mis.py",
            excerpt="update_weights(p_over_f, dr::detach(q), 1.0f, channel, perform_rr);",
            rows=("enclosure ρ=0.5 D=3",), at=(("rr_depth", 1),)),
    Finding("volpathmis-roulette-mis-agreement", "agreement", ("volpathmis",),
            "src/integrators/volpathmis.cpp:240",
            "the same roulette MIS weight (volpathmis-roulette-mis): in the agreement box (an "
            "area light, max_depth 5) roulette runs in the iterations with depth > rr_depth "
            "(line 238), and the emitter hits of BSDF-sampled rays counted there (depth < 5, "
            "line 244) are under-weighted: with rr_depth 1 every hit from the third vertex on, "
            "with rr_depth 3 those of the fifth; from rr_depth 4 on no such iteration is left "
            "and the row passes",
            "the enclosure of albedo 0.5 at the box's max_depth 5 (reproducer): 3.8213 ± "
            "0.0011 for 3.875 at rr_depth 3, 3.8745 ± 0.0008 at rr_depth 4",
            "the block means of path (max_depth 5)", "tests/repro/volpathmis_rr_mis.py",
            excerpt="update_weights(p_over_f, dr::detach(q), 1.0f, channel, perform_rr);",
            rows=("block means against path (max_depth 5)",), at=(("rr_depth", (1, 3)),)),
    Finding("prbvolpath-depth-limit", "bias", ("prbvolpath",),
            "src/python/python/ad/integrators/prbvolpath.py:192",
            "`active &= depth < self.max_depth` (line 192) masks `active` and the medium "
            "events but not `active_surface`, set from `active` earlier in the same iteration "
            "(line 152): a path whose BSDF sample made depth == max_depth still adds the "
            "(MIS-weighted) emission its ray hits and samples once more, so max_depth D "
            "renders part of vertex D + 1: +32 % at D = 1, +11 % at D = 2, +4.8 % at D = 3 in "
            "the albedo-0.5 enclosure; nothing once roulette has ended the paths (D = 64)",
            "the enclosure of albedo 0.5 (reproducer): 2.6441 at max_depth 1, 3.3311 at 2",
            "2, 3 (path: 2.0000, 2.9995)",
            "tests/repro/prbvolpath_depth_limit.py",
            excerpt="active &= depth < self.max_depth",
            rows=("enclosure ρ=0.5 D=1", "enclosure ρ=0.5 D=2", "enclosure ρ=0.5 D=3")),
    Finding("whitted-model-scope", "bias", ("whitted/radiance",), "plugins/whitted.py:49",
            "phonglab's Whitted model lights surfaces by point, spot and directional emitters "
            "only; area and environment emitters are seen directly or through delta "
            "reflections and refractions, never as light on a diffuse surface (the ambient "
            "term stands in for them): in the emitting enclosure it returns Le at every "
            "depth.  Where its model is exact (point lights, max_depth 2, radiance units) it "
            "is Mitsuba's path term for term and passes (the plane's bias and convergence)",
            "the enclosure of albedo 0.5 at max_depth 2 (reproducer): whitted 2.0000, path "
            "3.0034", "Le (1 - rho^D)/(1 - rho): 3 at D = 2, 3.5 at D = 3",
            "tests/repro/whitted_area_light.py", bug=False,
            excerpt="Area and environment emitters do not",
            rows=("enclosure ρ=0.5 D=2", "enclosure ρ=0.5 D=3")),
    Finding("whitted-model-scope-agreement", "agreement", ("whitted/radiance",),
            "plugins/whitted.py:49",
            "the same scope: the agreement box is lit by an area light, which the Whitted "
            "model never lets reach a diffuse wall (the box's walls are dark)",
            "the enclosure of albedo 0.5 at max_depth 2 (reproducer): whitted 2.0000, path "
            "3.0034",
            "path's image at depth 5", "tests/repro/whitted_area_light.py", bug=False,
            excerpt="Area and environment emitters do not",
            rows=("block means against path (max_depth 5)",)),
)


def catalogue_cases() -> list[KindCase]:
    """Every case of the integrator conformance table, in table order."""
    path = {"type": "path"}
    out = [
        KindCase("path", {"type": "path"}, note="unidirectional, MIS"),
        KindCase("direct", {"type": "direct"}, note="direct illumination (depth-2 model)"),
        KindCase("volpath", {"type": "volpath"}, note="volumetric path tracer (no media here)"),
        KindCase("volpathmis", {"type": "volpathmis"}, note="spectral MIS volumetric path "
                                                            "tracer (no media here)"),
        KindCase("ptracer", {"type": "ptracer"}, note="particle tracer (light paths)"),
        KindCase("prb", {"type": "prb"}, note="Path Replay Backpropagation"),
        KindCase("prb_basic", {"type": "prb_basic"}, note="PRB without emitter sampling"),
        KindCase("prbvolpath", {"type": "prbvolpath"}, note="volumetric PRB (no media here)"),
        KindCase("direct_projective", {"type": "direct_projective"},
                 note="projective direct illumination (keeps max_depth 2)"),
        KindCase("prb_projective", {"type": "prb_projective"},
                 note="projective PRB (visibility gradients)"),
        KindCase("moment", {"type": "moment", "nested": path},
                 note="first and second moments of path (AOV)"),
        KindCase("aov", {"type": "aov", "aovs": "dd.y:depth,nn:sh_normal"},
                 note="depth and shading-normal AOVs"),
        KindCase("depth", {"type": "depth"}, note="distance to the first hit"),
        KindCase("stokes", {"type": "stokes", "nested": path}, POLARIZED,
                 note="Stokes vector of path (polarized)"),
        KindCase("whitted/radiance", {"type": "whitted", "units": "radiance"},
                 note="phonglab: Whitted, radiance units"),
    ]
    return with_known(out, FINDINGS)


#: Mitsuba 3.9.1 integrator plugins not in the table, and why.
LEFT_OUT: dict[str, str] = {
    "volprim_rf_basic": "renders volumetric primitives (ellipsoids as a radiance field) only; "
                        "the validator's scenes hold surfaces and emitters it does not shade",
}

#: Rows of the integrator table that fail because of the validator while its fix is open (the
#: fixed ones are told in docs/validator-fixes.md).
VALIDATOR_ISSUES: tuple[ValidatorIssue, ...] = ()

CATALOGUE = Catalogue(
    catalogue_cases, "phonglab.validate.integrator.builtins.catalogue_cases()", FINDINGS,
    "phonglab.validate.integrator.builtins.FINDINGS", VALIDATOR_ISSUES, LEFT_OUT,
    tests="tests/test_conformance_kinds.py", case_text="one integrator at one setting")
