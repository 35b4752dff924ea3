"""py_constant_env -- a constant (uniform) environment emitter written in Python.

Style: trampoline-test style; ``radiance`` read with
``props.get_texture('radiance', 1.0)`` (float, rgb or a uniform texture; evaluated
with ``tex.eval(si, active)``); ``active`` positional WITHOUT a default;
``self.m_flags = mi.EmitterFlags.Infinite`` so the scene treats it as its
environment; ``traverse`` and ``to_string`` present.

Mitsuba 3.9.1 never calls a Python emitter's ``set_scene``, so the scene's bounding
sphere is not available: the emitter uses a fixed one, centre ``center`` (default
origin) and radius ``radius`` (default 1e3), which must enclose the scene.

CONTROL (correct): L(d) = radiance for every direction d;
sample_direction draws d uniformly on the sphere (pdf 1/(4 pi), weight L*4 pi);
pdf_direction = 1/(4 pi); sample_ray draws d uniformly and an origin uniformly on the
disk of radius R facing d, outside the bounding sphere (weight L * 4 pi * pi R^2, the
emitted power); ``sample_position`` returns an empty sample with pdf 0 and weight 0 (the
base class leaves it pure virtual, and ``ptracer`` calls it even for an environment
emitter -- without it ``ptracer`` fails with "tried to call a pure virtual function"),
and ``sample_wavelengths`` returns the radiance (RGB variants only: ``mi.Color0f()``).
"""

import drjit as dr
import mitsuba as mi


class PyConstantEnv(mi.Emitter):
    def __init__(self, props):
        mi.Emitter.__init__(self, props)
        self.radiance = props.get_texture('radiance', 1.0)
        self.radius = float(props.get('radius', 1e3))
        c = props.get('center', [0.0, 0.0, 0.0])
        self.center = mi.ScalarPoint3f(c[0], c[1], c[2])
        self.m_flags = mi.EmitterFlags.Infinite

    def _radiance(self, si, active):
        return self.radiance.eval(si, active)

    def eval(self, si, active):
        return dr.select(active, self._radiance(si, active), 0.0)

    def eval_direction(self, it, ds, active):
        si = dr.zeros(mi.SurfaceInteraction3f)
        si.wavelengths = it.wavelengths
        return dr.select(active, self._radiance(si, active), 0.0)

    def sample_direction(self, it, sample, active):
        d = mi.warp.square_to_uniform_sphere(sample)
        dist = 2.0 * self.radius

        ds = dr.zeros(mi.DirectionSample3f)
        ds.p = it.p + d * dist
        ds.n = -d
        ds.uv = sample
        ds.time = it.time
        ds.pdf = mi.warp.square_to_uniform_sphere_pdf(d)
        ds.delta = False
        ds.emitter = mi.EmitterPtr(self)
        ds.d = d
        ds.dist = dist

        si = dr.zeros(mi.SurfaceInteraction3f)
        si.wavelengths = it.wavelengths
        weight = self._radiance(si, active) / ds.pdf
        return ds, dr.select(active, weight, 0.0)

    def pdf_direction(self, it, ds, active):
        return dr.select(active, mi.warp.square_to_uniform_sphere_pdf(ds.d), 0.0)

    def sample_ray(self, time, sample1, sample2, sample3, active):
        # direction of travel of the emitted ray
        d = -mi.warp.square_to_uniform_sphere(sample3)
        disk = mi.warp.square_to_uniform_disk_concentric(sample2) * self.radius
        frame = mi.Frame3f(d)
        origin = (mi.Point3f(self.center) - d * self.radius
                  + frame.s * disk.x + frame.t * disk.y)
        ray = mi.Ray3f(origin, d, time)

        si = dr.zeros(mi.SurfaceInteraction3f)
        power = self._radiance(si, active) * (4.0 * dr.pi) * (dr.pi * self.radius ** 2)
        return ray, dr.select(active, power, 0.0)

    def sample_wavelengths(self, si, sample, active):
        # RGB variants: no wavelengths to draw, the weight is the radiance itself
        return mi.Color0f(), dr.select(active, self._radiance(si, active), 0.0)

    def sample_position(self, time, sample, active):
        # An environment has no surface to sample; the particle tracer still asks
        # (and Mitsuba's own ``constant`` answers with an empty, zero-pdf sample).
        ps = dr.zeros(mi.PositionSample3f)
        ps.time = time
        return ps, mi.Float(0.0)

    def pdf_position(self, ps, active):
        return mi.Float(0.0)

    def traverse(self, callback):
        callback.put('radiance', self.radiance, mi.ParamFlags.Differentiable)

    def to_string(self):
        return (f'PyConstantEnv[radiance={self.radiance}, radius={self.radius}, '
                f'center={self.center}]')


mi.register_emitter('py_constant_env', lambda props: PyConstantEnv(props))
