"""The identities' conditioning estimate (phonglab.validate.roundoff): random 8u corners, then, for
a lane that fails, every float32 wo within 8 ulps (roundoff.refine).  Pure numpy functions stand
in for a BSDF, so these tests need no Mitsuba."""

from __future__ import annotations

import numpy as np

from phonglab.validate import roundoff

#: The grazing retro-reflection lane of roughconductor (beckmann, alpha 0.4, no visible
#: sampling) at cos theta_i = 1e-4 whose pdf row failed: bs.pdf = 2348.7, pdf(bs.wo) = 0.
WI = np.array([[-0.5048461020756271, 0.8632093623328269, 9.999999999991701e-05]])
WO = np.array([[0.5048933625221252, -0.8631817102432251, 8.617780622444116e-06]])
BS_PDF = 2348.717041015625


def half_vector_pdf(wi, wo):
    """Mitsuba's side tests wi.m > 0 and wo.m > 0 with m = normalize(wi + wo) (float32 inputs,
    float64 arithmetic): non-zero only where |wo|^2 - |wi|^2 lies within
    |wi + wo|^2 ~ 1.5e-8 of 0, finer than the change one ulp of a component near 0.86 makes."""
    wi, wo = wi.astype(np.float32).astype(np.float64), wo.astype(np.float32).astype(np.float64)
    s = wi + wo
    ok = (np.sum(wi * s, axis=1) > 0) & (np.sum(wo * s, axis=1) > 0)
    return np.where(ok, BS_PDF, 0.0)


def test_ulp_box_holds_every_float32_neighbour():
    box = roundoff.ulp_box(WO, 2)
    assert box.shape == (125, 3)
    assert np.array_equal(box, box.astype(np.float32).astype(np.float64))
    assert any(np.array_equal(p, WO[0].astype(np.float32)) for p in box)
    steps = (box - WO.astype(np.float32)) / np.spacing(np.abs(WO.astype(np.float32)))
    assert np.allclose(np.unique(np.round(steps, 6)), np.arange(-2, 3))


def test_thin_set_missed_by_random_corners_is_found_by_the_box():
    pd = half_vector_pdf(WI, WO)
    assert pd[0] == 0.0                                   # the float32 wo misses the window
    rng = np.random.default_rng(0)
    sens = roundoff.sensitivity(half_vector_pdf, WI, WO, rng, pd)
    rel = roundoff.rel_diff(np.array([BS_PDF]), pd)
    assert sens[0] == 0.0 and roundoff.excess(rel, sens)[0] > 1.0      # the old verdict: fail
    ex, info = roundoff.refine(rel, sens, np.zeros(1), half_vector_pdf, WI, WO, pd)
    assert ex[0] <= 1.0
    assert info == {"box_searched": 1, "box_passed": 1, "box_stopped_early": False}


def _cosine(wi, wo):
    return np.asarray(wo, np.float32).astype(np.float64)[:, 2:3] / np.pi


def test_box_keeps_a_well_conditioned_defect_failing():
    """A 1 % error on a smooth lobe: the box changes the value by ~1e-6, the lane still fails."""
    rng = np.random.default_rng(1)
    wo = rng.normal(size=(64, 3))
    wo[:, 2] = np.abs(wo[:, 2]) + 0.2
    wo /= np.linalg.norm(wo, axis=1, keepdims=True)
    wi = np.tile([[0.0, 0.6, 0.8]], (64, 1))
    value = _cosine(wi, wo)
    box = roundoff.box_sensitivity(_cosine, wi, wo, value)
    assert box.max() < 1e-5
    rel = np.max(roundoff.rel_diff(1.01 * value, value), axis=1)
    sens = roundoff.sensitivity(_cosine, wi, wo, rng, value)
    ex, info = roundoff.refine(rel, sens, np.zeros(64), _cosine, wi, wo, value)
    assert ex.min() > 9.0
    # worst first, one batch, then stop: the row fails, the other lanes keep the random estimate
    assert info == {"box_searched": roundoff.BOX_BATCH, "box_passed": 0, "box_stopped_early": True}


def test_refine_leaves_passing_lanes_alone():
    wi, wo = np.tile([[0.0, 0.6, 0.8]], (4, 1)), np.tile([[0.0, -0.6, 0.8]], (4, 1))
    value = _cosine(wi, wo)
    rel = np.max(roundoff.rel_diff(value, value), axis=1)
    ex, info = roundoff.refine(rel, np.zeros(4), np.zeros(4), _cosine, wi, wo, value)
    assert np.all(ex == 0.0) and info["box_searched"] == 0


def test_a_lanes_box_does_not_depend_on_the_lanes_beside_it():
    """A lane whose value drops to 0 within its box (a grazing retro-reflection's pdf,
    1.05e5 -> 0) has relative change 1 there, whatever lanes share its batch: with one
    rel_diff floor for the batch, neighbours of ~1e9 (roughdielectric near eta = 1) made it
    0.21 and failed a row of a correct plugin."""
    def fn(wi, wo):
        # lane 0's value vanishes when wo.x moves off its float32 value; lane 1 is huge, flat
        big = wi[:, 0] > 0.5
        edge = np.float32(0.6)
        small = np.where(wo[:, 0].astype(np.float32) == edge, 1.05e5, 0.0)
        return np.where(big, 1e9, small)
    wi = np.array([[0.0, 0.0, 1.0], [1.0, 0.0, 0.0]])
    wo = np.array([[0.6, 0.0, 0.8], [0.0, 0.6, 0.8]], dtype=np.float32).astype(np.float64)
    value = fn(wi, wo)
    alone = roundoff.box_sensitivity(fn, wi[:1], wo[:1], value[:1])
    batch = roundoff.box_sensitivity(fn, wi, wo, value)
    assert alone[0] == 1.0 and batch[0] == alone[0] and batch[1] == 0.0
