r"""Mitsuba 3.9.1's built-in phase functions as validation cases, and the findings that explain
their failing rows (matched by signature).

Finding ``hg-small-g-sampling`` (src/phase/hg.cpp:78 at 478e193a): sample() inverts the HG CDF
as cos θ = (1 + g² − sqr_term²)/(2g), a difference of two numbers near 1 divided by 2g; the
isotropic fallback (line 81) takes over only for |g| < 2⁻²⁴, so for small non-zero |g| the
sampled cos θ is off by ~u/g (1.2e-3 at g = 1e-4, 1e-2 with a mean bias of −2.9e-3 at
g = 1e-5; reproducer tests/repro/hg_small_g_sampling.py) and χ² rejects it at g = 1e-5.

Finding ``sggx-sample-frame-transposed`` (include/mitsuba/render/microflake.h:84; mitsuba3
issue #1728, open: "erasing the transpose solves this"): sggx_sample projects S into the frame
of wi as Rᵀ S R instead of R S Rᵀ (Dr.Jit's Matrix3f takes rows and the code transposes them); right when wi lies on an axis (Mitsuba's own χ² test samples at
wi = (0, 0, 1) only), wrong otherwise: the mean sampled direction at wi = (0.48, −0.36, 0.8)
is −(the mean under eval_pdf) (reproducer tests/repro/sggx_sample_frame_transposed.py).

Finding ``sggx-eval-forward-nan`` (src/phase/sggx.cpp:116): eval_pdf normalizes wo + wi, the
zero vector at wo = −wi (forward scattering), and returns NaN there; sample() produces that
direction at its corner sample values along axis-aligned wi (reproducer
tests/repro/sggx_eval_forward_nan.py).

:data:`CATALOGUE` is the phase-function conformance table: :func:`catalogue_cases` (every
3.9.1 phase function that loads standalone), :data:`FINDINGS`, :data:`LEFT_OUT`.
"""

from __future__ import annotations

import numpy as np

from ..conformance import Catalogue, Finding, KindCase, ValidatorIssue, with_known

CHI2_ROW = "sampling matches eval_pdf (min p-value)"
SAMPLED_EVAL_ROW = "eval_pdf at the sampled wo: value, pdf"


class OffAxisIncidence:
    """χ² cells whose incidence wi is not a coordinate axis (where Rᵀ S R ≠ R S Rᵀ)."""

    text = "χ² incidences wi that are not a coordinate axis"

    def covers(self, row):
        cells = (row.failing_lanes or {}).get("cell")
        if cells is None:
            return None
        return np.array([np.sort(np.abs(c["wi"]))[1] > 1e-6 for c in cells])


class ForwardScattering:
    """Lanes with wo = −wi to float32 round-off (the zero half vector of sggx.cpp:116)."""

    text = "lanes with wo = −wi (|wo + wi| ≤ 1e-6)"

    def covers(self, row):
        lanes = row.failing_lanes or {}
        if "wi" not in lanes or "wo" not in lanes:
            return None
        s = np.asarray(lanes["wi"], np.float64) + np.asarray(lanes["wo"], np.float64)
        return np.linalg.norm(s, axis=1) <= 1e-6


_SGGX = ("sggx (0.15, 1, 0.8)",)

#: Every Mitsuba 3.9.1 behaviour behind a failing row of the phase-function table.
FINDINGS: tuple[Finding, ...] = (
    Finding("hg-small-g-sampling", "chi2", ("hg (g = 1e-05)",), "src/phase/hg.cpp:78",
            "sample() computes cos θ = (1 + g² − sqr_term²)/(2g) (lines 77-78): float32 "
            "cancellation divided by 2g, the isotropic fallback (line 81) only for |g| < 2^-24; "
            "for small non-zero |g| the sampled directions do not follow eval_pdf (the table's χ² "
            "p = 2e-80 at g = 1e-5, --quick sizes; cos θ is off by ~1.2e-3 at g = 1e-4)",
            "at g = 1e-5: cos θ off by up to 0.0103 (mean error −0.00286) against the float64 "
            "inversion of the same u",
            "sampled cos θ within float32 round-off of the inverse CDF",
            "tests/repro/hg_small_g_sampling.py",
            excerpt="cos_theta = (1.f + dr::square(m_g) - dr::square(sqr_term)) / (2.f * m_g);",
            rows=(CHI2_ROW,), at=(("g", (-1e-3, 1e-3)),)),
    Finding("sggx-sample-frame-transposed", "chi2", _SGGX,
            "include/mitsuba/render/microflake.h:84",
            "sggx_sample builds Matrix3f(s, t, n) (rows, line 83), transposes it (line 84) and "
            "forms s2 = m S mᵀ = Rᵀ S R (line 88), where the visible-normal sampling needs S in "
            "wi's frame, R S Rᵀ; the two agree only when wi lies on an axis (Mitsuba's test "
            "samples at wi = (0, 0, 1)); reported upstream as mitsuba3 issue #1728 (open: "
            "'erasing the transpose solves this'); the table's χ² gives p = 0 at both oblique "
            "incidences, p = 0.69 at wi = (0, 0, 1)",
            "at wi = (0.48, −0.36, 0.8): mean sampled direction (0.3139, 0.1217, −0.1309) "
            "against (−0.3119, −0.1232, 0.135) under eval_pdf (∫ pdf = 1.00000), 407-1323 "
            "standard errors",
            "sampled directions distributed by eval_pdf at every wi",
            "tests/repro/sggx_sample_frame_transposed.py", excerpt="m = dr::transpose(m);",
            rows=(CHI2_ROW,),
            region=OffAxisIncidence()),
    Finding("sggx-eval-forward-nan", "finite", _SGGX, "src/phase/sggx.cpp:116",
            "eval_pdf evaluates sggx_pdf(normalize(wo + wi)): at wo = −wi the half vector is "
            "zero and the value and pdf are NaN; sample() returns wo = −wi at its corner "
            "sample values along axis-aligned wi (2 of the table's 8192 sampled lanes, wi on "
            "the x and y axes)",
            "eval_pdf at wo = −wi = (−1, 0, 0): pdf = NaN",
            "a finite value (the limit through edge-on flakes)",
            "tests/repro/sggx_eval_forward_nan.py",
            excerpt="sggx_pdf(dr::normalize(wo + mi.wi), s)",
            rows=(SAMPLED_EVAL_ROW,),
            region=ForwardScattering()),
)

#: The SGGX matrix of the sggx case (Sxx, Syy, Szz, Sxy, Sxz, Syz): Mitsuba's own test's.
SGGX_S = (0.15, 1.0, 0.8, 0.0, 0.0, 0.0)


def sggx_spec(s=SGGX_S) -> dict:
    """An sggx phase function with a constant S (a 1³ six-channel grid volume)."""
    import mitsuba as mi

    data = mi.TensorXf(np.asarray(s, np.float32), (1, 1, 1, 6))
    return {"type": "sggx", "S": {"type": "gridvolume", "data": data}}


def catalogue_cases() -> list[KindCase]:
    """Every case of the phase-function table, in table order (sets phonglab's default variant
    when none is active: the sggx volume needs one)."""
    from ... import registration
    registration.register()

    hg = [(f"hg (g = {g:g})", {"type": "hg", "g": g}, note) for g, note in (
        (0.0, "isotropic through hg's fallback"), (0.5, "forward"), (-0.5, "backward"),
        (0.99, "strongly forward (lobe width ~1e-4 in cos θ)"), (-0.99, "strongly backward"),
        (1e-5, "nearly isotropic, above the fallback threshold 2^-24"))]
    out = [KindCase("isotropic", {"type": "isotropic"}, None, {}, "uniform sphere")]
    out += [KindCase(label, spec, None, {}, note) for label, spec, note in hg]
    out.append(KindCase("hg (g swept)", {"type": "hg"}, None, {},
                        "its default g = 0.8, and through the sweep g over [-0.99, 0.99]"))
    out += [
        KindCase("rayleigh", {"type": "rayleigh"}, None, {}, "Rayleigh (1 + cos² θ)"),
        KindCase("tabphase", {"type": "tabphase", "values": "0.2, 0.5, 1.0, 2.0, 4.0"}, None,
                 {}, "5-node table rising towards forward scattering"),
        KindCase("sggx (0.15, 1, 0.8)", sggx_spec(), None, {},
                 "SGGX with a constant diagonal S (Mitsuba's test matrix)"),
        KindCase("blendphase", {"type": "blendphase", "weight": 0.3,
                                "phase_0": {"type": "hg", "g": 0.5},
                                "phase_1": {"type": "hg", "g": -0.3}}, None, {},
                 "0.7 hg(0.5) + 0.3 hg(−0.3)"),
    ]
    return with_known(out, FINDINGS)


#: Mitsuba 3.9.1 phase-function plugins (src/phase/*.cpp) not validated by the table, and why.
LEFT_OUT: dict[str, str] = {}

#: Rows of the phase-function table that fail because of the validator while its fix is open (the
#: fixed ones are told in docs/validator-fixes.md).
VALIDATOR_ISSUES: tuple[ValidatorIssue, ...] = ()

CATALOGUE = Catalogue(
    catalogue_cases, "phonglab.validate.phase.builtins.catalogue_cases()", FINDINGS,
    "phonglab.validate.phase.builtins.FINDINGS", VALIDATOR_ISSUES, LEFT_OUT,
    tests="tests/test_conformance_kinds.py", case_text="one phase function at one setting")
