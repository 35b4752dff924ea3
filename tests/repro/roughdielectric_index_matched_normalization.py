"""Mitsuba 3.9.1 roughdielectric at nearly matched indices (eta = int_ior/ext_ior close to 1):
pdf() does not integrate to the probability that sample() returns a direction.

pdf() forms the half vector of a transmitted wo as m = normalize(wi + wo * eta)
(src/bsdfs/roughdielectric.cpp:458; eval() alike at line 381).  For wo in the refracted lobe
wo ~ -wi, so the sum cancels: it is exact in float32 (Sterbenz), but the float32 product
wo * eta is rounded, by up to 2^-25 |wo| per component, and that error is divided by
|wi + eta wo| ~ |eta - 1|, so m is off by ~2^-25 / |eta - 1| rad (2e-4 rad at eta 0.99972).
The error does not average out over the lobe: stepping wo by one float32 spacing moves
wo * eta by eta spacings, so its rounding error drifts by only |1 - eta| of a spacing per
step and stays nearly constant across the lobe (about alpha |eta - 1| wide, a few hundred
spacings): the density is evaluated at a consistently displaced half vector, and its
integral misses 1 by up to ~1e-3.

This script integrates Mitsuba's pdf (llvm_ad_rgb) over the sphere by stratified jittered
polar grids about the refracted and the mirror directions (log-spaced in the angle from 1e-10
rad to pi, replicas -> mean and standard error), and the same integral of the visible-normal
pdf of Walter et al. / Heitz (float64, at the same float32 directions), once in float64 and
once with only the product wo * eta rounded to float32: the latter reproduces Mitsuba, the
former gives 1, as does a float32 fused multiply-add of wi + wo * eta (one rounding of the
small result, the fix).  It also counts sample(): every sample is valid.  Control: eta 1.5,
where all agree; and Beckmann, whose pdf has the same product.

The plugin refuses int_ior == ext_ior exactly (roughdielectric.cpp:178) but not int_ior 1
against its default ext_ior, air (1.000277): eta = 0.99972, a corner of phonglab's sweep.

Run: python tests/repro/roughdielectric_index_matched_normalization.py  -> exit 1 while present.
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

mi.set_variant("llvm_ad_rgb")
AIR = 1.000277


def f32(x):
    return np.asarray(x, np.float32).astype(np.float64)


def _si(wi, n):
    si = dr.zeros(mi.SurfaceInteraction3f, n)
    si.wi = mi.Vector3f(*(mi.Float(np.full(n, wi[k], np.float32)) for k in range(3)))
    si.sh_frame = mi.Frame3f(mi.Vector3f(0, 0, 1))
    return si


def mitsuba_pdf(bsdf, wi, wo):
    wo32 = mi.Vector3f(*(mi.Float(np.ascontiguousarray(wo[:, k], np.float32)) for k in range(3)))
    return np.array(bsdf.pdf(mi.BSDFContext(), _si(wi, len(wo)), wo32), np.float64)


def counted(bsdf, wi, n=1 << 20, seed=0):
    """Fraction of n samples with weight != 0 (every sample here is a glossy one)."""
    rng = np.random.default_rng(seed)
    u1, u2 = rng.random(n), rng.random((n, 2))
    _, weight = bsdf.sample(mi.BSDFContext(), _si(wi, n), mi.Float(u1.astype(np.float32)),
                            mi.Point2f(*(mi.Float(u2[:, k].astype(np.float32)) for k in range(2))))
    return float(np.mean(np.any(np.array(weight) != 0, axis=0)))


def model_pdf(alpha, eta, wi, wo, round_product=False, dist="ggx", fused=False):
    """Visible-normal pdf of a rough dielectric (sample_visible, wi above the surface), float64;
    Beckmann with Mitsuba's rational smith_g1 (microfacet.h:346-352); ``round_product``: the
    product wo * eta rounded to float32 as Mitsuba's Vector3f * Float does, nothing else;
    ``fused``: instead the sum wi + wo * eta rounded once to float32 (a fused multiply-add, the
    fix: the float32 product of float32 numbers is exact in float64)."""
    wi = np.broadcast_to(wi, wo.shape)
    refl = wo[:, 2] * wi[:, 2] > 0
    ew = wo * np.where(refl, 1.0, eta)[:, None]
    if round_product:
        ew = np.where(refl[:, None], ew, f32(ew))
    h = wi + ew
    if fused:
        h = np.where(refl[:, None], h, f32(h))
    with np.errstate(all="ignore"):
        m = h / np.linalg.norm(h, axis=1)[:, None]
        m *= np.sign(m[:, 2])[:, None]
        wim, wom = np.sum(wi * m, axis=1), np.sum(wo * m, axis=1)
        ok = (wim * wi[:, 2] > 0) & (wom * wo[:, 2] > 0)
        cos2 = m[:, 2] ** 2
        tan2 = (1 - cos2) / cos2
        ct = wi[:, 2]
        tan_i = math.sqrt(max(0.0, 1 - ct[0] ** 2)) / abs(ct[0])
        if dist == "ggx":
            D = 1 / (math.pi * alpha ** 2 * cos2 ** 2 * (1 + tan2 / alpha ** 2) ** 2)
            g1 = 2 / (1 + math.sqrt(1 + (alpha * tan_i) ** 2))
        else:
            D = np.exp(-tan2 / alpha ** 2) / (math.pi * alpha ** 2 * cos2 ** 2)
            a = 1 / max(alpha * tan_i, 1e-300)
            g1 = 1.0 if a >= 1.6 else (3.535 * a + 2.181 * a * a) / (1 + 2.276 * a + 2.577 * a * a)
        sin_t2 = (1 - wim * wim) / eta ** 2
        cos_t = np.sqrt(np.clip(1 - sin_t2, 0, None))
        rs = (wim - eta * cos_t) / (wim + eta * cos_t)
        rp = (eta * wim - cos_t) / (eta * wim + cos_t)
        F = np.where(sin_t2 >= 1, 1.0, 0.5 * (rs ** 2 + rp ** 2))
        jac = np.where(refl, 1 / (4 * wom), eta * eta * wom / (wim + eta * wom) ** 2)
        p = g1 * np.abs(wim) * D / np.abs(ct) * np.where(refl, F, 1 - F) * np.abs(jac)
    return np.where(ok & np.isfinite(p), p, 0.0)


def integral(pdf, wi, eta, nr=1200, npsi=256, reps=6, seed=1):
    """int pdf dw_o over the sphere (mean, standard error over ``reps`` jittered replicas):
    polar grids about the refracted (lower hemisphere) and the mirror direction (upper),
    log-spaced in the angle from 1e-10 rad to pi, one uniform point per cell; the directions
    are rounded to float32 before any pdf sees them."""
    cos_t = math.sqrt(max(0.0, 1 - (1 - wi[2] ** 2) / eta ** 2))
    refracted = -wi / eta + (wi[2] / eta - cos_t) * np.array([0.0, 0.0, 1.0])
    mirror = np.array([-wi[0], -wi[1], wi[2]])
    rng = np.random.default_rng(seed)
    lo = math.log(1e-10)
    du, dp = (math.log(math.pi) - lo) / nr, 2 * math.pi / npsi
    iu, ip = np.meshgrid(np.arange(nr), np.arange(npsi), indexing="ij")
    out = []
    for _ in range(reps):
        total = 0.0
        for centre, side in ((refracted, -1.0), (mirror, 1.0)):
            c = centre / np.linalg.norm(centre)
            s = np.cross(c, [0.0, 1.0, 0.0] if abs(c[1]) < 0.9 else [1.0, 0.0, 0.0])
            s /= np.linalg.norm(s)
            t = np.cross(c, s)
            r = np.exp(lo + (iu + rng.random(iu.shape)) * du).ravel()
            psi = ((ip + rng.random(ip.shape)) * dp).ravel()
            d = (np.cos(r)[:, None] * c + np.sin(r)[:, None]
                 * (np.cos(psi)[:, None] * s + np.sin(psi)[:, None] * t))
            d = f32(d)
            keep = (np.sign(d[:, 2]) == side) & (r <= math.pi)
            total += float(np.sum(pdf(d[keep]) * (np.sin(r) * r)[keep]) * du * dp)
        out.append(total)
    out = np.array(out)
    return out.mean(), out.std(ddof=1) / math.sqrt(reps)


def main() -> int:
    present = False
    # phonglab's normalization cells: cos theta_i 0.7 (45.6 deg) and 0.3 (72.5 deg)
    for dist, alpha, int_ior, cos, phi in (("ggx", 0.1, 1.5, 0.7, 0.0),        # control
                                           ("ggx", 0.1, 1.0, 0.7, 0.0),
                                           ("ggx", 0.1, 1.0, 0.7, 2.1),
                                           ("ggx", 0.01, 1.0, 0.3, 2.1),
                                           ("ggx", 0.01, 1.0, 0.5, 0.0),
                                           ("ggx", 1.0, 1.000577, 1.0, 0.0),    # eta 1.0003
                                           ("beckmann", 0.1, 1.0, 0.7, 0.0)):
        eta = float(np.float32(int_ior) / np.float32(AIR))       # as the plugin stores it
        bsdf = mi.load_dict({"type": "roughdielectric", "distribution": dist, "alpha": alpha,
                             "int_ior": int_ior})
        t, p = math.acos(cos), phi
        wi = f32([math.sin(t) * math.cos(p), math.sin(t) * math.sin(p), math.cos(t)])
        q_mi, e_mi = integral(lambda d: mitsuba_pdf(bsdf, wi, d), wi, eta)
        q_64, e_64 = integral(lambda d: model_pdf(alpha, eta, wi, d, False, dist), wi, eta)
        q_pr, e_pr = integral(lambda d: model_pdf(alpha, eta, wi, d, True, dist), wi, eta)
        q_fm, e_fm = integral(lambda d: model_pdf(alpha, eta, wi, d, False, dist, True), wi, eta)
        n = counted(bsdf, wi)
        print(f"{dist:8s} alpha {alpha:<4g} eta {eta:.5f} theta_i {math.degrees(t):5.2f} deg "
              f"phi {phi}: int pdf: Mitsuba {q_mi:.6f} +- {e_mi:.1e}, model float64 {q_64:.6f} +- "
              f"{e_64:.1e}, model with float32(wo * eta) {q_pr:.6f} +- {e_pr:.1e}, with "
              f"float32(wi + wo * eta) {q_fm:.6f} +- {e_fm:.1e}; "
              f"samples counted {n:.6f}")
        present |= (abs(eta - 1) < 0.01 and abs(q_mi - q_64) > max(1e-4, 6 * math.hypot(e_mi, e_64))
                    and abs(q_64 - n) < 1e-4)
    print("behaviour present: int pdf != share of counted samples near eta = 1" if present
          else "fixed")
    return 1 if present else 0


if __name__ == "__main__":
    sys.exit(main())
