"""Mitsuba 3.9.1 fresnel_conductor: d/d eta is 0 at eta = 0, the default of roughconductor.

roughconductor's default material "none" is eta = 0, k = 1 (src/bsdfs/roughconductor.cpp:
166-167).  include/mitsuba/render/fresnel.h:103-104 computes
a = safe_sqrt(0.5 (sqrt(t^2 + 4 k^2 eta^2) + t)), t = eta^2 - k^2 - sin^2; for small eta the
argument is k^2 eta^2 / |t|, so a = k eta / sqrt(|t|) and R(eta) is smooth with a finite,
non-zero slope -- but AD differentiates safe_sqrt at 0 as 0, so d eval / d eta = 0 exactly at
eta = 0 while it is finite for eta = 1e-3.  (The float32 sum sqrt(...) + t also cancels, which
makes finite differences at eta ~ 1e-3 noisy.)

Run: python tests/repro/conductor_eta0_gradient.py  -> exit 1 while the bug is present.
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
bsdf = mi.load_dict({"type": "roughconductor", "alpha": 0.3})
params = mi.traverse(bsdf)
si = dr.zeros(mi.SurfaceInteraction3f, 1)
si.sh_frame = mi.Frame3f(mi.Vector3f(0, 0, 1))
si.wi = dr.normalize(mi.Vector3f(0.6, 0.0, 0.8))
wo = dr.normalize(mi.Vector3f(-0.5, 0.1, 0.85))


def ad(eta):
    params["eta.value"] = eta
    x = params["eta.value"]
    dr.enable_grad(x)
    params.update()
    v = bsdf.eval(mi.BSDFContext(), si, wo).x
    dr.forward(x)
    g = float(dr.grad(v)[0])
    dr.disable_grad(x)
    return g


grads = {eta: ad(eta) for eta in (0.0, 1e-3, 2e-3)}
print("d eval / d eta by AD:", ", ".join(f"eta={k:g}: {v:.5g}" for k, v in grads.items()))
sys.exit(1 if grads[0.0] == 0.0 and grads[1e-3] != 0.0 else 0)
