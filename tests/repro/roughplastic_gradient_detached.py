"""Mitsuba 3.9.1 roughplastic: d eval / d alpha and d eval / d eta miss the precomputed tables.

src/bsdfs/roughplastic.cpp:235 (parameters_changed) takes ``dr::slice(m_eta)`` and
``dr::slice(m_alpha)`` as plain scalars to precompute the rough transmittance table
m_external_transmittance and m_internal_reflectance (lines 232-251), which eval() uses for the
diffuse term (t_i, t_o, line 354-361).  Both parameters are exposed as Differentiable
(lines 210-211), but automatic differentiation only sees their explicit use in the specular
term: the derivative through the tables is lost.  A central finite difference (which calls
parameters_changed() and rebuilds the tables) disagrees with forward-mode AD.

Run: python tests/repro/roughplastic_gradient_detached.py  -> exit 1 while the bug is present.
"""
import sys

try:                                   # phonglab pins a libLLVM that Dr.Jit can use
    import phonglab.runtime
    phonglab.runtime.configure()
except ImportError:
    pass
import drjit as dr
import mitsuba as mi

mi.set_variant("llvm_ad_rgb")
bsdf = mi.load_dict({"type": "roughplastic", "alpha": 0.25, "diffuse_reflectance": 0.5})
params = mi.traverse(bsdf)
si = dr.zeros(mi.SurfaceInteraction3f, 1)
si.sh_frame = mi.Frame3f(mi.Vector3f(0, 0, 1))
si.wi = dr.normalize(mi.Vector3f(0.6, 0.0, 0.8))
wo = dr.normalize(mi.Vector3f(-0.3, 0.4, 0.866))      # off the specular peak: diffuse dominates


def value():
    return float(bsdf.eval(mi.BSDFContext(), si, wo).x[0])


bad = False
for key, h in (("alpha", 1e-3), ("eta", 5e-3)):
    x0 = float(params[key][0])
    dr.enable_grad(params[key])
    params.update()
    v = bsdf.eval(mi.BSDFContext(), si, wo).x
    dr.forward(params[key])
    ad = float(dr.grad(v)[0])
    dr.disable_grad(params[key])
    params[key] = x0 + h
    params.update()
    up = value()
    params[key] = x0 - h
    params.update()
    down = value()
    params[key] = x0
    params.update()
    fd = (up - down) / (2 * h)
    print(f"d eval / d {key}: AD {ad:.6g}, central difference {fd:.6g}")
    bad |= abs(ad - fd) > 0.05 * abs(fd)
sys.exit(1 if bad else 0)
