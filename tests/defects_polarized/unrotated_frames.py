"""Planted defect: the diattenuating Lambertian of diattenuating_lambert.py (s/p-frame matrix
f·[[1, d, 0, 0], [d, 1, 0, 0], [0, 0, c, 0], [0, 0, 0, c]], d = 0.5) returned in the s/p
frames of the plane of incidence, *without* the rotation into Mitsuba's implicit Stokes bases
stokes_basis(−wo_hat), stokes_basis(wi_hat) -- the step conductor.cpp:296-299 takes and an
author most easily forgets.  The matrix is still a realizable Jones matrix with the right M00,
symmetric (reciprocal in Mitsuba's frames too, since stokes_basis(−d) = stokes_basis(d)), and
eval, pdf and sample agree, so only the ``mueller_identities`` row "isotropy in Mitsuba's
Stokes frames" can see it: in the s/p frames its matrix changes when wi and wo rotate together
about the normal.

It changes renders: the polarization it puts out has the wrong angle.  A 4×4 plane of it under
a constant unit environment, seen from 60° off its normal (64×64, 32 spp, path depth 4, seed 0,
the `stokes` integrator, llvm_ad_spectral_polarized), against the correct plugin at the same
seed: S0 is the same to float32 round-off (M00 is right), S1 differs by 0.02 % and S2 by 11 %
of the mean S0 per pixel (its sign flips: the s/p angle is read in the wrong frame).  With a
linear polarizer at 45° in front of the camera the *intensity* changes: the left half of the
image 10.5 % darker, the right half 11.7 % brighter, up to 43 % in a pixel (11 % mean
|ΔS0|/S0, against 3.3 % between two seeds of the correct plugin).
tests/test_validate_polarized.py renders this scene smaller."""

import drjit as dr
import mitsuba as mi

#: The diattenuation d and √(1 − d²).
D, C = 0.5, 0.75 ** 0.5


class UnrotatedFrames(mi.BSDF):
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
        # A matrix in the s/p frames of the plane of incidence (s ⟂ it) ...
        m = mi.depolarizer(f)
        m[0][1] = m[1][0] = D * f
        m[1][1] = f
        m[2][2] = m[3][3] = C * f
        # DEFECT: ... returned as it is, not rotated into the implicit Stokes bases of
        # -wo_hat and wi_hat with mi.mueller.rotate_mueller_basis
        return m

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
        return "UnrotatedFrames[]"


mi.register_bsdf("defect_unrotated_frames", lambda props: UnrotatedFrames(props))
