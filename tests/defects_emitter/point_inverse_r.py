"""A point light whose weight falls as 1/r instead of 1/r² (planted defect; else as the control).

Intensity I (W/sr, ``intensity``) at ``position``: sample_direction returns ds.pdf = 1,
ds.delta, weight = I / r² (point.cpp); sample_ray a uniform direction with weight 4π I.
"""
import drjit as dr
import mitsuba as mi

INVERSE_POWER = 1          # the planted defect: 1/r


class PointInverseR(mi.Emitter):
    def __init__(self, props):
        super().__init__(props)
        self.m_flags = mi.EmitterFlags.DeltaPosition
        self.intensity = mi.Float(props.get("intensity", 3.0))
        self.position = mi.Point3f(0.0, 0.0, 1.0)

    def traverse(self, cb):
        cb.put("intensity", self.intensity, mi.ParamFlags.Differentiable)

    def parameters_changed(self, keys=[]):
        pass

    def _falloff(self, dist):
        return dr.rcp(dr.square(dist)) if INVERSE_POWER == 2 else dr.rcp(dist)

    def sample_direction(self, it, sample, active=True):
        d = self.position - it.p
        dist = dr.norm(d)
        ds = dr.zeros(mi.DirectionSample3f)
        ds.p = self.position
        ds.d = d / dist
        ds.dist = dist
        ds.pdf = 1.0
        ds.delta = True
        return ds, mi.Color3f(self.intensity * self._falloff(dist))

    def pdf_direction(self, it, ds, active=True):
        return mi.Float(0.0)

    def eval_direction(self, it, ds, active=True):
        return mi.Color3f(self.intensity * self._falloff(ds.dist))

    def eval(self, si, active=True):
        return mi.Color3f(0.0)

    def sample_ray(self, time, wavelength_sample, sample2, sample3, active=True):
        d = mi.warp.square_to_uniform_sphere(sample3)
        return (mi.Ray3f(self.position, d, time, dr.zeros(mi.Color0f)),
                mi.Color3f(4.0 * dr.pi * self.intensity))

    def sample_position(self, time, sample, active=True):
        ps = dr.zeros(mi.PositionSample3f)
        ps.p = self.position
        ps.pdf = 1.0
        ps.delta = True
        ps.time = time
        return ps, mi.Float(1.0)


mi.register_emitter("defect_point_inverse_r", lambda props: PointInverseR(props))
