"""A correct Lambertian area light written as a plugin author would (the control).

It samples its shape by area (shape.sample_position, p_A = 1/A) and converts the density to
solid angle at the reference point: pdf = p_A · dist² / |cos θ'| (area.cpp / sphere.cpp
convention); weight = L / pdf on the emitting side (dot(ds.d, ds.n) < 0).  sample_ray: a
point by area and a cosine-weighted direction, weight = A · π · L.
"""
import drjit as dr
import mitsuba as mi

SOLID_ANGLE = True          # area_pdf_measure.py: False (reports the area-measure density)
RAY_PI = dr.pi              # area_ray_missing_pi.py: 1.0 (forgets the π of the cosine lobe)


class AreaControl(mi.Emitter):
    def __init__(self, props):
        super().__init__(props)
        self.m_flags = mi.EmitterFlags.Surface
        self.radiance = mi.Float(props.get("radiance", 2.0))

    def traverse(self, cb):
        cb.put("radiance", self.radiance, mi.ParamFlags.Differentiable)

    def parameters_changed(self, keys=[]):
        pass

    def _pdf(self, ps_pdf, ds):
        if not SOLID_ANGLE:
            return ps_pdf
        return ps_pdf * dr.square(ds.dist) / dr.abs(dr.dot(ds.d, ds.n))

    def sample_direction(self, it, sample, active=True):
        shape = self.get_shape()
        ps = shape.sample_position(it.time, sample, active)
        ds = mi.DirectionSample3f(ps)
        d = ps.p - it.p
        ds.dist = dr.norm(d)
        ds.d = d / ds.dist
        front = dr.dot(ds.d, ds.n) < 0.0
        ds.pdf = dr.select(front, self._pdf(ps.pdf, ds), 0.0)
        ds.delta = False
        weight = dr.select(front & (ds.pdf > 0), self.radiance / ds.pdf, 0.0)
        return ds, mi.Color3f(weight)

    def pdf_direction(self, it, ds, active=True):
        front = dr.dot(ds.d, ds.n) < 0.0
        ps = mi.PositionSample3f()
        ps.p, ps.n = ds.p, ds.n
        p_area = self.get_shape().pdf_position(ps, active)
        return dr.select(front, self._pdf(p_area, ds), 0.0)

    def eval_direction(self, it, ds, active=True):
        return mi.Color3f(dr.select(dr.dot(ds.d, ds.n) < 0.0, self.radiance, 0.0))

    def eval(self, si, active=True):
        return mi.Color3f(dr.select(mi.Frame3f.cos_theta(si.wi) > 0.0, self.radiance, 0.0))

    def sample_ray(self, time, wavelength_sample, sample2, sample3, active=True):
        shape = self.get_shape()
        ps = shape.sample_position(time, sample2, active)
        local = mi.warp.square_to_cosine_hemisphere(sample3)
        d = mi.Frame3f(ps.n).to_world(local)
        weight = self.radiance * RAY_PI / ps.pdf
        return mi.Ray3f(ps.p, d, time, dr.zeros(mi.Color0f)), mi.Color3f(weight)

    def sample_position(self, time, sample, active=True):
        ps = self.get_shape().sample_position(time, sample, active)
        return ps, dr.select(ps.pdf > 0, dr.rcp(ps.pdf), 0.0)

    def pdf_position(self, ps, active=True):
        return self.get_shape().pdf_position(ps, active)


mi.register_emitter("defect_area_control", lambda props: AreaControl(props))
