"""Mitsuba 3.9.1 roughdielectric at nearly matched indices (eta = int_ior/ext_ior close to 1):
the directional albedo of eval exceeds 1.

As eta -> 1 every microfacet refracts wi to nearly -wi: the transmission lobe narrows to a
width of about alpha |eta - 1| and Fresnel reflection vanishes, so the albedo tends to
G1(wi) G1(-wi) / G1_exact(wi) = G1(wi)^2 / G1_exact(wi) (the visible-normal integral
of D |wi.m| is cos theta_i / G1_exact) and no loss is left to hide an error in it:

* Beckmann: smith_g1() is Walter et al.'s rational approximation, 1 for a >= 1.6
  (include/mitsuba/render/microfacet.h:346-352), above the exact Smith G1 there: the albedo
  is G1_approx^2 / G1_exact > 1 (alpha 1, 31.8 deg: 1 / 0.9984 = 1.0016);
* any distribution: the half vector normalize(wi + wo * eta) (src/bsdfs/roughdielectric.cpp:381)
  rounds the product wo * eta to float32; for wo ~ -wi the sum then cancels (exactly) and
  leaves that rounding divided by |eta - 1|, nearly the same across the narrow lobe, so eval
  there is off (up to 1.6 % pointwise for GGX alpha 0.01 at eta 0.99972) and its integral
  lands above or below the model's by up to ~1e-3 (Beckmann alpha 0.1, 31.8 deg: 1.00056;
  GGX alpha 0.01, 60 deg: 1.00076; the float64 model: 1.00000 and 0.99992).  The float64
  model with only wo * eta rounded to float32 (``round_product``) gives Mitsuba's albedo; the
  float32 denominator (wi.m + eta wo.m)^2 (line 425) adds nothing measurable.  pdf() has the
  same product (line 458): tests/repro/roughdielectric_index_matched_normalization.py.

The plugin refuses int_ior == ext_ior exactly (roughdielectric.cpp:178) but not int_ior 1
against its default ext_ior, air (1.000277): eta = 0.99972, a corner of phonglab's sweep.

This script integrates eval (TransportMode.Importance, cosine included) over a polar grid about
the refracted and the mirror directions, and the same integral of Walter et al.'s model
(EGSR 2007, eqs. 20-21, 27, 33-34) in float64, with the approximate and with the exact
Beckmann G1; the model reproduces Mitsuba where it is well conditioned (GGX alpha 0.3,
eta 1.5).

Run: python tests/repro/roughdielectric_index_matched_energy.py  -> exit 1 while present.
(tests/test_validate_energy.py imports albedo() and mitsuba_eval() as the fine reference of the
energy topic's quadrature.)
"""
import math
import sys

try:                                   # phonglab pins a libLLVM that Dr.Jit can use
    import phonglab.runtime
    phonglab.runtime.configure()
except ImportError:
    pass
import drjit as dr
import mitsuba as mi
import numpy as np
from scipy.special import erf

mi.set_variant("llvm_ad_rgb")
AIR = 1.000277


def mitsuba_eval(bsdf, wi, wo):
    n = len(wo)
    si = dr.zeros(mi.SurfaceInteraction3f, n)
    si.wi = mi.Vector3f(*(mi.Float(np.full(n, wi[k], np.float32)) for k in range(3)))
    si.sh_frame = mi.Frame3f(mi.Vector3f(0, 0, 1))
    wo32 = mi.Vector3f(*(mi.Float(np.ascontiguousarray(wo[:, k], np.float32)) for k in range(3)))
    value = bsdf.eval(mi.BSDFContext(mi.TransportMode.Importance), si, wo32)
    return np.array(value, np.float64).mean(axis=0)


def walter(dist, alpha, eta, wi, wo, exact_g1=True, round_product=False):
    """f cos theta_o of a rough dielectric in float64 (Walter et al. 2007), Importance mode;
    ``round_product``: the half vector's product wo * eta rounded to float32, as Mitsuba's."""
    wi = np.broadcast_to(wi, wo.shape)
    refl = wo[:, 2] > 0
    ew = wo * np.where(refl, 1.0, eta)[:, None]
    if round_product:
        ew = np.where(refl[:, None], ew, ew.astype(np.float32).astype(np.float64))
    m = wi + ew
    m /= np.linalg.norm(m, axis=1)[:, None]
    m *= np.sign(m[:, 2])[:, None]
    cos2 = m[:, 2] ** 2
    tan2 = (1 - cos2) / cos2
    if dist == "ggx":
        D = 1 / (math.pi * alpha ** 2 * cos2 ** 2 * (1 + tan2 / alpha ** 2) ** 2)
    else:
        D = np.exp(-tan2 / alpha ** 2) / (math.pi * alpha ** 2 * cos2 ** 2)

    def g1(v):
        tan_v = np.sqrt(np.clip(1 - v[:, 2] ** 2, 0, None)) / np.abs(v[:, 2])
        if dist == "ggx":
            g = 2 / (1 + np.sqrt(1 + (alpha * tan_v) ** 2))
        else:
            a = 1 / np.maximum(alpha * tan_v, 1e-300)
            g = (2 / (1 + erf(a) + np.exp(-a * a) / (a * math.sqrt(math.pi))) if exact_g1 else
                 np.where(a >= 1.6, 1.0, (3.535 * a + 2.181 * a * a) / (1 + 2.276 * a + 2.577 * a * a)))
        return np.where(np.sum(v * m, axis=1) * v[:, 2] > 0, g, 0.0)

    wim, wom = np.sum(wi * m, axis=1), np.sum(wo * m, axis=1)
    sin_t2 = (1 - wim ** 2) / eta ** 2
    cos_t = np.sqrt(np.clip(1 - sin_t2, 0, None))
    rs = (wim - eta * cos_t) / (wim + eta * cos_t)
    rp = (eta * wim - cos_t) / (eta * wim + cos_t)
    F = np.where(sin_t2 >= 1, 1.0, 0.5 * (rs ** 2 + rp ** 2))
    G = g1(wi) * g1(wo)
    fr = F * D * G / (4 * wi[:, 2])
    ft = np.abs((1 - F) * D * G * eta ** 2 * wim * wom / (wi[:, 2] * (wim + eta * wom) ** 2))
    out = np.where(refl, fr, ft)
    return np.where(np.isfinite(out), out, 0.0) if round_product else out


def albedo(f, wi, eta, nr=1500, npsi=256):
    """int f dw_o: polar grids about the refracted (lower hemisphere) and the mirror direction
    (upper), log-spaced in the angle from 1e-9 rad to pi; directions rounded to float32."""
    cos_t = math.sqrt(max(0.0, 1 - (1 - wi[2] ** 2) / eta ** 2))
    refracted = -wi / eta + (wi[2] / eta - cos_t) * np.array([0.0, 0.0, 1.0])
    mirror = np.array([-wi[0], -wi[1], wi[2]])
    u = np.linspace(math.log(1e-9), math.log(math.pi), nr)
    r = np.exp(u)
    psi = (np.arange(npsi) + 0.5) * 2 * math.pi / npsi
    R, P = np.meshgrid(r, psi, indexing="ij")
    weight = (np.sin(R) * R).ravel() * (u[1] - u[0]) * 2 * math.pi / npsi
    total = 0.0
    for centre, side in ((refracted, -1.0), (mirror, 1.0)):
        c = centre / np.linalg.norm(centre)
        s = np.cross(c, [0.0, 1.0, 0.0] if abs(c[1]) < 0.9 else [1.0, 0.0, 0.0])
        s /= np.linalg.norm(s)
        t = np.cross(c, s)
        d = (np.cos(R)[..., None] * c + np.sin(R)[..., None]
             * (np.cos(P)[..., None] * s + np.sin(P)[..., None] * t)).reshape(-1, 3)
        d = d.astype(np.float32).astype(np.float64)
        keep = np.sign(d[:, 2]) == side
        total += float(np.sum(f(d[keep]) * weight[keep]))
    return total


def main() -> int:
    present = False
    for dist, alpha, int_ior, ext_ior, theta in (("ggx", 0.3, 1.5, AIR, 31.8),
                                                 ("beckmann", 1.0, 1.001, 1.0, 31.8),
                                                 ("beckmann", 0.1, 1.0, AIR, 31.8),
                                                 ("ggx", 0.01, 1.0, AIR, 60.0)):
        eta = float(np.float32(int_ior) / np.float32(ext_ior))     # as the plugin stores it
        bsdf = mi.load_dict({"type": "roughdielectric", "distribution": dist, "alpha": alpha,
                             "int_ior": int_ior, "ext_ior": ext_ior})
        wi = np.array([math.sin(math.radians(theta)), 0.0, math.cos(math.radians(theta))])
        a_mi = albedo(lambda d: mitsuba_eval(bsdf, wi, d), wi, eta)
        a_exact = albedo(lambda d: walter(dist, alpha, eta, wi, d), wi, eta)
        line = (f"{dist:8s} alpha {alpha:<4g} eta {eta:.5f} theta_i {theta:4.1f} deg: albedo of "
                f"Mitsuba's eval {a_mi:.6f}, float64 model {a_exact:.6f}")
        if dist == "beckmann":
            line += f" (with the approximate G1 {albedo(lambda d: walter(dist, alpha, eta, wi, d, False), wi, eta):.6f})"
        if abs(eta - 1) < 0.001:         # the float32 product wo * eta alone (line 381)
            product = albedo(lambda d: walter(dist, alpha, eta, wi, d, dist == "ggx", True),
                             wi, eta)
            line += f"; float64 model with float32(wo * eta) {product:.6f}"
        print(line)
        present |= abs(eta - 1) < 0.01 and a_mi > 1 + 1e-4 and a_exact <= 1 + 1e-5
    print("behaviour present: albedo above 1 near eta = 1" if present else "fixed")
    return 1 if present else 0


if __name__ == "__main__":
    sys.exit(main())
