"""Mitsuba 3.9.1 principled: AD at a weight's range ends differentiates the switched-off lobe.

src/bsdfs/principled.cpp:558-572 activates lobes with strict inequalities on their weights:
clearcoat_active needs clearcoat > 0 (line 559), spec_trans_active bsdf > 0 (line 563),
diffuse_active brdf = (1 - metallic)(1 - spec_trans) > 0 (line 568), sheen_active sheen > 0 and
1 - metallic > 0 (lines 571-572).  At exactly 0 (clearcoat, sheen and spec_trans default to 0)
or at metallic = 1 the lobe is masked out, so automatic differentiation returns the derivative
of the model WITHOUT that lobe: d eval / d clearcoat = 0 at clearcoat = 0 although the
right-hand derivative (the only one inside [0, 1]) is the clearcoat lobe itself, and at
metallic = 1 AD gives the derivative from outside the range (metallic > 1), not from inside.
principledthin.cpp:458-467 does the same with spec_trans > 0 and diff_trans > 0.

Run: python tests/repro/principled_gradient_lobe_masks.py  -> exit 1 while the bug is present.
"""
import sys

import numpy as np

try:                                   # phonglab pins a libLLVM that Dr.Jit can use
    import phonglab.runtime
    phonglab.runtime.configure()
except ImportError:
    pass
import drjit as dr
import mitsuba as mi

mi.set_variant("llvm_ad_rgb")
n = 256
rng = np.random.default_rng(0)


def directions():
    mu, phi = rng.random(n), 2 * np.pi * rng.random(n)
    s = np.sqrt(1 - mu * mu)
    return mi.Vector3f(s * np.cos(phi), s * np.sin(phi), mu)


si = dr.zeros(mi.SurfaceInteraction3f, n)
si.sh_frame = mi.Frame3f(mi.Vector3f(0, 0, 1))
si.wi = directions()
wo = directions()


def total(bsdf):
    return float(np.sum(np.array(bsdf.eval(mi.BSDFContext(), si, wo).x)))


def check(spec, key, x0, side):
    bsdf = mi.load_dict(spec)
    params = mi.traverse(bsdf)
    x = params[key]
    dr.enable_grad(x)
    params.update()
    v = bsdf.eval(mi.BSDFContext(), si, wo).x
    dr.forward(x)
    ad = float(np.sum(np.array(dr.grad(v))))
    dr.disable_grad(x)
    h = 1e-3
    params[key] = x0
    params.update()
    f0 = total(bsdf)
    params[key] = x0 + side * h
    params.update()
    fd = (total(bsdf) - f0) / (side * h)
    inside = "right" if side > 0 else "left"
    print(f"{spec['type']} {key} = {x0}: AD {ad:.5g}, {inside}-hand difference (inside [0, 1]) "
          f"{fd:.5g}")
    return abs(ad - fd) > 0.05 * abs(fd)


bad = check({"type": "principled"}, "clearcoat.value", 0.0, +1)
bad |= check({"type": "principled", "metallic": 1.0, "roughness": 0.2}, "metallic.value", 1.0, -1)
sys.exit(1 if bad else 0)
