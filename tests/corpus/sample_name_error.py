"""sample_name_error -- a direct-illumination integrator (emitter sampling only) with a
typo on its main code path.

Style: plain ``mi.SamplingIntegrator`` subclass; ``active`` positional WITHOUT a
default; ``to_string`` present, no ``traverse``.

BUG (one): ``sample`` refers to ``bsdf_ctx``, a name that is never defined (the
context is created as ``ctx``), on the line every shaded pixel runs, so the first
call of ``sample`` -- the first ``mi.render`` -- raises ``NameError: name 'bsdf_ctx' is
not defined``.  Loading the scene works.  Property broken: none measurable, the plugin
cannot render (``error``): for checking that the error is attributed to this file and
line.
"""

import drjit as dr
import mitsuba as mi


class SampleNameError(mi.SamplingIntegrator):
    def __init__(self, props):
        mi.SamplingIntegrator.__init__(self, props)

    def sample(self, scene, sampler, ray, medium, active):
        ctx = mi.BSDFContext()
        ray = mi.Ray3f(ray)
        si = scene.ray_intersect(ray, active)
        L = mi.Spectrum(si.emitter(scene, active).eval(si, active))

        active = active & si.is_valid()
        bsdf = si.bsdf(ray)
        ds, em_weight = scene.sample_emitter_direction(si, sampler.next_2d(active), True,
                                                       active)
        f = bsdf.eval(bsdf_ctx, si, si.to_local(ds.d), active)  # noqa: F821
        L += dr.select(active & (ds.pdf > 0.0), f * em_weight, 0.0)
        return L, si.is_valid(), []

    def to_string(self):
        return 'SampleNameError[]'


mi.register_integrator('sample_name_error', lambda props: SampleNameError(props))
