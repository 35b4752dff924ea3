"""The ``energy`` topic's quadrature on a lobe far narrower than any fixed node spacing.

roughdielectric GGX alpha 0.01 at int_ior 1 against the default ext_ior (air, 1.000277):
eta 0.99972, a transmission lobe about alpha |eta - 1| ~ 3e-6 rad wide.  The topic's albedo
at each theta_i must equal a fine polar quadrature of the same ``eval`` (the reproducer's,
tests/repro/roughdielectric_index_matched_energy.py) within the row's own band (its
|Q(n) - Q(n/2)| error estimate plus the float32 floor), widened only by the reference's own
error (its value at the default grid against one half as fine in each axis).
"""

from __future__ import annotations

import importlib.util
import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

REPRO = Path(__file__).parent / "repro" / "roughdielectric_index_matched_energy.py"


def _reference_module():
    spec = importlib.util.spec_from_file_location("roughdielectric_index_matched_energy", REPRO)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_energy_reads_an_index_matched_transmission_lobe(variant_llvm_rgb):
    import mitsuba as mi

    from phonglab.validate.bsdf.config import options
    from phonglab.validate.bsdf.energy import energy

    if not variant_llvm_rgb.startswith("llvm"):
        pytest.skip("the reference evaluates eval in llvm_ad_rgb")
    ref = _reference_module()
    params = {"type": "roughdielectric", "distribution": "ggx", "alpha": 0.01, "int_ior": 1.0}
    bsdf = mi.load_dict(params)
    eta = float(np.float32(1.0) / np.float32(ref.AIR))
    cos = (0.95, 0.85, 0.5)                      # theta_i 18.2, 31.8, 60 deg
    (row,) = energy(bsdf, replace(options(), energy_cos=cos), 1)
    d = row.details
    for k, c in enumerate(cos):
        wi = np.array([math.sqrt(1.0 - c * c), 0.0, c])

        def f(w):
            return ref.mitsuba_eval(bsdf, wi, w)
        fine = ref.albedo(f, wi, eta, nr=1500, npsi=256)
        coarse = ref.albedo(f, wi, eta, nr=750, npsi=128)
        assert d["band"][k] < 1e-3, (d["theta_deg"][k], d["band"][k])
        assert abs(d["albedo"][k] - fine) <= d["band"][k] + abs(fine - coarse), \
            (d["theta_deg"][k], d["albedo"][k], fine, coarse, d["band"][k])
