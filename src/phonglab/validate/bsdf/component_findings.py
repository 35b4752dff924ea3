r"""Every Mitsuba 3.9.1 behaviour behind a failing row of the ``component`` topic in the BSDF
conformance table: how a BSDF numbers its lobes (``sampled_component`` against
``component_count()`` and ``flags(k)``) and honours a context restricted to some components or
lobe types.  :class:`~phonglab.validate.conformance.Finding` records as in :mod:`.findings`,
which joins them into ``FINDINGS``.

A composite BSDF numbers its children's components after one another (blendbsdf, twosided:
bsdf_1's component k is bsdf_0->component_count() + k); one that returns a child's sample as
is keeps the child's own index, so the sample names another lobe.  principled lists only the
lobes that are on (:data:`SPEC_TRANS_ON` and ``clearcoat`` decide which) while its sample()
hard-codes the all-lobes indices.
"""

from __future__ import annotations

from ..conformance import Finding
from .signatures import BelowHorizon, ComponentOfAnotherLobe, ComponentOutOfRange

#: The ``component`` topic's row names the findings' signatures refer to.
ONE_TYPE_ROW = "one sampled_type per component"
AGREE_ROW = "sampled_component/sampled_type agree with the flags"
RESTRICTED_ROW = "restricted context samples only its component"
SUM_ROW = "Σ_k eval(component k) = eval"
MASK_ROW = "type_mask: samples only the lobes asked for"
MASK_SUM_ROW = "type_mask: Σ eval(mask) = eval"

#: Where principled's and principledthin's specular-transmission lobe is on (spec_trans > 0;
#: 1e-4 is the sweep's smallest non-zero value).
SPEC_TRANS_ON = (("spec_trans", (1e-4, 1.0)),)

#: The ``component`` topic's findings.
COMPONENT_FINDINGS: tuple[Finding, ...] = (
    Finding("principled-component-ids", "component",
            ("principled/default", "principled/metal"),
            "src/bsdfs/principled.cpp:423",
            "sample() hard-codes the all-lobes indices (3 = specular here, 2 = spec_trans at "
            "line 440, 1 = clearcoat at line 463) while m_components (lines 242-265) only holds "
            "the lobes that are on",
            "sampled_component 3 with component_count() = 2",
            "sampled_component < component_count() and flags(i) containing sampled_type",
            "tests/repro/principled_component_ids.py",
            excerpt="dr::masked(bs.sampled_component, sample_spec_reflect) = 3;",
            rows=(AGREE_ROW,), region=ComponentOutOfRange()),
    Finding("principled-component-ids-shifted", "component", ("principled/default",),
            "src/bsdfs/principled.cpp:440",
            "the same hard-coded indices: with spec_trans on and clearcoat off m_components is "
            "[diffuse, spec_trans, specular] (lines 242-265), so the transmission samples' "
            "index 2 (line 440) names the specular-reflection component",
            "spec_trans 1: the transmission samples report component 2, whose flags have "
            "GlossyReflection",
            "component 1 for the transmission samples",
            "tests/repro/principled_component_ids.py",
            excerpt="dr::masked(bs.sampled_component, sample_spec_trans) = 2;",
            rows=(AGREE_ROW,), region=ComponentOfAnotherLobe(),
            at=SPEC_TRANS_ON + (("clearcoat", 0.0),)),
    Finding("principled-ignores-component", "component",
            ("principled/default", "principled/all-lobes", "principled/metal",
             "principledthin/default", "principledthin/all-lobes"),
            "src/bsdfs/principled.cpp:377",
            "the lobe probabilities (principled.cpp:377-393, principledthin.cpp:291-299) and "
            "eval/pdf never consult ctx.component, ctx.type_mask or ctx.is_enabled(), so a "
            "context restricted to one component or to some lobe types still samples and "
            "evaluates every lobe",
            "BSDFContext(component=0) samples components [0, 1, 2, 3]; type_mask "
            "DiffuseReflection (0x2) samples types ['0x2', '0x8', '0x10']",
            "only component 0; only type 0x2",
            "tests/repro/principled_ignores_component.py",
            excerpt="Float prob_spec_reflect = dr::select(",
            rows=(RESTRICTED_ROW, SUM_ROW, MASK_ROW, MASK_SUM_ROW)),
    Finding("blendbsdf-component-ids", "component",
            ("blendbsdf/diffuse+roughconductor", "blendbsdf/roughconductor+roughdielectric"),
            "src/bsdfs/blendbsdf.cpp:154",
            "`dr::masked(bs, m1) = bs1` keeps bsdf_1's own component index instead of adding "
            "bsdf_0->component_count() (the numbering of lines 94-97; line 123 likewise)",
            "components [32770, 32776] (DiffuseReflection | FrontSide, GlossyReflection | "
            "FrontSide); the glossy samples of bsdf_1 report component 0",
            "component 1",
            "tests/repro/blendbsdf_component_ids.py",
            excerpt="dr::masked(bs, m1) = bs1;",
            rows=(AGREE_ROW, RESTRICTED_ROW), region=ComponentOfAnotherLobe()),
    Finding("blendbsdf-component-ids-mixed", "component",
            ("blendbsdf/diffuse+roughconductor", "blendbsdf/roughconductor+roughdielectric"),
            "src/bsdfs/blendbsdf.cpp:154",
            "the same numbering: bsdf_1's samples report component 0, so component 0 shows both "
            "nested BSDFs' sampled types (a component is one lobe)",
            "components [32770, 32776] (DiffuseReflection | FrontSide, GlossyReflection | "
            "FrontSide); the glossy samples of bsdf_1 report component 0",
            "component 1",
            "tests/repro/blendbsdf_component_ids.py", excerpt="dr::masked(bs, m1) = bs1;",
            rows=(ONE_TYPE_ROW,)),
    Finding("twosided-component-ids", "component", ("twosided/diffuse|roughconductor",),
            "src/bsdfs/twosided.cpp:142",
            "with two different BSDFs, sample() returns bsdf_1's sample for the back_side "
            "lanes as is (`m_brdf[1]->sample(ctx, si, ...)`, lines 141-142), so it keeps "
            "bsdf_1's own component index instead of adding bsdf_0->component_count() (the "
            "numbering of the constructor's two loops, lines 90-100; a context restricted to a "
            "front component also wraps to (uint32_t) -1 on the back side, lines 137-138); "
            "only ω_i below the surface shows it",
            "components [32770, 65544] (DiffuseReflection | FrontSide, GlossyReflection | "
            "BackSide); 10000 glossy samples of bsdf_1 (ω_i below) report component 0",
            "component 1",
            "tests/repro/twosided_component_ids.py",
            excerpt="m_brdf[1]->sample(ctx, si, sample1, sample2, back_side);",
            rows=(AGREE_ROW, RESTRICTED_ROW), region=ComponentOfAnotherLobe()),
    Finding("twosided-component-ids-mixed", "component", ("twosided/diffuse|roughconductor",),
            "src/bsdfs/twosided.cpp:142",
            "the same numbering: bsdf_1's samples report component 0, so component 0 shows both "
            "nested BSDFs' sampled types (a component is one lobe)",
            "10000 glossy samples of bsdf_1 (ω_i below) report component 0 (flags(0) = 32770, "
            "DiffuseReflection | FrontSide)",
            "component 1",
            "tests/repro/twosided_component_ids.py",
            excerpt="m_brdf[1]->sample(ctx, si, sample1, sample2, back_side);",
            rows=(ONE_TYPE_ROW,)),
    Finding("twosided-component-wrap", "component", ("twosided/diffuse|roughconductor",),
            "src/bsdfs/twosided.cpp:172",
            "with two different BSDFs, a context restricted to component k has "
            "bsdf_0->component_count() subtracted on the back side (`ctx.component -= ...`, "
            "eval() at lines 171-172) "
            "without a check that k is a back component: k = 0 wraps to (uint32_t) -1, which "
            "means every component, so for ω_i below the surface component 0 evaluates the "
            "whole back BSDF and Σ_k eval_k is twice eval (sample(), pdf() and eval_pdf() "
            "subtract the same way, lines 137-138, 206-207, 244-245)",
            "Σ_k eval_k / eval below the surface = 2.0000",
            "Σ_k eval_k = eval",
            "tests/repro/twosided_component_ids.py",
            excerpt="ctx.component -= (uint32_t) m_brdf[0]->component_count();",
            rows=(SUM_ROW,), region=BelowHorizon()),
    Finding("pplastic-component-ids", "component", ("pplastic/default", "pplastic/rough-ggx"),
            "src/bsdfs/pplastic.cpp:210",
            "one component (Glossy|Diffuse) is declared but sample() reports components 0 and 1 "
            "(lines 278, 284) and the lobes are enabled with ctx.is_enabled(..., 0/1) "
            "(lines 251-252)",
            "sampled_component 1 with component_count() = 1",
            "sampled_component < component_count()",
            "tests/repro/pplastic_component_ids.py",
            excerpt="m_components.push_back(m_flags);",
            rows=(AGREE_ROW,), region=ComponentOutOfRange()),
    Finding("mask-restricted-context", "component",
            ("mask/diffuse-0.5", "mask/roughconductor-0.8"),
            "src/bsdfs/mask.cpp:140",
            "`opacity = sample_transmission ? 1.f : 0.f` is inverted (opacity is the "
            "probability of the NESTED lobe, line 157): a context without the Null lobe returns "
            "only pass-through samples, one with only the Null lobe samples the nested BSDF",
            "context = DiffuseReflection: 100 % of the samples are Null (wo = -wi)",
            "0 % Null samples (pdf() at line 177 already treats the context the right way)",
            "tests/repro/mask_restricted_context.py",
            excerpt="opacity = sample_transmission ? 1.f : 0.f;",
            rows=(RESTRICTED_ROW, MASK_ROW)),
)
