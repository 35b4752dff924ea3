"""A wrapper BSDF as authors port Mitsuba's tinting and blending plugins to Python: it holds a
built-in child (``bsdf``, a Beckmann ``roughconductor`` at alpha 0.3 by default) and scales the
child's value by ``tint``; sampling, pdf and flags are the child's.

Correct as a wrapper: every row it fails is its child's (Beckmann's smith_g1 approximation,
microfacet.h:346, on ``normalization``; the conductor Fresnel term's derivative at eta = 0,
fresnel.h:104, on ``gradient``).  ``pdf_scale`` (default 1) plants a defect of its own: the
pdf it reports is scaled by it, which the child does not do.
"""

import mitsuba as mi


class TintedWrapper(mi.BSDF):
    def __init__(self, props):
        mi.BSDF.__init__(self, props)
        self.nested = props.get("bsdf", None)
        if self.nested is None:
            self.nested = mi.load_dict({"type": "roughconductor", "alpha": 0.3})
        self.tint = props.get("tint", 0.8)
        self.pdf_scale = props.get("pdf_scale", 1.0)
        self.m_components = [self.nested.flags(i) for i in range(self.nested.component_count())]
        self.m_flags = self.nested.flags()

    def sample(self, ctx, si, sample1, sample2, active):
        bs, weight = self.nested.sample(ctx, si, sample1, sample2, active)
        bs.pdf = bs.pdf * self.pdf_scale
        return bs, weight * self.tint / self.pdf_scale

    def eval(self, ctx, si, wo, active):
        return self.nested.eval(ctx, si, wo, active) * self.tint

    def pdf(self, ctx, si, wo, active):
        return self.nested.pdf(ctx, si, wo, active) * self.pdf_scale

    def eval_pdf(self, ctx, si, wo, active):
        value, pdf = self.nested.eval_pdf(ctx, si, wo, active)
        return value * self.tint, pdf * self.pdf_scale

    def traverse(self, callback):
        callback.put("nested", self.nested, mi.ParamFlags.Differentiable)

    def to_string(self):
        return f"TintedWrapper[tint={self.tint}, nested={self.nested}]"


mi.register_bsdf("tinted_wrapper", lambda props: TintedWrapper(props))
