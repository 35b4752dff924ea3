"""Every row of the BSDF conformance table that failed because of the validator itself: the open
ones (to be fixed in the validator) and, with ``fixed_by``, the validator's own mistakes found and
fixed (:class:`~phonglab.validate.conformance.ValidatorIssue`; the Mitsuba findings are
:mod:`.findings`)."""

from __future__ import annotations

from ..conformance import ValidatorIssue


_D815814 = ("commit d815814 (validate: fixes for the validator-side fails found by the "
            "conformance run)")

#: Every row of a conformance run that failed because of the validator: the open ones (to be
#: fixed there) and, with ``fixed_by``, the validator's own mistakes found and fixed.
VALIDATOR_ISSUES: tuple[ValidatorIssue, ...] = (
    ValidatorIssue(
        "grazing-half-vector-conditioning", "weight",
        ("roughconductor/beckmann-novisible", "roughdielectric/beckmann-a0.1",
         "roughdielectric/ggx-aniso-inverted"),
        "at cos theta_i = 1e-4 with a near-retro-reflected wo, pdf(wo) recomputes "
        "m = normalize(wi + wo) from a float32 wo whose x component is about -1: moving wo.x by "
        "ONE float32 ulp changes pdf from 1488.7 to 1078.1 or 2404.7 (-28 %/+62 %; beckmann, "
        "alpha 0.4, no visible sampling), so bs.pdf (from the exact sampled m) and pdf(bs.wo) "
        "differ by rounding alone.  config.perturb() moved every component by 8 u and then "
        "renormalized, which undid the move of a component near +-1, so the sensitivity "
        "missed exactly this rounding and the per-sample tolerance was too tight (weight and "
        "pdf rows alike)",
        fixed_by=_D815814 + ": config.perturb no longer renormalizes, and rel_diff has a "
        "floor at the quantity's own scale"),
    ValidatorIssue(
        "grazing-half-vector-conditioning-pdf", "pdf",
        ("roughconductor/beckmann-novisible", "roughdielectric/beckmann-a0.1",
         "roughdielectric/ggx-aniso-inverted"),
        "the same rounding as the weight row: bs.pdf vs pdf(bs.wo) at cos theta_i = 1e-4.  "
        "With the validator's later perturbation (no renormalization) one lane still failed: "
        "wi = (-0.50485, 0.86321, 1e-4), wo = (0.50489, -0.86318, 8.6e-6) is a grazing "
        "retro-reflection, |wi + wo| = 1.2e-4.  The side tests wi.m > 0 and wo.m > 0 "
        "(src/bsdfs/roughconductor.cpp:406-407, m = normalize(wi + wo)) both hold only where "
        "|wo|^2 - |wi|^2 lies within |wi + wo|^2 = 1.5e-8 < u of 0, and the float32 wo has "
        "|wo|^2 - 1 = -2.75e-8: wo.m = -5.9e-5 and pdf(bs.wo) = 0 against bs.pdf = 2348.7 from "
        "the exact sampled m.  Neither value is wrong for its input; no random 8u corner hits "
        "that window, so the sensitivity draws missed the flip",
        fixed_by="commit 'validate: a lane that fails gets its sensitivity over every float32 wo "
        "within 8 ulps' (config.refine, config.box_sensitivity): 36 of the 729 directions within "
        "4 ulps of this wo give pdf 1220.5-3212.0 and the rest 0, so the lane's sensitivity is 1 "
        "and it passes; the weight and pdf rows use it"),
    ValidatorIssue(
        "bumpmap-without-surface-derivatives", "chi2",
        ("bumpmap/diffuse", "bumpmap/roughconductor"),
        "phonglab.probe.interaction() leaves si.dp_du = si.dp_dv = 0, which a real shape sets; "
        "bumpmap builds its perturbed frame from them (src/bsdfs/bumpmap.cpp:229-234: "
        "n = normalize(cross(dp_du', dp_dv')) with dp_du' = dp_du + n (grad_u - n.dp_du)), "
        "i.e. from two parallel vectors: the frame is NaN, every sample is invalid (wo = NaN, "
        "weight 0) and the chi2, weight and pdf rows are skipped as 'sampled nothing' -- the "
        "case is not really validated.  With si.dp_du = (1, 0, 0) and si.dp_dv = (0, 1, 0) "
        "both bumpmap cases sample finite directions with non-zero weights; the fix belongs "
        "in probe.interaction", statuses=("skipped",),
        fixed_by="commit f654325 (probe.interaction: dp_du = +x, dp_dv = +y, a unit square's "
        "parametrization, so bumpmap builds a finite frame): the weight, pdf and chi2 rows of "
        "both bumpmap cases run"),
    ValidatorIssue(
        "tail-conditioning-reciprocity", "reciprocity",
        ("roughdielectric/beckmann-a0.1", "roughdielectric/ggx-a0.3",
         "blendbsdf/roughconductor+roughdielectric"),
        "the failing transmission pairs lie far in the microfacet tail (f = 0.0029 for "
        "Beckmann alpha 0.1, 3.2e-6 for GGX alpha 0.3), where D changes by percent for a "
        "1e-6 rad move of the half vector: moving both directions by 1e-6, 1e-5, 1e-4 and "
        "1e-3 rad turns the relative asymmetry 0.023 into 0.0045, -0.0012, -0.0034 and "
        "0.0107 (beckmann) -- rounding noise of both signs, not a systematic non-reciprocity; "
        "the 4-draw sensitivity estimate (measured 1.13 and 2.07 against 1) under-samples it",
        fixed_by=_D815814 + ": perturbation without renormalization, so the 8u moves of "
        "both directions reach the tail's sensitivity"),
    ValidatorIssue(
        "normalmap-data-discontinuous-fd", "gradient", ("normalmap/diffuse",),
        "eval is discontinuous in the normal-map data: the nested diffuse BSDF is cut at "
        "cos theta'_i = 0 (and the normal flipped where dot(wi, n) <= 0, normalmap.cpp:225), "
        "and that perturbed horizon moves with the normal.  The central difference over lanes "
        "that straddle it does not converge (D(h) = -260, D(h/2) = -250) and doubles when "
        "flip_invalid_normals is off (-536, -512) while AD moves from -309 to -293: the "
        "difference measures the jumps (a boundary term), not a wrong derivative",
        fixed_by=_D815814 + ": lanes whose difference holds a jump that moves with the "
        "parameter are left out (counted in the row)"),
    ValidatorIssue(
        "discontinuous-parameter-fd", "gradient", ("roughdielectric/ggx-aniso-inverted",),
        "eta is flagged ParamFlags::Discontinuous (src/bsdfs/roughdielectric.cpp:223): with "
        "eta < 1 the total-internal-reflection boundary moves with eta, so a central difference "
        "over lanes that straddle it picks up the jump (D(h) = 144.7, D(h/2) = 132.0, not "
        "converging) while AD (9.98) differentiates the continuous part; the topic should skip "
        "Discontinuous parameters or use lanes away from the boundary",
        fixed_by=_D815814 + ": per-lane jump exclusion for ParamFlags.Discontinuous "
        "parameters"),
    ValidatorIssue(
        "spectral-rgb-coefficients-fd", "gradient", ("pplastic/rough-ggx",),
        "in spectral variants an `rgb` texture's diffuse_reflectance.value holds the "
        "sRGB-to-spectrum polynomial coefficients (here (-7.5e-5, 0.082, -22.55)); the step "
        "h = 2^-7 max|x| = 0.18 along (1, 1, 1) adds 0.18 to the lambda^2 coefficient and "
        "saturates the sigmoid, so D(h) = 750, D(h/2) = 1501 (not converging) vs AD 1.75e7: "
        "the difference is not a derivative",
        fixed_by=_D815814 + ": the direction is v_i = |x_i| (each coefficient moves by "
        "2^-8 of itself)"),
    ValidatorIssue(
        "chi2-resolution", "chi2", ("principled/metal",),
        "principled with roughness 0.2 is GGX alpha = 0.04; with --quick sizes (61x122 cells, "
        "2e5 samples) the cell at 78.5 deg is rejected, while mi.chi2 with 201x402 cells, "
        "ires 16 and 1e6 samples accepts the same incidence (p = 0.44, histogram 0.99037 vs "
        "pdf 0.99018): the pdf integration of a sharp lobe on the coarse grid, not sampling",
        fixed_by="commit 0402b28 (chi2: 24x24 pdf integration points per bin), and since #26 "
        "a lobe-adaptive integral per bin (validate/bsdf/sphere_bins.py: Gauss-Legendre "
        "refined until two levels agree to 0.02 of the bin's Poisson error)"),
    ValidatorIssue(
        "energy-quadrature-off-lobe", "energy", ("normalmap/roughconductor",),
        "the validator's albedo at theta_i = 0 is 1.282, but a 1600x800 midpoint rule over "
        "the sphere gives 0.9004 and the mean sample weight of 4e5 samples 0.9001 +- 0.0004: "
        "lobe_quadrature places its panels around the geometric mirror direction, while the "
        "normal map moves the lobe (normal tilted 22 deg), and |Q10 - Q5| does not detect the "
        "misplaced panels",
        fixed_by="commit a41771f (energy: quadrature centred on the lobe's peak, from the "
        "most probable samples, whole circle)"),
    ValidatorIssue(
        "hair-gradient-crash", "finite", ("hair/default", "hair/blond-rough"),
        "the gradient topic raises TypeError in collect_indices() for hair, and run_case turns "
        "the whole case into one failing 'the case loads and runs' row, so no other hair row is "
        "reported (hair samples, evaluates and passes chi2 standalone)",
        fixed_by="commit 7442576 (validate.gradient: unreadable traversed values are skipped: "
        "hair's unused sigma_a) and " + _D815814 + ": a topic that raises is one failing row"),
    ValidatorIssue(
        "diffuse-reflectance-vanishing-lobe", "eval_diffuse_reflectance", ("plastic/default",),
        "found by the --quick sweep at int_ior = 1 (eta = 1/1.000277 < 1): beyond the critical "
        "angle the coating reflects everything, so plastic's diffuse lobe is 0 at cos theta_i "
        "= 1e-4 (its albedo 0 there) while eval_diffuse_reflectance returns the reflectance "
        "0.5; the validator called a lobe that is 0 at one incidence 'Lambertian' there "
        "(eval/cos theta_o constant: 0), though it is not 0 at the other incidences, so it "
        "depends on wi and Mitsuba's documented approximation applies (bsdf.h:566-575)",
        fixed_by="commit 0b7989a (eval_diffuse_reflectance: a lobe that vanishes at some lit "
        "incidences only is not Lambertian there; one that is 0 everywhere still is)"),
    ValidatorIssue(
        "normalization-spike-beside-lobe", "normalization",
        ("principled/default", "principled/metal"),
        "found by the --quick sweep at the corner where every parameter is 1: at cos theta_i "
        "= 1e-4 about 1 % of the samples fall in the clearcoat's spike (GTR1, alpha 0.001, "
        "~7e-4 rad wide, pdf up to 1.6e7) beside a GGX lobe 0.3 rad wide; lobes.layout "
        "centred the rule on the mean of the 10 % most probable samples (0.37 rad off the "
        "spike at phi = 2.1) and as wide as the broad lobe, so the spike fell between nodes: "
        "integral of pdf 0.8625 for 0.9004 counted, where an independent Monte Carlo integral "
        "gives 0.905 +- 0.0015 (Mitsuba's sample and pdf agree)",
        fixed_by="commit 59e3f4a (lobes.layout: where the 1 % most probable samples lie 16x closer "
        "together than the lobe's width, the rule is centred on them and graded down to "
        "their width)"),
    ValidatorIssue(
        "chi2-zero-weight-where-black", "chi2", ("plastic/default",),
        "found by the default-size sweep at int_ior 1 and 1.0001 (eta < 1): plastic's "
        "diffuse samples beyond the critical angle (cos theta_o < 0.0236) have eval 0, the "
        "coating reflecting that light back in, so their weight is 0; chi2 counted only "
        "samples of non-zero weight while pdf() has density there, so the first cos theta_o "
        "row of the histogram was empty against ~8 expected per bin (p = 3.5e-13); the "
        "normalization topic already counted such samples",
        fixed_by="commit 60bd8f0 (chi2 counts a zero-weight sample drawn where the BSDF is black "
        "at its wo: lanes.black_at_wo, the normalization topic's rule)"),
    ValidatorIssue(
        "box-sensitivity-batch-floor", "pdf", ("roughdielectric/beckmann-a0.1",),
        "found by the default-size sweep at alpha 0.01, int_ior 1: refine searches failing "
        "lanes 32 at a time, and box_sensitivity took rel_diff's floor (2^-10 of the median "
        "|value|) over the whole batch, so a grazing retro-reflection lane whose pdf moves "
        "from 1.05e5 to 0 within its 8-ulp box got a sensitivity of 0.21 instead of 1.0 beside "
        "near-straight transmission lanes of pdf ~1e8; the row failed (5.87) on a lane never "
        "searched, and searched alone each of the 241 lanes passes",
        fixed_by="commit b093250 (box_sensitivity: each lane against its own box)"),
    ValidatorIssue(
        "gradient-convergence-judged-by-ad", "gradient", ("pplastic/default", "pplastic/rough-ggx"),
        "found by the default-size sweep at int_ior 1 and 1.0001 (eta 0.99972, 0.99982 < 1): "
        "lanes just above the critical cosine (0.0235) have a Fresnel derivative growing as "
        "1/sqrt(cos^2 theta - cos^2 theta_c), and the step h = 2^-7 eta crosses the "
        "total-reflection edge (cos theta_c 0.127 at eta - h), so their quotients do not "
        "converge (D(h) 0.31, D(h/2) 0.78, AD 138 on one lane).  A lane was left out when "
        "|D(h) - D(h/2)| exceeded 1 % of max(|D(h/2)|, |AD|): the large AD derivative itself "
        "kept it, and the sums read 544 against 4.5 (default), 216 against 1.7 (rough-ggx)",
        fixed_by="commit 1cf0c21 (gradient.unconverged: a lane's quotients judge their own "
        "convergence, never AD; one rule for the BSDF, emitter and phase kinds): at int_ior 1 "
        "AD 0.181 against D(h/2) 0.232, tolerance 0.861"),
)


def validator_issues() -> dict[tuple[str, str], ValidatorIssue]:
    """(label, topic) -> the OPEN validator issue that explains that row's fail (a fixed one
    explains nothing: its row failing again is an unexplained fail)."""
    return {(label, v.topic): v for v in VALIDATOR_ISSUES if not v.fixed for label in v.labels}
