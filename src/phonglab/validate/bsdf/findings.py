r"""Every Mitsuba 3.9.1 behaviour behind a failing row of the BSDF conformance table.

A :class:`~phonglab.validate.conformance.Finding` pins a row that fails in Mitsuba to its source
line (``file:line`` at tag v3.9.1, commit
:data:`~phonglab.validate.conformance.MITSUBA_COMMIT`), one sentence of cause, what the probe
measures, what a correct plugin gives and a reproducer in ``tests/repro/`` that exits 1 while
the behaviour is present (the polarized topics' findings are :mod:`.polarized_findings`, the
``component`` topic's :mod:`.component_findings`);
:func:`phonglab.validate.conformance.known_causes` turns
:data:`FINDINGS` into the ``known`` entries of the catalogue's cases (their rows are reported as
KNOWN).  The rows traced to the validator itself are :data:`.builtins.VALIDATOR_ISSUES`.
"""

from __future__ import annotations

from ..conformance import Finding
from .component_findings import COMPONENT_FINDINGS, SPEC_TRANS_ON
from .polarized_findings import POLARIZED_FINDINGS, PPLASTIC_GRAZING
from .signatures import (BelowHorizon, Chi2Outside, Chi2Excess, GrazingIncidence, IncidenceFrom,
                         MaskedReflection, ParameterAt, SampleEdgeAtNormalIncidence, SamplePoint,
                         Union)

#: Cases whose sample() returns NaN directions/pdfs from microfacet sampling (measured over
#: sample values {0, 1e-7, 0.5, 1 - 2^-24}^3 and incidence angles including below the horizon).
_MICROFACET_NAN = ("roughconductor/beckmann-a0.2", "roughconductor/ggx-a0.3-Cu",
                   "roughconductor/ggx-aniso", "roughconductor/ggx-Cu-spectral",
                   "roughconductor/polarized", "roughdielectric/ggx-a0.3",
                   "roughdielectric/ggx-aniso-inverted", "roughplastic/ggx-a0.25",
                   "roughplastic/ggx-a0.5-nonlinear", "principled/default", "principled/metal",
                   "principledthin/all-lobes", "twosided/diffuse|roughconductor",
                   "bumpmap/roughconductor", "normalmap/roughconductor",
                   "mask/roughconductor-0.8", "pplastic/rough-ggx")

#: Row names the findings' signatures refer to (as the topics name them).
CHI2_ROW = "sampling matches pdf (min p-value)"
SAMPLE_ROW = "sample: NaN/Inf/negative values"
NAN_ROWS = ("pdf: NaN/Inf/negative values", "eval_pdf: NaN/Inf/negative values")
NORM_ROW = "∫ pdf dω_o = P(sample counted)"
ENERGY_ROW = "directional albedo ≤ 1"
REFLECTION_ROW = "f(wi, wo) = f(wo, wi), reflection"
TRANSMISSION_ROW = "f(wi, wo) = f*(wo, wi), transmission (η² form)"

#: Every roughplastic case: a sweep reaches both reflectances 0 from each of them.
_ROUGHPLASTIC = ("roughplastic/beckmann-a0.1", "roughplastic/beckmann-a0.25",
                 "roughplastic/ggx-a0.25", "roughplastic/ggx-a0.5-nonlinear",
                 "roughplastic/black")
BLACK_PLASTIC = (("diffuse_reflectance", 0.0), ("specular_reflectance", 0.0))
#: The plastic cases (a sweep reaches both reflectances 0 and int_ior 3 from the default).
_PLASTIC = ("plastic/default", "plastic/nonlinear-ior1.9")
#: The pplastic cases (a sweep reaches both reflectances 0 and int_ior 3 from each).
_PPLASTIC = ("pplastic/default", "pplastic/rough-ggx")

#: Every Mitsuba 3.9.1 behaviour behind a failing row of the conformance table.
FINDINGS: tuple[Finding, ...] = POLARIZED_FINDINGS + COMPONENT_FINDINGS + (
    Finding("roughplastic-pdf-below-horizon", "chi2",
            ("roughplastic/beckmann-a0.1", "roughplastic/beckmann-a0.25",
             "roughplastic/ggx-a0.25", "roughplastic/ggx-a0.5-nonlinear"),
            "src/bsdfs/roughplastic.cpp:422",
            "pdf() returns `result` without masking it by `active` (cos_theta_o > 0, line 391; "
            "eval_pdf() likewise at line 501), so in vectorized variants wo below the horizon "
            "gets the specular density that sample() never produces",
            "pdf(wo below the horizon) = 0.0677 in llvm_ad_rgb (eval_pdf alike), 0 in "
            "scalar_rgb (alpha 0.25, wi at 45 deg)",
            "pdf = 0 below the horizon (scalar_rgb gives 0); chi2 passes when the pdf is masked "
            "to wo.z > 0 (p = 0.09-0.78 at 0-85 deg, both distributions)",
            "tests/repro/roughplastic_pdf_below_horizon.py",
            excerpt="return result;",
            rows=(CHI2_ROW,), region=Chi2Outside("below_horizon")),
    Finding("roughplastic-pdf-below-horizon-normalization", "normalization",
            ("roughplastic/beckmann-a0.1", "roughplastic/beckmann-a0.25",
             "roughplastic/ggx-a0.25", "roughplastic/ggx-a0.5-nonlinear"),
            "src/bsdfs/roughplastic.cpp:422",
            "the same unmasked pdf: the specular density it gives wo below the horizon, where "
            "sample() never goes, makes pdf integrate to more than the probability of a "
            "counted sample",
            "pdf(wo below the horizon) = 0.0677 in llvm_ad_rgb (alpha 0.25, wi at 45 deg)",
            "int pdf = P(sample counted), 1 for roughplastic's valid samples",
            "tests/repro/roughplastic_pdf_below_horizon.py", excerpt="return result;",
            rows=(NORM_ROW,)),
    Finding("roughplastic-pdf-nan-grazing", "finite",
            ("roughplastic/beckmann-a0.1", "roughplastic/beckmann-a0.25",
             "roughplastic/ggx-a0.25", "roughplastic/ggx-a0.5-nonlinear"),
            "src/bsdfs/roughplastic.cpp:422",
            "the same unmasked `return result;`: at exactly grazing incidence cos_theta_i = 0 "
            "(a measure-zero input: a ray meeting the surface exactly edge-on) the specular "
            "term divides by 4 cos_theta_i (line 414) and the NaN is returned whenever another "
            "lane is active (eval_pdf() likewise, line 501)",
            "pdf = NaN for wi = (1, 0, 0) in a call with other, valid lanes",
            "pdf = 0 for an inactive lane",
            "tests/repro/roughplastic_pdf_below_horizon.py",
            excerpt="return result;",
            rows=NAN_ROWS, region=GrazingIncidence()),
    Finding("roughplastic-pdf-nan-specular0", "finite", _ROUGHPLASTIC,
            "src/bsdfs/roughplastic.cpp:422",
            "the same unmasked `return result;`: with specular_reflectance 0 the sampling "
            "weight is 0, and on a masked-off lane (cos_theta_o <= 0) lerp_gather returns "
            "t_i = 0 (lines 396-397), so prob_specular / (prob_specular + prob_diffuse) "
            "(line 406) is 0/0 and pdf() (eval_pdf() likewise, line 501) returns NaN for wo "
            "below the horizon, at any int_ior",
            "pdf = nan for wo below the horizon (0.2546 above; wi at 45 deg, alpha 0.5)",
            "pdf = 0 below the horizon",
            "tests/repro/roughplastic_pdf_nan_specular0.py", excerpt="return result;",
            rows=NAN_ROWS,
            region=MaskedReflection(), at=(("specular_reflectance", 0.0),)),
    Finding("roughplastic-black-nan-pdf", "finite", _ROUGHPLASTIC,
            "src/bsdfs/roughplastic.cpp:229",
            "`m_specular_sampling_weight = s_mean / (d_mean + s_mean)` is 0/0 = NaN when both "
            "reflectances are 0, so prob_specular and prob_diffuse (lines 400-401, 446-447) and "
            "with them pdf() and eval_pdf() are NaN for every direction; Mitsuba's path tracer "
            "is unaffected (its MIS weight drops non-finite values, path.cpp:363), an "
            "integrator that uses the pdf directly is not",
            "pdf = nan at 40 deg (eval = 0)",
            "a finite pdf (e.g. the diffuse lobe's, or 0)",
            "tests/repro/roughplastic_black_nan.py",
            excerpt="m_specular_sampling_weight = s_mean / (d_mean + s_mean);",
            rows=NAN_ROWS, at=BLACK_PLASTIC),
    Finding("plastic-black-nan-pdf", "finite", _PLASTIC, "src/bsdfs/plastic.cpp:206",
            "`m_specular_sampling_weight = s_mean / (d_mean + s_mean)` is 0/0 = NaN when both "
            "reflectances are 0 (roughplastic.cpp:229's line), so prob_specular (lines 229, "
            "235, 315, 353) and with it pdf(), eval_pdf() and the sample() weight are NaN "
            "above the horizon; Mitsuba's path tracer is unaffected (path.cpp:363 drops a "
            "non-finite MIS weight, a NaN throughput fails its != 0 test)",
            "pdf = nan, sample weight = nan at 40 deg (eval = 0)",
            "a finite pdf and weight (e.g. the diffuse lobe's, or 0)",
            "tests/repro/plastic_black_nan.py",
            excerpt="m_specular_sampling_weight = s_mean / (d_mean + s_mean);",
            rows=NAN_ROWS + (SAMPLE_ROW,),
            at=BLACK_PLASTIC),
    Finding("pplastic-black-nan-pdf", "finite", _PPLASTIC, "src/bsdfs/pplastic.cpp:239",
            "`m_specular_sampling_weight = s_mean / (d_mean + s_mean)` is 0/0 = NaN when both "
            "reflectances are 0 (roughplastic.cpp:229's line), so prob_specular and "
            "prob_diffuse (lines 454-455) and with them pdf() (line 476) and eval_pdf() are NaN "
            "above the horizon; sample() compares sample1 < NaN (line 265), false, so it draws "
            "the diffuse lobe, and returns bs.pdf = pdf(bs.wo) = NaN (line 288) with the weight "
            "masked to 0 by `active &= bs.pdf > 0.f` (lines 289, 292): a rejected sample that "
            "carries a NaN pdf",
            "pdf = nan at 40 deg (eval = 0); sample(): bs.pdf = nan, weight = 0",
            "a finite pdf (e.g. the diffuse lobe's, or 0)",
            "tests/repro/pplastic_black_nan.py",
            excerpt="m_specular_sampling_weight = s_mean / (d_mean + s_mean);",
            rows=NAN_ROWS, at=BLACK_PLASTIC),
    Finding("plastic-fdr-fit-energy", "energy", _PLASTIC,
            "include/mitsuba/render/fresnel.h:341",
            "plastic's diffuse term divides by 1 − F_dr(1/η) (plastic.cpp:196, 290-294), and "
            "fresnel_diffuse_reflectance() takes F_dr for η < 1 from Egan and Hilgeman's fit "
            "(lines 341-343; its comment: 9.5 % maximum error for IOR 2-5): at int_ior 3 the "
            "fit is 0.9355 for an exact 0.9196, so the diffuse albedo is 25 % high and the "
            "directional albedo of a white plastic exceeds 1 (4 % high at 2.5, < 0.15 % "
            "below 2)",
            "albedo 1.185 at normal incidence (int_ior 3, both reflectances 1)",
            "albedo <= 1: eta^2 (1 - F_dr(1/eta)) = 1 - F_dr(eta) for the exact F_dr",
            "tests/repro/plastic_fdr_fit_energy.py", excerpt="Float approx_1 =",
            rows=(ENERGY_ROW,),
            at=(("int_ior", (2.0, 3.0)),)),
    Finding("roughplastic-gradient-detached", "gradient",
            ("roughplastic/beckmann-a0.1", "roughplastic/beckmann-a0.25",
             "roughplastic/ggx-a0.25", "roughplastic/ggx-a0.5-nonlinear"),
            "src/bsdfs/roughplastic.cpp:235",
            "parameters_changed() builds the rough transmittance table and internal reflectance "
            "(lines 232-251) from `dr::slice(m_eta)` and `dr::slice(m_alpha)`, plain scalars, so "
            "AD misses the derivative of the diffuse term through them although both "
            "parameters are exposed as Differentiable (lines 210-211)",
            "d eval/d alpha: AD 0.0633 vs central difference -0.0250; d/d eta: AD -0.108 vs "
            "0.0265 (alpha 0.25, one lane off the specular peak)",
            "AD equal to the central difference within its error",
            "tests/repro/roughplastic_gradient_detached.py",
            excerpt="ScalarFloat eta = dr::slice(m_eta), alpha = dr::slice(m_alpha);",
            rows=("alpha", "eta")),
    Finding("principledthin-pdf-nan-grazing", "finite",
            ("principledthin/default", "principledthin/all-lobes"),
            "src/bsdfs/principledthin.cpp:704",
            "pdf() sets `active &= cos_theta_i != 0` (line 606) but returns `pdf` unmasked, so a "
            "lane at exactly grazing incidence (cos_theta_i = 0, a measure-zero input) gets "
            "the NaN of the microfacet densities (they divide by cos_theta_i) whenever another "
            "lane is active -- roughplastic's pattern",
            "pdf = NaN for wi = (1, 0, 0) next to a valid lane",
            "pdf = 0 for an inactive lane",
            "tests/repro/principledthin_pdf_nan_grazing.py",
            excerpt="return pdf;",
            rows=NAN_ROWS, region=GrazingIncidence(), at=SPEC_TRANS_ON),
    Finding("principledthin-pdf-grazing-normalization", "normalization",
            ("principledthin/default", "principledthin/all-lobes"),
            "src/bsdfs/principledthin.cpp:704",
            "the same unmasked `pdf`: at exactly grazing incidence (cos_theta_i = 0, a "
            "measure-zero input) sample() returns no sample while pdf() still returns a "
            "density, so pdf integrates to more than the (zero) share of counted samples",
            "pdf = NaN for wi = (1, 0, 0) next to a valid lane",
            "pdf = 0 for an inactive lane",
            "tests/repro/principledthin_pdf_nan_grazing.py", excerpt="return pdf;",
            rows=(NORM_ROW,),
            region=GrazingIncidence()),
    Finding("hair-residual-lobe-sampling", "chi2", ("hair/default", "hair/blond-rough"),
            "src/bsdfs/hair.cpp:267",
            "the loop `for (j = 0; j < P_MAX; j++)` never sets the incident angle of the "
            "residual lobe p = P_MAX, so its samples keep sin/cos_theta_ip = 0 (line 265) and "
            "land exactly in the fiber's normal plane (line 287: sin_theta_o = 0), unlike "
            "pdf()/eval() (lines 437, 389)",
            "3.49 % of samples have wo.y == 0 exactly (blond, 85 deg)",
            "P(wo.y == 0) ~ 1e-7 for a continuous density; sampling consistent with pdf",
            "tests/repro/hair_residual_lobe_sampling.py",
            excerpt="for (size_t j = 0; j < P_MAX; j++)",
            rows=(CHI2_ROW,), region=Chi2Excess("normal_plane")),
    Finding("hair-fiber-pdf-i0-normalization", "normalization",
            ("hair/default", "hair/blond-rough"),
            "include/mitsuba/core/warp.h:752",
            "detail::i0() sums only 11 terms of the power series of I0 (lines 749-758), which "
            "log_i0() uses up to x = 12 (line 763): short by 0.06 % at x = 10, 0.21 % at 11, "
            "0.57 % at 12, so square_to_rough_fiber_pdf() -- hair's longitudinal density M_p -- "
            "is too small wherever kappa cos(theta_i) cos(theta_o) lies just below 12, while "
            "hair.cpp's sample() inverts the exact M_p (lines 275-283); pdf integrates to less "
            "than the share of counted samples",
            "kappa = 11.8: pdf relative to the exact density -6.9e-4 at kappa cos = 10, -2.1e-3 "
            "at 11, -4.4e-3 at 11.7",
            "the exact density (I0 to float32 precision, e.g. its exponentially scaled form)",
            "tests/repro/hair_fiber_pdf_i0.py", excerpt="for (int i = 1; i <= 10; ++i)",
            rows=(NORM_ROW,)),
    Finding("hair-fiber-pdf-i0-chi2", "chi2", ("hair/default", "hair/blond-rough"),
            "include/mitsuba/core/warp.h:752",
            "the same truncated I0 series: the density pdf() reports for the longitudinal lobes "
            "is not the one sample() draws (up to 0.57 % smaller near kappa cos(theta_i) "
            "cos(theta_o) = 12), a shape error a million samples resolve at cells where the "
            "residual-lobe collapse is small (0.02 % of the samples in wo.y = 0 at 60 deg, "
            "phi_i = 1)",
            "kappa = 11.8: pdf relative to the exact density -6.9e-4 at kappa cos = 10, -2.1e-3 "
            "at 11, -4.4e-3 at 11.7",
            "sampling consistent with pdf",
            "tests/repro/hair_fiber_pdf_i0.py", excerpt="for (int i = 1; i <= 10; ++i)",
            rows=(CHI2_ROW,)),
    Finding("beckmann-pdf-normalization", "normalization",
            ("roughconductor/beckmann-a0.2", "roughconductor/polarized",
             "roughdielectric/beckmann-a0.1", "blendbsdf/roughconductor+roughdielectric",
             "pplastic/default", "roughdielectric/polarized"),
            "include/mitsuba/render/microfacet.h:350",
            "Beckmann's smith_g1() is a rational approximation (\"< 0.35 % rel. error\", lines "
            "348-352) while sample_visible() inverts the exact visible-normal distribution, so "
            "the visible-normal pdf D G1 |wi.m| / cos theta_i (line 223) integrates to "
            "G1_approx / G1_exact instead of 1",
            "int pdf dm = 0.99724 at cos theta_i = 1e-4, 1.00283 at 0.05, 1.00036 at 0.5 "
            "(alpha 0.3; GGX 1.00000 at each)",
            "int pdf = 1 with every sample valid (the exact G1, as for GGX at line 354)",
            "tests/repro/beckmann_pdf_normalization.py",
            excerpt="result = dr::select(a >= 1.6f, 1.f,",
            rows=(NORM_ROW,),
            given=(("distribution", "beckmann"),)),
    Finding("roughdielectric-index-matched-energy", "energy",
            ("roughdielectric/beckmann-a0.1", "roughdielectric/ggx-a0.3",
             "roughdielectric/ggx-aniso-inverted", "roughdielectric/polarized"),
            "src/bsdfs/roughdielectric.cpp:381",
            "near index matching (the plugin refuses only int_ior == ext_ior, line 178; "
            "int_ior 1 against the default ext_ior, air 1.000277, is eta 0.99972) the "
            "transmission lobe narrows to about alpha |eta - 1| and Fresnel reflection "
            "vanishes, so the albedo tends to G1(wi)^2 / G1_exact(wi) with no loss left to "
            "absorb an error, and two errors lift it above 1: the float32 product wo * eta in "
            "the half vector normalize(wi + wo * eta) (line 381) -- for wo near -wi the sum "
            "cancels exactly and leaves the product's rounding divided by |eta - 1|, nearly "
            "the same across the lobe (the roughdielectric-index-matched-normalization "
            "cause; eval up to 1.6 % off pointwise on the lobe of GGX alpha 0.01 at eta "
            "0.99972) -- and Beckmann's smith_g1() is a rational approximation, 1 for "
            "a >= 1.6 (include/mitsuba/render/microfacet.h:348-352), above the exact Smith G1 "
            "there.  The float64 model with only wo * eta rounded to float32 gives Mitsuba's "
            "albedo, so the float32 denominator (wi.m + eta wo.m)^2 (line 425) adds nothing "
            "measurable.  In the sweep the energy row (default sizes, seed 0) fails for Beckmann "
            "at eta 0.998-1.015 (alpha 1), 0.999-1.005 (0.5), 0.999-1.003 (0.3), 0.9995-1.001 "
            "(0.1), at scattered points for alpha 0.01-0.05, for GGX alpha 0.01 at 0.9992-1.0007 "
            "(0.99972, 60 deg: 1.000763, band 1.7e-4) and alpha 0.05 at 0.9997-1.0002 (0.99972, "
            "45.6 deg: 1.000268; the fine integral 1.000264); every alpha passes at 0.995 and "
            "1.02, GGX alpha >= 0.1 everywhere.  The topic reads such a lobe (1e-6 rad wide) as "
            "the mean of rules on shifted nodes (lobes.integrate_rounded) and agrees with the fine "
            "integral within its band",
            "albedo of eval by a fine polar quadrature (reproducer), against Walter et al.'s model "
            "in float64: Beckmann alpha 1, eta 1.001, 31.8 deg 1.001615 (model 0.998240 with the "
            "exact G1, 1.001616 with the approximate one); Beckmann alpha 0.1, eta 0.99972, 31.8 "
            "deg 1.000561 (model 0.999998); GGX alpha 0.01, eta 0.99972, 60 deg 1.000757 (model "
            "0.999919); the float64 model with only wo * eta rounded to float32: 1.000560 "
            "(Beckmann alpha 0.1), 1.000752 (GGX alpha 0.01)",
            "albedo <= 1 (the float64 model with the exact G1 stays below 1)",
            "tests/repro/roughdielectric_index_matched_energy.py",
            excerpt="dr::normalize(si.wi + wo * dr::select(reflect, Float(1.f), eta))",
            rows=(ENERGY_ROW,),
            at=(("eta", (0.998, 1.015)),)),
    Finding("roughdielectric-index-matched-normalization", "normalization",
            ("roughdielectric/beckmann-a0.1", "roughdielectric/ggx-a0.3",
             "roughdielectric/ggx-aniso-inverted", "roughdielectric/polarized"),
            "src/bsdfs/roughdielectric.cpp:458",
            "pdf() forms the transmission half vector as normalize(wi + wo * eta) (line 458; "
            "eval() alike at line 381): near index matching (int_ior 1 against the default "
            "ext_ior, air 1.000277, is eta 0.99972; the plugin refuses only int_ior == "
            "ext_ior, line 178) wo ~ -wi, so the sum cancels -- exactly, in float32 -- and "
            "leaves the float32 rounding of the product wo * eta (up to 2^-25 per component) "
            "divided by |wi + eta wo| ~ |eta - 1|: m is off by ~2e-4 rad at eta 0.99972, by "
            "nearly the same amount across the whole lobe (alpha |eta - 1| wide), since the "
            "product's rounding error drifts by only |eta - 1| of a float32 spacing per "
            "spacing of wo; pdf then integrates to 1 +- up to ~1e-3 while every sample is "
            "valid.  The row (--quick) reads 1.0004 against 0.99998 (GGX alpha 0.1, 45.6 deg) "
            "and 0.9996 against 0.99999 (alpha 0.01, 72.5 deg).  The product's effect on int pdf "
            "(GGX, the largest over cos theta_i 0.05 to 0.95): alpha 0.01 6.5e-4 to 4.8e-3 at eta "
            "0.999 to 1.001, 6e-5 and 7e-5 at 0.998 and 1.002, <= 4e-6 from 0.995 and 1.005 out; "
            "alpha 0.1 4.6e-4 at 0.99972, 1e-4 at 0.9995 and 1.0005, 2e-6 at 0.999 and 1.001; at "
            "cos theta_i 0.05 up to 2.3e-4 (alpha 0.01, eta 0.99972), at <= 0.01 (alpha 0.01, 0.1) "
            "<= 3e-5, below every band (the signature: |cos theta_i| >= 0.03); at normal incidence "
            "it is not 0 for a wide lobe (GGX alpha 1, eta 1.0003: the --quick row of the topic "
            "alone there reads 0.99979 against 0.99992, band 1.3e-4)",
            "int pdf by stratified polar grids about the lobes (reproducer, s.e. 1e-5 to 3e-5) at "
            "eta 0.99972, phonglab's cells: GGX alpha 0.1, 45.6 deg: Mitsuba 1.000468 (phi 0), "
            "1.000404 (phi 2.1), the float64 pdf 1.000011, 0.999981, the float64 pdf with only wo "
            "* eta rounded to float32 1.000469, 1.000406; GGX alpha 0.01, 72.5 deg, phi 2.1: "
            "0.999536, 0.999964, 0.999535; 60 deg: 1.000822, 0.999985, 1.000822; samples counted "
            "0.999987 to 0.999999; Beckmann alpha 0.1, 45.6 deg (the same product): 1.000617, "
            "1.000050, 1.000618; GGX alpha 1, eta 1.0003, normal incidence: 0.999795, 0.999896, "
            "0.999794, samples counted 0.999887",
            "int pdf = the share of counted samples, 1: the float64 pdf gives 1.000011, "
            "0.999981, 0.999964, 0.999985 at those cells, and so does the sum wi + wo * eta "
            "rounded once to float32 (a fused multiply-add, the fix): the same to 1e-6",
            "tests/repro/roughdielectric_index_matched_normalization.py",
            excerpt="dr::normalize(si.wi + wo * dr::select(reflect, Float(1.f), eta))",
            rows=(NORM_ROW,),
            region=IncidenceFrom(0.03), at=(("eta", (0.999, 1.001)),)),
    Finding("mask-diffuse-reflectance-opacity", "eval_diffuse_reflectance",
            ("mask/diffuse-0.5",),
            "src/bsdfs/mask.cpp:231",
            "eval_diffuse_reflectance() returns the nested BSDF's value (lines 229-231) without "
            "the opacity that eval() applies, so it reports the nested albedo, not the masked "
            "one",
            "eval_diffuse_reflectance = 0.5000; pi * eval(wi, n) = 0.2500 (opacity 0.5)",
            "the masked albedo 0.25 (opacity x the nested diffuse albedo)",
            "tests/repro/mask_diffuse_reflectance_opacity.py",
            excerpt="return m_nested_bsdf->eval_diffuse_reflectance(si, active);",
            rows=("eval_diffuse_reflectance = diffuse albedo",)),
    Finding("principled-diffuse-retro-energy", "energy",
            ("principled/default", "principledthin/default"),
            "src/bsdfs/principled.cpp:655",
            "by design: Burley's diffuse term f_diff + f_retro (line 655; principledthin.cpp:539) "
            "raises the grazing response of a rough surface (Burley 2012, sec. 5.3: 'up to 2.5' "
            "for rough surfaces), so a white base_color's diffuse lobe alone reflects more "
            "than it receives, and principled adds its specular lobe on top of it without "
            "(1 - F) (lines 677-679)",
            "base_color 1: albedo 1.0194 at 72.54 deg (principledthin, its diffuse lobe), "
            "1.1907 at 87.13 deg (principled, its specular lobe added)",
            "albedo <= 1 for a passive surface",
            "tests/repro/principled_energy_by_design.py", bug=False,
            excerpt="Float f_retro = Rr * (Fo + Fi + Fo * Fi * (Rr - 1.0f));",
            rows=(ENERGY_ROW,),
            at=(("base_color", 1.0),)),
    Finding("principled-specular-uncoupled-energy", "energy", ("principled/default",),
            "src/bsdfs/principled.cpp:678",
            "by design: the diffuse lobe is weighted by brdf = (1 - metallic)(1 - spec_trans) "
            "(lines 515, 677-679), not by the (1 - F) the specular lobe (line 599-600) leaves, "
            "so at grazing incidence, where the smooth specular lobe reflects most of the "
            "light, the sum exceeds 1",
            "roughness 0.1 (base_color 0.5): albedo 1.0628 at 89.99 deg",
            "albedo <= 1 for a passive surface",
            "tests/repro/principled_energy_by_design.py", bug=False,
            excerpt="brdf * dr::abs(cos_theta_o) * base_color *",
            rows=(ENERGY_ROW,),
            at=(("roughness", 0.1),)),
    Finding("principled-clearcoat-missing-denominator", "energy", ("principled/metal",),
            "src/bsdfs/principled.cpp:639",
            "the clearcoat term is `(clearcoat * 0.25) * Fcc * Dcc * G_cc * |cos_theta_o|` "
            "without the microfacet 1 / (4 cos_theta_i cos_theta_o) of the specular lobe "
            "(line 600; Burley's reference code folds it into its smithG_GGX, Mitsuba's "
            "smith_ggx1 in clearcoat_G, principledhelpers.h:79, is the plain G1), so near "
            "normal incidence the clearcoat reflects about 4x its microfacet value and a "
            "white metal under a full clearcoat exceeds 1",
            "metallic 1, base_color 1, roughness 0.2, clearcoat_gloss 1: albedo at normal "
            "incidence 1.0332 with clearcoat 1, 0.9983 without: the clearcoat adds 0.0349, more "
            "than 0.25 x F0 = 0.01, the bound for any microfacet lobe with G <= 1",
            "a clearcoat adding at most 0.25 x 0.04 = 0.01 at normal incidence",
            "tests/repro/principled_clearcoat_energy.py",
            excerpt="(clearcoat * 0.25f) * Fcc * Dcc * G_cc * dr::abs(cos_theta_o)",
            rows=(ENERGY_ROW,),
            at=(("clearcoat", 1.0), ("metallic", 1.0), ("base_color", 1.0))),
    Finding("principled-metal-diffuse-reflectance", "eval_diffuse_reflectance",
            ("principled/metal",),
            "src/bsdfs/principled.cpp:841",
            "eval_diffuse_reflectance() returns base_color without the diffuse weight "
            "brdf = (1 - metallic)(1 - spec_trans) that eval() applies (lines 515, 568), so a "
            "metal, which has no diffuse lobe, reports base_color; the row is measurable at "
            "specular 0 because there the whole metal is black: eta = 1 (line 230) makes "
            "F_spec_dielectric 0 and the specular mask `F_spec_dielectric > 0` (line 555) "
            "switches off the metallic lobe too",
            "metallic 1, specular 0: eval_diffuse_reflectance = 0.5, eval = 0 for every "
            "direction (diffuse albedo 0)",
            "the diffuse albedo (0 for a metal)",
            "tests/repro/principled_metal_diffuse_reflectance.py",
            excerpt="return m_base_color->eval(si, active);",
            rows=("eval_diffuse_reflectance = diffuse albedo",),
            at=(("metallic", 1.0), ("specular", 0.0))),
    Finding("microfacet-sample-nan", "finite", _MICROFACET_NAN,
            "include/mitsuba/render/microfacet.h:418",
            "GGX visible-normal sampling divides by 0 on a measure-zero set of sample values: "
            "`norm = rcp(sin_theta_i * y + cos_theta_i * z)` is 1/0 for sample2 = (0, 0.5) "
            "(the concentric disk maps it to (-1, 0), so y = z = 0) and, at normal incidence, "
            "for every sample2 on an edge of [0, 1]^2 (mapped onto the circle, z = 0); Beckmann "
            "visible sampling (line 375) returns an infinite normal for wi below the horizon; "
            "roughconductor.cpp:250 and the other callers keep the NaN wo and bs.pdf (only the "
            "weight is masked to 0)",
            "wo = NaN and bs.pdf = NaN (weight 0) for sample2 = (0, 0.5) at 40 deg, and for wi "
            "below the horizon (Beckmann)",
            "finite wo and pdf for every sample in [0, 1)^2 (an invalid sample: weight 0, "
            "pdf 0)",
            "tests/repro/microfacet_sample_nan.py",
            excerpt="Float norm = dr::rcp(dr::fmadd(sin_theta_i, y, cos_theta_i * z));",
            rows=(SAMPLE_ROW,),
            region=Union((SamplePoint((0.0, 0.5)), SampleEdgeAtNormalIncidence(),
                          BelowHorizon()))),
    Finding("blendbsdf-stale-child-pdf", "pdf",
            ("blendbsdf/roughconductor+roughdielectric",), "src/bsdfs/blendbsdf.cpp:138",
            "sample() mixes bsdf_0's bs0.pdf into pdf_weighted (line 138; result0 * bs0.pdf into "
            "the weight, line 139) without asking whether bsdf_0's sample is valid: "
            "roughconductor sampled from below its surface returns a zero weight but a non-zero "
            "bs.pdf on some lanes, which the blend keeps",
            "249 of 17007 samples from below (wi.z = -0.7): bs.pdf differs from pdf(bs.wo) by "
            "more than 1 % (e.g. 2.26e-05 against 2.716e-09)",
            "bs.pdf = pdf(bs.wo) and weight = eval/pdf for every sample",
            "tests/repro/blendbsdf_stale_child_pdf.py",
            excerpt="auto pdf_weighted = weight * pdf1 + (1.f - weight) * bs0.pdf;",
            rows=("bs.pdf = pdf(bs.wo)",), region=BelowHorizon()),
    Finding("blendbsdf-stale-child-pdf-weight", "weight",
            ("blendbsdf/roughconductor+roughdielectric",), "src/bsdfs/blendbsdf.cpp:138",
            "sample() mixes bsdf_0's bs0.pdf into pdf_weighted (line 138; result0 * bs0.pdf into "
            "the weight, line 139) without asking whether bsdf_0's sample is valid: "
            "roughconductor sampled from below its surface returns a zero weight but a non-zero "
            "bs.pdf on some lanes, which the blend keeps",
            "249 of 17007 samples from below (wi.z = -0.7): bs.pdf differs from pdf(bs.wo) by "
            "more than 1 % (e.g. 2.26e-05 against 2.716e-09)",
            "bs.pdf = pdf(bs.wo) and weight = eval/pdf for every sample",
            "tests/repro/blendbsdf_stale_child_pdf.py",
            excerpt="auto pdf_weighted = weight * pdf1 + (1.f - weight) * bs0.pdf;",
            rows=("weight = eval/pdf per sample",), region=BelowHorizon()),
    Finding("blendbsdf-nan-weight", "finite",
            ("blendbsdf/diffuse+roughconductor", "blendbsdf/roughconductor+roughdielectric"),
            "src/bsdfs/blendbsdf.cpp:151",
            "sample() forms `weight * result1 * bs1.pdf` (line 151; `result0 * bs0.pdf` at "
            "line 139): the nested microfacet sampler marks an invalid sample with weight 0 but "
            "keeps bs.pdf = NaN, and 0 x NaN = NaN, so the blend's sample weight is NaN; the "
            "NaN pdf comes from measure-zero inputs only: exactly grazing wi (cos theta_i = 0) "
            "in a call with other active lanes, where the visible-normal pdf divides by "
            "cos_theta(wi) (microfacet.h:223), and the sample values of microfacet.h:418 "
            "(sample2 = (0, 0.5); an edge of [0, 1]^2 at normal incidence)",
            "weight = NaN for wi = (1, 0, 0) next to a valid lane (sample1 = 0.1), for "
            "sample2 = (0, 0.5) at 40 deg and for sample2 = (0, 0) at normal incidence",
            "weight 0 for an invalid sample",
            "tests/repro/microfacet_sample_nan.py",
            excerpt="weight * result1 * bs1.pdf",
            rows=(SAMPLE_ROW,),
            region=Union((GrazingIncidence(), SamplePoint((0.0, 0.5)),
                          SampleEdgeAtNormalIncidence(), BelowHorizon()))),
    Finding("conductor-eta0-gradient", "gradient",
            ("roughconductor/beckmann-a0.2", "roughconductor/beckmann-novisible",
             "blendbsdf/diffuse+roughconductor", "blendbsdf/roughconductor+roughdielectric",
             "twosided/diffuse|roughconductor", "bumpmap/roughconductor",
             "normalmap/roughconductor", "mask/roughconductor-0.8"),
            "include/mitsuba/render/fresnel.h:104",
            "at the default material 'none' (eta = 0, k = 1, roughconductor.cpp:166-167) "
            "`a = safe_sqrt(0.5 (a_2_pb_2 + temp_1))` is the square root of k^2 eta^2 / |t|, "
            "so a = k eta / sqrt(|t|) has a finite slope, but AD differentiates safe_sqrt at 0 "
            "as 0 (and the float32 sum a_2_pb_2 + temp_1 cancels, making differences noisy)",
            "d eval/d eta by AD: 0 at eta = 0, -1.955 at eta = 1e-3, -1.970 at 2e-3 (one "
            "lane)",
            "a continuous derivative (about -1.95 at eta = 0)",
            "tests/repro/conductor_eta0_gradient.py",
            excerpt="a = dr::safe_sqrt(.5f * (a_2_pb_2 + temp_1));",
            rows=("eta.value",), region=ParameterAt((0.0,))),
    Finding("principled-gradient-lobe-masks", "gradient",
            ("principled/default", "principled/metal", "principledthin/default"),
            "src/bsdfs/principled.cpp:559",
            "lobes are switched on by strict inequalities on their weights (clearcoat > 0 at "
            "line 559, bsdf > 0 at 563, brdf > 0 at 568, sheen > 0 and 1 - metallic > 0 at "
            "571-572; principledthin.cpp:458-467 spec_trans > 0, diff_trans > 0), so at a "
            "range end (0, the default of clearcoat/sheen/spec_trans, or metallic = 1) AD "
            "returns the derivative of the model without that lobe, i.e. the derivative from "
            "outside [0, 1]",
            "d/d clearcoat at 0: AD 0 vs right-hand difference 0.61417; d/d metallic at 1: AD "
            "20.539 vs left-hand difference 1.4191 (256 lanes)",
            "the one-sided derivative from inside [0, 1]",
            "tests/repro/principled_gradient_lobe_masks.py",
            excerpt="(clearcoat > 0.0f) && reflect &&",
            rows=("clearcoat.value", "sheen.value", "spec_trans.value", "metallic.value",
                  "diff_trans.value"), region=ParameterAt((0.0, 1.0))),
    Finding("principledthin-transmission-reciprocity", "reciprocity",
            ("principledthin/default", "principledthin/all-lobes"),
            "src/bsdfs/principledthin.cpp:463",
            "the specular-transmission mask `mac_mic_compatibility(wh, wi, wo_t, wi.z(), false)` "
            "tests the unmirrored wo_t against the half vector built from the mirrored wo_r "
            "(lines 451-454), so whether the lobe is on depends on which of the two directions "
            "is wi; the lobe value (lines 523-525) is symmetric",
            "f(a, b) = 0 vs f(b, a) = 10.67 for a = (-0.49, 0.85, 0.2), b = (0.49, -0.87, "
            "-0.0216) (roughness 0.4, spec_trans 0.3); f(c, d) = 0.004108 vs f(d, c) = 0 for "
            "c = (-0.404, 0.691, 0.6), d = (0.275, 0.505, -0.818) (defaults, spec_trans 1)",
            "f(a, b) = f(b, a) (a thin sheet transmits with eta = 1)",
            "tests/repro/principledthin_transmission_reciprocity.py",
            excerpt="mac_mic_compatibility(wh, wi, wo_t, wi.z(), false);",
            rows=(TRANSMISSION_ROW,), at=SPEC_TRANS_ON),
    Finding("pplastic-polarized-grazing", "reciprocity", ("pplastic/default", "pplastic/rough-ggx"),
            "src/bsdfs/pplastic.cpp:376",
            "the polarized diffuse term evaluates the second Fresnel transmission from the "
            "internally refracted direction (lines 375-376); for grazing wi that direction is "
            "at the critical angle, where cos = sqrt(1 - eta^2 sin^2) cancels in float32 (the "
            "unpolarized branch, lines 429-432, uses 1 - R(cos_theta_i) directly)",
            "f(a, b) = 0.0011334 vs f(b, a) = 0.0011194 (1.3 %) at cos = 0.0019; the spectral "
            "(unpolarized) variant agrees to 1.5e-8",
            "f(a, b) = f(b, a) to float32 precision",
            "tests/repro/pplastic_polarized_grazing.py",
            excerpt="specular_transmission(dr::abs(Frame3f::cos_theta(wi_hat_p)), inv_eta)",
            rows=(REFLECTION_ROW,), region=PPLASTIC_GRAZING),
    Finding("shading-normal-reciprocity", "reciprocity",
            ("normalmap/diffuse", "normalmap/roughconductor", "bumpmap/diffuse",
             "bumpmap/roughconductor"),
            "src/bsdfs/normalmap.cpp:171",
            "by design: eval() is the nested BSDF in the perturbed frame, f(wi', wo') cos theta'_o, "
            "zeroed where wo and wo' lie on different sides (lines 168-169; bumpmap.cpp:174-177 "
            "alike, in the frame it builds from the height gradient and si.dp_du, si.dp_dv); "
            "shading normals are not reciprocal w.r.t. the geometric normal "
            "(Veach 1997, sec. 5.3)",
            "eval(a, b) / cos b != eval(b, a) / cos a: 0.1366 vs 0.1830 (normalmap, tilted "
            "normal), 0.1450 vs 0.0277 (bumpmap, height h = u)",
            "f(a, b) = f(b, a) for a reciprocal BRDF",
            "tests/repro/shading_normal_reciprocity.py", bug=False,
            excerpt="m_nested_bsdf->eval(ctx, perturbed_si, perturbed_wo, active);",
            rows=(REFLECTION_ROW,)),
    Finding("hair-reciprocity", "reciprocity", ("hair/default", "hair/blond-rough"),
            "src/bsdfs/hair.cpp:349",
            "by design: eval() takes the fiber offset h = sin(gamma_i) from wi alone "
            "(near-field model at the offset where the ray hit), so swapping wi and wo changes h",
            "f(a, b) = 0.0379 vs f(b, a) = 0.0343 for one pair of directions",
            "f(a, b) = f(b, a) for a reciprocal BSDF",
            "tests/repro/hair_reciprocity.py", bug=False,
            excerpt="Float h = dr::sin(gamma_i);",
            rows=(REFLECTION_ROW, TRANSMISSION_ROW)),
)
