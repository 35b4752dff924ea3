"""traverse_renamed_api -- a correct Lambertian BSDF whose ``traverse`` was written
against the early Mitsuba 3 Python API (as in the first versions of the custom-BSDF
tutorial): it registers its parameter with ``callback.put_parameter(...)``.

Style: early-tutorial; ``active`` positional WITHOUT a default; reflectance a
``mi.Color3f`` from ``props.get('reflectance', 0.5)``; ``m_flags``/``m_components``
set; ``to_string`` present.

BUG (one): ``mi.TraversalCallback`` in Mitsuba 3.9.1 has ``put``, ``put_value`` and
``put_object`` but no ``put_parameter``, so ``traverse`` raises ``AttributeError``
(surfacing from ``mi.traverse(...)``).  eval, pdf and sample are correct, and a plain
render that never traverses works.  Property broken: parameter traversal
(``traverse``): no differentiable parameters, no scene editing.
"""

import drjit as dr
import mitsuba as mi


class TraverseRenamedApi(mi.BSDF):
    def __init__(self, props):
        mi.BSDF.__init__(self, props)
        self.reflectance = mi.Color3f(props.get('reflectance', 0.5))
        self.m_components = [mi.BSDFFlags.DiffuseReflection | mi.BSDFFlags.FrontSide]
        self.m_flags = self.m_components[0]

    def sample(self, ctx, si, sample1, sample2, active):
        bs = dr.zeros(mi.BSDFSample3f)
        if not ctx.is_enabled(mi.BSDFFlags.DiffuseReflection, 0):
            return bs, mi.Color3f(0.0)
        active = active & (mi.Frame3f.cos_theta(si.wi) > 0.0)
        bs.wo = mi.warp.square_to_cosine_hemisphere(sample2)
        bs.pdf = mi.warp.square_to_cosine_hemisphere_pdf(bs.wo)
        bs.eta = 1.0
        bs.sampled_type = mi.UInt32(+mi.BSDFFlags.DiffuseReflection)
        bs.sampled_component = mi.UInt32(0)
        active = active & (bs.pdf > 0.0)
        return bs, dr.select(active, self.reflectance, 0.0)

    def eval(self, ctx, si, wo, active):
        if not ctx.is_enabled(mi.BSDFFlags.DiffuseReflection, 0):
            return mi.Color3f(0.0)
        cos_theta_i = mi.Frame3f.cos_theta(si.wi)
        cos_theta_o = mi.Frame3f.cos_theta(wo)
        active = active & (cos_theta_i > 0.0) & (cos_theta_o > 0.0)
        return dr.select(active, self.reflectance * dr.inv_pi * cos_theta_o, 0.0)

    def pdf(self, ctx, si, wo, active):
        if not ctx.is_enabled(mi.BSDFFlags.DiffuseReflection, 0):
            return mi.Float(0.0)
        cos_theta_i = mi.Frame3f.cos_theta(si.wi)
        cos_theta_o = mi.Frame3f.cos_theta(wo)
        active = active & (cos_theta_i > 0.0) & (cos_theta_o > 0.0)
        return dr.select(active, mi.warp.square_to_cosine_hemisphere_pdf(wo), 0.0)

    def eval_pdf(self, ctx, si, wo, active):
        return self.eval(ctx, si, wo, active), self.pdf(ctx, si, wo, active)

    def traverse(self, callback):
        callback.put_parameter('reflectance', self.reflectance,
                               mi.ParamFlags.Differentiable)

    def parameters_changed(self, keys):
        pass

    def to_string(self):
        return f'TraverseRenamedApi[reflectance={self.reflectance}]'


mi.register_bsdf('traverse_renamed_api', lambda props: TraverseRenamedApi(props))
