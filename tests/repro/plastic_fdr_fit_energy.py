"""Mitsuba 3.9.1 plastic reflects more than it receives at int_ior = 3 (albedo 1.185).

plastic's diffuse term is ρ/(1 − F_dr,int) · (1 − F_i)(1 − F_o)/η² · cos θ_o/π
(src/bsdfs/plastic.cpp:290-294), with m_fdr_int = fresnel_diffuse_reflectance(1/η) (:196).
Energy is conserved for ρ = 1 exactly when η²(1 − F_dr(1/η)) = 1 − F_dr(η), which holds
for the exact diffuse Fresnel reflectance.  fresnel_diffuse_reflectance()
(include/mitsuba/render/fresnel.h:341-343) evaluates F_dr(1/η) with the Egan and
Hilgeman (1973) fit, whose own comment gives a 9.5 % maximum relative error for η in [2, 5].
At η = 3 the fit gives F_dr(1/3) = 0.9355, where the exact integral is 0.9196.  So
1/(1 − F_dr,int) is 25 % too large, and the albedo at normal incidence is 1.185 (F_i = 0.25
plus 0.935 diffuse).  At η = 2.5 the excess is 4 %; at η ≤ 2 it is under 0.15 %.  A render of a white
plastic sphere at int_ior 3 under a constant environment is brighter than the environment.

Run: python tests/repro/plastic_fdr_fit_energy.py  -> exit 1 while the behaviour is present.
"""
import sys

try:                                   # phonglab pins a libLLVM that Dr.Jit can use
    import phonglab.runtime
    phonglab.runtime.configure()
except ImportError:
    pass
import drjit as dr
import mitsuba as mi
import numpy as np

mi.set_variant("llvm_ad_rgb")
mu, w = np.polynomial.legendre.leggauss(2000)
mu, w = 0.5 * (mu + 1), 0.5 * w


def fdr_exact(eta):
    """F_dr(η) = 2 ∫ F(μ, η) μ dμ by Gauss-Legendre (2000 nodes)."""
    return float(np.sum(w * np.array(mi.fresnel(mi.Float(mu), mi.Float(eta))[0]) * 2 * mu))


eta = 3.0
fit = float(mi.fresnel_diffuse_reflectance(mi.Float(1 / eta))[0])
print(f"F_dr(1/{eta:g}): fit {fit:.4f}, exact {fdr_exact(1 / eta):.4f}")
bsdf = mi.load_dict({"type": "plastic", "int_ior": eta, "diffuse_reflectance": 1.0,
                     "specular_reflectance": 1.0})
# albedo at normal incidence: the delta coat's F_i plus ∫ eval dω_o (eval includes cos θ_o)
si = dr.zeros(mi.SurfaceInteraction3f, 1)
si.sh_frame = mi.Frame3f(mi.Vector3f(0, 0, 1))
si.wi = mi.Vector3f(0, 0, 1)
n = 512
ct, wt = np.polynomial.legendre.leggauss(n)
ct, wt = 0.5 * (ct + 1), 0.5 * wt          # cos θ_o on (0, 1); eval is azimuth-independent
st = np.sqrt(1 - ct * ct)
si_n = dr.zeros(mi.SurfaceInteraction3f, n)
si_n.sh_frame = mi.Frame3f(mi.Vector3f(0, 0, 1))
si_n.wi = mi.Vector3f(0, 0, 1)
wo = mi.Vector3f(mi.Float(st), 0, mi.Float(ct))
diffuse = 2 * np.pi * float(np.sum(wt * np.array(bsdf.eval(mi.BSDFContext(), si_n, wo).x)))
f_i = float(mi.fresnel(mi.Float(1.0), mi.Float(eta))[0][0])
albedo = f_i + diffuse
print(f"plastic int_ior {eta:g}, reflectances 1: albedo at normal incidence {albedo:.4f} "
      f"(specular {f_i:.4f} + diffuse {diffuse:.4f}); a passive surface reflects <= 1")
sys.exit(1 if albedo > 1.001 else 0)
