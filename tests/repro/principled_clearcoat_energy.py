"""Mitsuba 3.9.1 principled: the clearcoat lobe lacks the microfacet 1 / (4 cos_i cos_o).

src/bsdfs/principled.cpp:639 adds (clearcoat * 0.25) * Fcc * Dcc * G_cc * |cos_theta_o| to
eval (= f cos_theta_o), i.e. f = 0.25 clearcoat Fcc D G, while the specular lobe (line 600) has
f = F D G / (4 cos_i cos_o) and Burley's reference code folds that denominator into its
smithG_GGX (Mitsuba's clearcoat_G, principledhelpers.h:79, multiplies plain G1s).  At normal
incidence any microfacet lobe with weight 0.25 and F0 = 0.04 reflects at most 0.25 x 0.04 =
0.01 (integral of D cos_h = 1, G <= 1); the clearcoat adds 0.035, and a white metal (roughness
0.2) under a full clearcoat has albedo 1.033.

Run: python tests/repro/principled_clearcoat_energy.py -> exit 1 while present.
"""
import sys

import principled_energy_by_design as grid   # noqa: E402  (the half-vector albedo rule)

metal = {"type": "principled", "metallic": 1.0, "base_color": 1.0, "roughness": 0.2,
         "clearcoat_gloss": 1.0}
with_cc = grid.albedo({**metal, "clearcoat": 1.0}, 0.0)
without = grid.albedo(metal, 0.0)
print(f"albedo at normal incidence: {with_cc:.4f} with clearcoat 1, {without:.4f} without: the "
      f"clearcoat adds {with_cc - without:.4f} (a microfacet lobe: at most 0.25 x 0.04 = 0.01)")
sys.exit(1 if with_cc - without > 0.0125 else 0)
