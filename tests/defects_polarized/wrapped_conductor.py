"""Control: a Python BSDF that forwards every call to a loaded Mitsuba ``conductor`` (gold).

Whatever the built-in returns (Mueller matrices in polarized variants, in its own Stokes
frames) the wrapper returns unchanged, so it must pass wherever the built-in does.
"""

import mitsuba as mi


class WrappedConductor(mi.BSDF):
    def __init__(self, props):
        mi.BSDF.__init__(self, props)
        self.inner = mi.load_dict({"type": "conductor", "material": "Au"})
        self.m_components = [self.inner.flags(k) for k in range(self.inner.component_count())]
        self.m_flags = self.inner.flags()

    def eval(self, ctx, si, wo, active=True):
        return self.inner.eval(ctx, si, wo, active)

    def pdf(self, ctx, si, wo, active=True):
        return self.inner.pdf(ctx, si, wo, active)

    def eval_pdf(self, ctx, si, wo, active=True):
        return self.inner.eval_pdf(ctx, si, wo, active)

    def sample(self, ctx, si, sample1, sample2, active=True):
        return self.inner.sample(ctx, si, sample1, sample2, active)

    def to_string(self):
        return "WrappedConductor[]"


mi.register_bsdf("pol_wrapped_conductor", lambda props: WrappedConductor(props))
