r"""Every Mitsuba 3.9.1 behaviour behind a failing row of the polarized topics (``mueller``,
``intensity``, ``mueller_identities``, ``mueller_reciprocity``) in the BSDF conformance table:
:class:`~phonglab.validate.conformance.Finding` records as in :mod:`.findings`, which joins them
into ``FINDINGS``.
"""

from __future__ import annotations

from ..conformance import Finding
from .signatures import Grazing, IncidencePlaneY0

#: Where pplastic's polarized grazing cancellation (pplastic.cpp:375-376) shows: its error grows
#: with η, and the last pair whose reciprocity differs by more than 2^-10 (no sensitivity
#: allowance; 400 000 random pairs, llvm_ad_spectral_polarized) lies at min cos 0.0112 for
#: η = 1.5, 0.0130 for 2, 0.0164 for 2.5 and 0.0197 for 3, the top of the documented IOR range.
PPLASTIC_GRAZING = Grazing(0.02)

#: The polarized topics' findings.
POLARIZED_FINDINGS: tuple[Finding, ...] = (
    Finding("pplastic-polarized-grazing-mueller", "mueller_reciprocity",
            ("pplastic/default", "pplastic/rough-ggx"), "src/bsdfs/pplastic.cpp:376",
            "the same cause as pplastic-polarized-grazing, seen in the whole Mueller matrix: the "
            "polarized diffuse term's second Fresnel transmission is evaluated from the "
            "internally refracted direction, at the critical angle for grazing directions, "
            "where float32 cancels (lines 375-376), so f(wo, wi) and the reversed f(wi, wo) "
            "differ there",
            "the matrix's M00 (reproducer, pplastic/default, 550 nm): f(a, b) = 0.001133417 vs "
            "f(b, a) = 0.00111937 (1.3 %) at cos = 0.0019 in llvm_ad_spectral_polarized, "
            "1.5e-8 in llvm_ad_spectral; the row compares every element of M/M00",
            "the reversed path's matrix to float32 precision",
            "tests/repro/pplastic_polarized_grazing.py",
            excerpt="specular_transmission(dr::abs(Frame3f::cos_theta(wi_hat_p)), inv_eta)",
            rows=("f(wo, wi) = R_out Q f(wi, wo)ᵀ Q R_inᵀ, reflection",),
            region=PPLASTIC_GRAZING),
    Finding("pplastic-polarized-grazing-intensity", "intensity",
            ("pplastic/default", "pplastic/rough-ggx"), "src/bsdfs/pplastic.cpp:376",
            "the same cause as pplastic-polarized-grazing: at cos_theta_i = 1e-4 the internally "
            "refracted direction (line 375) lies at the critical angle, where "
            "specular_transmission(|cos|, 1/eta) (line 376) rounds to 0 in float32, so the "
            "polarized diffuse term is 0 where the unpolarized branch's (1 - R(cos_theta_i)) "
            "(lines 429-431) is not",
            "at cos_theta_i = 1e-4, 550 nm (reproducer): M00 = 0 against the unpolarized "
            "8.765e-05 (pplastic/default), 0.01068 against 0.01077 (rough-ggx, 0.81 % low: its "
            "specular lobe is unaffected); at cos_theta_i >= 0.2 the largest relative "
            "difference is 3.7e-07 (30 lanes)",
            "M00 of the polarized eval = the unpolarized eval to float32 precision",
            "tests/repro/pplastic_polarized_grazing_intensity.py",
            excerpt="specular_transmission(dr::abs(Frame3f::cos_theta(wi_hat_p)), inv_eta)",
            rows=("eval M00 = eval in llvm_ad_spectral",
                  "sample: wo, pdf, weight M00 = llvm_ad_spectral's"), region=PPLASTIC_GRAZING),
    Finding("dielectric-polarized-grazing-transmission", "intensity", ("dielectric/polarized",),
            "src/bsdfs/dielectric.cpp:305",
            "in polarized variants sample() evaluates the transmission Mueller matrix at the "
            "refracted direction (cos_theta_o_hat, line 305) but divides it by bs.pdf, the "
            "transmission probability computed from the incident side (line 266); for grazing "
            "wi the refracted direction lies at the critical angle, where "
            "cos = sqrt(1 - eta^2 sin^2) cancels in float32, so the two disagree there (the "
            "unpolarized branch divides t_i by t_i)",
            "transmitted weight at cos_theta_i = 1e-4 (int_ior 1.5): polarized M00 1.788, "
            "unpolarized 0.4447 (1/eta^2 = 0.4444)",
            "weight M00 = the unpolarized weight to float32 precision",
            "tests/repro/dielectric_polarized_grazing.py",
            excerpt="T = mueller::specular_transmission(UnpolarizedSpectrum(cos_theta_o_hat)",
            rows=("sample: wo, pdf, weight M00 = llvm_ad_spectral's",), region=Grazing(0.01)),
    Finding("retarder-jump-y0", "mueller_identities", ("retarder/quarter", "retarder/half"),
            "src/bsdfs/retarder.cpp:129",
            "sample() re-expresses the element's Mueller matrix from the fixed axis (1, 0, 0) to "
            "stokes_basis(forward) with rotate_mueller_basis_collinear (lines 129-131) without "
            "projecting that axis onto the plane normal to forward (polarizer.cpp:134-136 "
            "does); rotate_stokes_basis takes the angle's sign from dot(forward, cross(x, b)), "
            "which changes sign with forward.y, so the matrix jumps across wi.y = 0 "
            "(mitsuba3#1963, open)",
            "at wi = (0.5, +-1e-5, 0.8) (quarter wave, theta = 30 deg): M11 = 0.9963 against "
            "0.4754, M13 = 0.068 against -0.8054; the largest entry difference 1.51 (M00 = 1)",
            "a Mueller matrix continuous in wi",
            "tests/repro/retarder_jump_y0.py",
            excerpt="M = mueller::rotate_mueller_basis_collinear(M, forward,",
            rows=("delta-lobe matrices continuous in wi (8-ulp move, common frames)",),
            region=IncidencePlaneY0(1e-5)),
)
