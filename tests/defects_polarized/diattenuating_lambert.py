"""Control: a diattenuating Lambertian.  Its Mueller matrix in the s/p frames of the plane of
incidence is f·D, f = ρ/π cos θ_o and D the linear diattenuator [[1, d, 0, 0], [d, 1, 0, 0],
[0, 0, c, 0], [0, 0, 0, c]], d = 0.5, c = √(1 − d²) (a Jones matrix diag(√(1 + d), √(1 − d)):
unpolarized light comes out half s-polarized), rotated into Mitsuba's implicit Stokes bases as
conductor.cpp does.  Realizable, symmetric in the s/p frames (reciprocal), isotropic: it must
pass every topic.  tests/defects_polarized/unrotated_frames.py is this plugin without the
rotation."""

import drjit as dr
import mitsuba as mi

#: The diattenuation d and √(1 − d²).
D, C = 0.5, 0.75 ** 0.5


class DiattenuatingLambert(mi.BSDF):
    def __init__(self, props):
        mi.BSDF.__init__(self, props)
        self.reflectance = mi.Float(props.get("reflectance", 0.5))
        self.m_components = [mi.BSDFFlags.DiffuseReflection | mi.BSDFFlags.FrontSide]
        self.m_flags = self.m_components[0]

    def traverse(self, callback):
        callback.put("reflectance", self.reflectance, mi.ParamFlags.Differentiable)

    def _ok(self, si, wo):
        return (mi.Frame3f.cos_theta(si.wi) > 0) & (mi.Frame3f.cos_theta(wo) > 0)

    def _value(self, ctx, si, wo):
        f = mi.UnpolarizedSpectrum(self.reflectance * dr.inv_pi * mi.Frame3f.cos_theta(wo))
        if not mi.is_polarized:
            return mi.Spectrum(f)
        # A matrix in the s/p frames of the plane of incidence (s ⟂ it), rotated into Mitsuba's
        # implicit Stokes bases of −wo_hat (in) and wi_hat (out), as conductor.cpp:272-301.
        radiance = ctx.mode == mi.TransportMode.Radiance
        wo_hat = dr.select(radiance, wo, si.wi)
        wi_hat = dr.select(radiance, si.wi, wo)
        n = mi.Vector3f(0, 0, 1)
        s_in, s_out = dr.cross(n, -wo_hat), dr.cross(n, wi_hat)
        s_in = dr.select(dr.norm(s_in) > 1e-12, dr.normalize(s_in), mi.Vector3f(1, 0, 0))
        s_out = dr.select(dr.norm(s_out) > 1e-12, dr.normalize(s_out), mi.Vector3f(1, 0, 0))
        m = mi.depolarizer(f)
        m[0][1] = m[1][0] = D * f
        m[1][1] = f
        m[2][2] = m[3][3] = C * f
        return mi.mueller.rotate_mueller_basis(m, -wo_hat, s_in, mi.mueller.stokes_basis(-wo_hat),
                                               wi_hat, s_out, mi.mueller.stokes_basis(wi_hat))

    def eval(self, ctx, si, wo, active=True):
        return dr.select(self._ok(si, wo), self._value(ctx, si, wo), 0.0)

    def pdf(self, ctx, si, wo, active=True):
        return dr.select(self._ok(si, wo), mi.warp.square_to_cosine_hemisphere_pdf(wo), 0.0)

    def eval_pdf(self, ctx, si, wo, active=True):
        return self.eval(ctx, si, wo, active), self.pdf(ctx, si, wo, active)

    def sample(self, ctx, si, sample1, sample2, active=True):
        bs = dr.zeros(mi.BSDFSample3f)
        bs.wo = mi.warp.square_to_cosine_hemisphere(sample2)
        bs.pdf = self.pdf(ctx, si, bs.wo)
        bs.eta = 1.0
        bs.sampled_type = mi.UInt32(int(mi.BSDFFlags.DiffuseReflection))
        bs.sampled_component = mi.UInt32(0)
        value = self.eval(ctx, si, bs.wo) / dr.select(bs.pdf > 0, bs.pdf, 1.0)
        return bs, dr.select(bs.pdf > 0, value, 0.0)

    def to_string(self):
        return "DiattenuatingLambert[]"


mi.register_bsdf("pol_diattenuating_lambert", lambda props: DiattenuatingLambert(props))
