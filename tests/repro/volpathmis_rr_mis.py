"""Mitsuba 3.9.1 volpathmis: Russian roulette is left out of the NEE density of the MIS weight
of emitters hit by BSDF- or phase-sampled rays, in the iterations where roulette runs.

src/integrators/volpathmis.cpp (commit 478e193a): in an iteration with depth > rr_depth
(line 238) a surviving path's p_over_f (its pdf/f) is multiplied by the survival probability q
(lines 239-240), but p_over_f_nee, the NEE strategy's pdf/f of the same path, was copied from
p_over_f at the last real scattering (line 437; line 339 in a medium) and is not updated; an
emitter hit by a BSDF-sampled ray adds emitted / (p_over_f + p_over_f_nee) (lines 393-397,
mis_weight at 657-671), i.e. f / (q p_bsdf + p_nee) where the balance heuristic after roulette
needs f / (q (p_bsdf + p_nee)).  With q < 1 those hits are under-weighted; next-event estimation
keeps p_nee / (p_nee + p_bsdf) (lines 410-415), hits by camera rays and specular chains take
mis_weight(p_over_f) alone (count_direct, line 384), and iterations up to rr_depth are not
affected.  This script's scene, a closed emitting box of albedo 0.8 (Le = 2, max_depth 64,
every pixel sees exactly 10), reads 9.79 with the default rr_depth 5 and 9.67 with rr_depth 1;
10.000 with roulette off (rr_depth 1000) and in volpath.  An emitter hit is handled in an
iteration only while depth < max_depth (line 244), so the bias needs an iteration with
rr_depth < depth <= max_depth - 1, i.e. rr_depth <= max_depth - 2: the script also renders the
enclosure of albedo 0.5 at max_depth 3 and 5 with rr_depth max_depth - 2 (biased) and
max_depth - 1 (exact).

Run: python tests/repro/volpathmis_rr_mis.py  -> exit 1 while the behaviour is present.
"""
import sys

try:                                   # phonglab pins a libLLVM that Dr.Jit can use
    import phonglab.runtime
    phonglab.runtime.configure()
except ImportError:
    pass
import mitsuba as mi
import numpy as np

mi.set_variant("llvm_ad_rgb")


def enclosure(rho):
    """A closed emitting box of albedo rho (Le = 2): every pixel sees Le (1 - rho^D)/(1 - rho)
    at max_depth D."""
    return mi.load_dict({
        "type": "scene",
        "box": {"type": "cube", "flip_normals": True,
                "bsdf": {"type": "diffuse", "reflectance": rho},
                "emitter": {"type": "area", "radiance": 2.0}},
        "sensor": {"type": "perspective", "fov": 60,
                   "film": {"type": "hdrfilm", "width": 16, "height": 16,
                            "rfilter": {"type": "box"}},
                   "sampler": {"type": "independent", "sample_count": 64}}})


def image_mean(scene, max_depth, rr_depth):
    """The image mean over 8 seeds and its standard error."""
    integ = mi.load_dict({"type": "volpathmis", "max_depth": max_depth, "rr_depth": rr_depth})
    m = [float(np.mean(mi.render(scene, integrator=integ, seed=s))) for s in range(8)]
    return np.mean(m), np.std(m, ddof=1) / np.sqrt(len(m))


scene = enclosure(0.8)
res = {}
for rr in (1, 1000):
    res[rr] = image_mean(scene, 64, rr)
    print(f"rr_depth {rr:4d}: {res[rr][0]:.4f} ± {res[rr][1]:.4f} (exact 10)")
# roulette runs in the iterations with depth > rr_depth, and an iteration's emitter hit counts
# only while depth < max_depth: the bias needs rr_depth <= max_depth - 2
shallow = enclosure(0.5)
for depth, exact in ((3, 3.5), (5, 3.875)):
    reads = [(rr, *image_mean(shallow, depth, rr)) for rr in (depth - 2, depth - 1)]
    print(f"enclosure rho 0.5, max_depth {depth} (exact {exact}): "
          + ", ".join(f"rr_depth {rr} {m:.4f} ± {e:.4f} ({(m - exact) / e:+.1f} s.e.)"
                      for rr, m, e in reads))
z = (10.0 - res[1][0]) / res[1][1]
present = z > 5 and abs(res[1000][0] - 10.0) < 5 * res[1000][1] + 1e-3
print(f"roulette on: {z:.1f} standard errors below 10 -- "
      + ("behaviour present" if present else "fixed"))
sys.exit(1 if present else 0)
