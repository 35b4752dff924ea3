"""Mitsuba 3.9.1 sunsky: sun samples on the rim of the sun's cone lose the sun in pdf_direction.

include/mitsuba/render/sunsky.h (commit 478e193a): sample_direction picks the sun or the sky
and sets ``sun_hit = !pick_sky || hit_sun(sun_angles, sample_dir)`` (line 430): every direction
drawn from the sun's cone (sample_sun, line 903: warp::square_to_uniform_cone, then
Frame3f::to_world) counts as inside it, so ds.pdf holds the sun's cone pdf (line 434) and the
weight the sun's radiance (line 436).  pdf_direction (line 451) and eval (lines 319-321)
re-test ``hit_sun``: dot(sun, normalize(to_world^-1 d)) >= cos(half aperture) (line 946), in
float32.  The sun's half aperture is 0.268 deg: 1 - cos = 1.09e-5, 183 float32 steps (2^-24)
below 1, and directions drawn at the cone's rim round 1-3 steps outside that test.  There
pdf_direction returns the sky's pdf alone (0.10 against ds.pdf 8959 at latitude 0) and
eval_direction the sky's radiance alone.  Which samples do depends on the sun's direction:
at latitude 0 about 0.2 % of all samples, at the default place (Tokyo) none; timed_sunsky
shares the code (its sun at time 0: the first hour of its default window).

Run: python tests/repro/sunsky_sun_rim_pdf.py  -> exit 1 while the behaviour is present.
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
n = 65536
u = np.random.default_rng(1).random((n, 2)).astype(np.float32)
it = dr.zeros(mi.Interaction3f, n)                        # reference point at the origin, time 0
cos_half = dr.cos(dr.deg2rad(mi.Float(0.5) * mi.Float(0.5358)))
cone_pdf = 1.0 / (2.0 * np.pi * (1.0 - float(np.array(cos_half)[0])))   # 14591; the sky's ~0.1-1


def rim(emitter):
    """(sun samples, those whose pdf_direction lost the sun, the sample record, its arrays)."""
    ds, w = emitter.sample_direction(it, mi.Point2f(mi.Float(u[:, 0]), mi.Float(u[:, 1])))
    pdf, pd = np.array(ds.pdf), np.array(emitter.pdf_direction(it, ds))
    sun_lanes = pdf > 0.01 * cone_pdf                     # ds.pdf holds the sun's cone pdf
    return sun_lanes, sun_lanes & (pd < 0.5 * pdf), ds, w, pdf, pd


def steps_of(emitter, ds):
    """dot(sun, d) - cos(half aperture) in float32 steps of 2^-24, as hit_sun (sunsky.h:946)
    tests it (sunsky only: its sun_direction is a parameter)."""
    params = mi.traverse(emitter)
    inv = params["to_world"].inverse()
    angles = mi.dir_to_sph(inv @ params["sun_direction"])     # m_sun_angles (sunsky.cpp:257)
    sun = mi.sph_to_dir(angles.x, angles.y)
    return np.array(dr.dot(sun, dr.normalize(inv @ ds.d)) - cos_half) / 2.0 ** -24


sky = mi.load_dict({"type": "sunsky", "latitude": 0.0})
sun_lanes, dropped, ds, w, pdf, pd = rim(sky)
wp = np.array(w).T * pdf[:, None]
ev = np.array(sky.eval_direction(it, ds)).T
steps = steps_of(sky, ds)
print(f"sunsky, latitude 0: {sun_lanes.sum()} of {n} samples hold the sun's cone pdf (ds.pdf > "
      f"1 % of 1/(2π(1 - cos)) = {cone_pdf:.0f})")
print(f"{dropped.sum()} of them get pdf_direction without the sun: ds.pdf "
      f"{np.unique(np.round(pdf[dropped], 1))} vs pdf_direction "
      f"{pd[dropped].min(initial=np.inf):.3f}..{pd[dropped].max(initial=-np.inf):.3f}")
print(f"their dot(sun, d) - cos(half aperture), in float32 steps of 2^-24: "
      f"{np.unique(steps[dropped]).tolist()} (hit_sun: >= 0); sun samples with steps < 0: "
      f"{(sun_lanes & (steps < 0)).sum()}, the steps of all sun samples "
      f"{steps[sun_lanes].min(initial=np.inf):g}..{steps[sun_lanes].max(initial=-np.inf):g}")
if dropped.any():
    k = int(np.flatnonzero(dropped)[0])
    print(f"first: u = ({u[k, 0]:.6f}, {u[k, 1]:.6f}), weight x ds.pdf = "
          f"({', '.join(f'{x:.1f}' for x in wp[k])}) against eval_direction = "
          f"({', '.join(f'{x:.4f}' for x in ev[k])})")
# the same test of other suns: sunsky elsewhere, and timed_sunsky (its default day, time 0)
for label, spec in (("sunsky, latitude -20", {"type": "sunsky", "latitude": -20.0}),
                    ("sunsky, latitude 10", {"type": "sunsky", "latitude": 10.0}),
                    ("sunsky, Tokyo (default)", {"type": "sunsky"}),
                    ("timed_sunsky (default)", {"type": "timed_sunsky"})):
    em = mi.load_dict(spec)
    s_l, d_l, ds_l, *_ = rim(em)
    where = ""
    if spec["type"] == "sunsky" and d_l.any():
        st = steps_of(em, ds_l)[d_l]
        where = f" ({st.min():g} to {st.max():g} steps)"
    print(f"{label}: {d_l.sum()} of {s_l.sum()} sun samples lose the sun in pdf_direction{where}")
present = bool(dropped.any())
print("behaviour present: sun samples at the cone's rim lose the sun in pdf_direction and eval"
      if present else "fixed: pdf_direction keeps the sun on every sun sample")
sys.exit(1 if present else 0)
