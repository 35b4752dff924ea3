"""Mitsuba 3.9.1 heterogeneous: σ_t > 0 outside the bounds the medium reports.

src/media/heterogeneous.cpp (commit 478e193a) line 200: ``intersect_aabb`` returns the σ_t
volume's bounding box (the unit cube by default, include/mitsuba/render/volume.h:99-107), and
``Medium::sample_interaction`` (src/render/medium.cpp:53-60) never samples a collision outside
it; but a constvolume (heterogeneous's default σ_t) has its value everywhere, and a
gridvolume's default wrap mode is ``clamp`` (src/volumes/grid.cpp:175), so
``get_scattering_coefficients`` returns σ_t > 0 at points outside the box.  The medium rendered
is the volume cut at its box (by design: a heterogeneous medium is meant to fill a shape that
encloses its box), not the σ_t the medium itself reports there.

Run: python tests/repro/heterogeneous_volume_outside_bounds.py  -> exit 1 while the
behaviour is present (for both volumes).
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
grid = mi.VolumeGrid(np.full((4, 4, 4, 1), 2.0, np.float32))
ray = mi.Ray3f(mi.Point3f(1.5, 0.5, 0.5), mi.Vector3f(1.0, 0.0, 0.0))   # outside, going away
present = []
for what, spec in (("constvolume (default)", {"type": "heterogeneous"}),
                   ("gridvolume", {"type": "heterogeneous",
                                   "sigma_t": {"type": "gridvolume", "grid": grid}})):
    medium = mi.load_dict(spec)
    hit, mint, maxt = medium.intersect_aabb(ray)
    mei = dr.zeros(mi.MediumInteraction3f, 1)
    mei.p = ray.o
    mei.wi = -ray.d
    mei.sh_frame = mi.Frame3f(mei.wi)
    sigma_s, sigma_n, sigma_t = medium.get_scattering_coefficients(mei, mi.Bool(True))
    st = float(np.array(sigma_t)[0, 0])
    entered = bool(np.array(hit)[0]) and float(np.array(maxt)[0]) > 0
    print(f"{what}: at p = (1.5, 0.5, 0.5), outside the unit cube, sigma_t = {st}; the ray "
          f"from there {'meets' if entered else 'does not meet'} the bounds")
    present.append(st > 0 and not entered)
sys.exit(1 if all(present) else 0)
