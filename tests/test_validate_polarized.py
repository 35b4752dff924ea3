"""The polarized topics (``mueller``, ``intensity``, ``mueller_identities``,
``mueller_reciprocity``; :mod:`phonglab.validate.bsdf.polarization`).

The planted defects are tests/defects_polarized/*.py: each fails its own topic and no other in
``llvm_ad_spectral_polarized`` (quick, seed 0), and -- the reason the topics exist -- passes
every topic in an unpolarized variant, where the polarized topics report one ``skipped`` row
each.  The controls (a depolarizing Lambertian, Python wrappers of ``conductor`` and
``roughconductor``) pass everything.  The criteria are checked on matrices whose answer is
known, and the reciprocity form Q Mᵀ Q (with Mitsuba's Stokes frames) against alternatives
that a reciprocal built-in does not satisfy.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import phonglab
from phonglab.validate import validate_bsdf
from phonglab.validate.bsdf.topics import TOPICS
from phonglab.validate.bsdf import mueller as pol, polarization, stokes_frames

DEFECTS = Path(__file__).parent / "defects_polarized"
POLARIZED = "llvm_ad_spectral_polarized"
POLAR_TOPICS = list(polarization.POLAR_TOPICS)

#: defect file -> the one topic it must fail in a polarized variant
PLANTED = {"over_polarizing": "mueller", "conjugating": "mueller",
           "dim_intensity": "intensity", "nan_offdiagonal": "mueller",
           "depolarized_sample": "mueller_identities",
           "nonreciprocal_matrix": "mueller_reciprocity",
           "unrotated_frames": "mueller_identities"}
#: control file -> its registered name
CONTROLS = {"depolarizing_lambert": "pol_depolarizing_lambert",
            "wrapped_conductor": "pol_wrapped_conductor",
            "wrapped_roughconductor": "pol_wrapped_roughconductor",
            "diattenuating_lambert": "pol_diattenuating_lambert"}


@pytest.fixture
def polarized():
    return phonglab.register(POLARIZED)


@pytest.mark.parametrize("name", sorted(PLANTED))
def test_defect_fails_its_polarized_topic_only(polarized, name):
    report = validate_bsdf(f"defect_{name}", plugins=[DEFECTS / f"{name}.py"], quick=True,
                           seed=0, variant=POLARIZED)
    assert {r.topic for r in report.failing} == {PLANTED[name]}, report.table(report.failing)
    assert {r.topic for r in report.rows} == set(TOPICS)


@pytest.mark.parametrize("name", sorted(CONTROLS))
def test_controls_pass_every_topic(polarized, name):
    report = validate_bsdf(CONTROLS[name], plugins=[DEFECTS / f"{name}.py"], quick=True, seed=0,
                           variant=POLARIZED)
    assert report.passed, report.table(report.failing)
    ran = {r.topic for r in report.rows if r.status == "pass"}
    assert {"mueller", "intensity", "mueller_identities"} <= ran
    if name != "wrapped_conductor":                  # every lobe a delta: eval is 0, skipped
        assert "mueller_reciprocity" in ran


def test_defect_rows_name_the_lane_and_the_violated_quantity(polarized):
    report = validate_bsdf("defect_over_polarizing", plugins=[DEFECTS / "over_polarizing.py"],
                           quick=True, seed=0, variant=POLARIZED, topics=["mueller"])
    row = next(r for r in report.failing if "Stokes cone" in r.name and r.name.startswith("eval"))
    d = row.details
    assert {"worst_wi", "worst_wo", "wavelength", "matrix", "stokes_in", "stokes_out"} <= set(d)
    assert "s0' − |s'|" in d["violated"]
    s_out = np.array(d["stokes_out"])
    assert s_out[0] < np.linalg.norm(s_out[1:])          # the image is not a Stokes vector
    assert row.measured == pytest.approx(1.53, abs=0.02)  # (1 − 1.5·… ) / max|M|: M10 = 1.5 M00


def test_unrotated_frames_fails_the_isotropy_row_only(polarized):
    """The s/p matrix returned without the rotation into Mitsuba's frames: only the isotropy row
    sees it; the same plugin with the rotation (diattenuating_lambert.py) passes that row."""
    report = validate_bsdf("defect_unrotated_frames", plugins=[DEFECTS / "unrotated_frames.py"],
                           quick=True, seed=0, variant=POLARIZED, topics=["mueller_identities"])
    (row,) = report.failing
    assert row.name == stokes_frames.ISOTROPY and row.measured > 100
    assert row.details["max_difference"] > 0.1 and row.details["m00_moved"] == 0
    assert {"psi", "rotated_wi", "rotated_wo", "worst_entry"} <= set(row.details)
    report = validate_bsdf("pol_diattenuating_lambert",
                           plugins=[DEFECTS / "diattenuating_lambert.py"], quick=True, seed=0,
                           variant=POLARIZED, topics=["mueller_identities"])
    row = next(r for r in report.rows if r.name == stokes_frames.ISOTROPY)
    assert row.status == "pass" and row.measured < 0.1


@pytest.mark.parametrize("spec, reason", [
    ({"type": "roughconductor", "alpha_u": 0.1, "alpha_v": 0.4}, "Anisotropic"),
    ({"type": "conductor"}, "every lobe is a delta")])
def test_isotropy_row_skips_what_it_cannot_judge(polarized, spec, reason):
    report = validate_bsdf(spec, quick=True, seed=0, variant=POLARIZED,
                           topics=["mueller_identities"])
    row = next(r for r in report.rows if r.name == stokes_frames.ISOTROPY)
    assert row.status == "skipped" and reason in row.reason


def test_isotropy_row_skips_a_tilted_shading_frame(polarized):
    """bumpmap has no flag for its tilted frame; its M00 moves under the rotation: skipped."""
    from phonglab.validate.bsdf import builtins
    spec = next(c.spec for c in builtins.cases() if c.label == "bumpmap/roughconductor")
    report = validate_bsdf(spec, quick=True, seed=0, variant=POLARIZED,
                           topics=["mueller_identities"])
    row = next(r for r in report.rows if r.name == stokes_frames.ISOTROPY)
    assert row.status == "skipped" and "M00 itself changes" in row.reason


def test_isotropy_transform_is_rotation_covariant():
    """The s/p frames follow a rotation about n; a matrix built in them and rotated into
    stokes_basis frames comes back unchanged through to_sp, whatever ψ."""
    rng = np.random.default_rng(6)
    wi, wo = rng.normal(size=(50, 3)), rng.normal(size=(50, 3))
    wi /= np.linalg.norm(wi, axis=1, keepdims=True)
    wo /= np.linalg.norm(wo, axis=1, keepdims=True)
    m0 = np.array([pol.jones_to_mueller(j) for j in _random_jones(rng, 50)])[:, None]
    for psi in (0.0, 1.0, 4.0):
        a, b = (stokes_frames.rotate_z(v, np.full(50, psi)) for v in (wi, wo))
        s_in, s_out = stokes_frames.sp_frames(a, b)
        r_in = pol.rotate_stokes_basis(-b, s_in, pol.stokes_basis(-b))
        r_out = pol.rotate_stokes_basis(a, s_out, pol.stokes_basis(a))
        mitsuba = r_out[:, None] @ m0 @ np.swapaxes(r_in, -1, -2)[:, None]
        assert np.allclose(stokes_frames.to_sp(mitsuba, a, b), m0, atol=1e-9)


def _render_frames(bsdf, polarizer, spp=16, size=32):
    """The scene of unrotated_frames.py's docstring: a plane under a constant environment seen
    at 60° off its normal by the stokes integrator, a 45° polarizer in front if asked."""
    import mitsuba as mi
    look = mi.ScalarTransform4f().look_at
    scene = {"type": "scene",
             "integrator": {"type": "stokes", "integrator": {"type": "path", "max_depth": 4}},
             "sensor": {"type": "perspective", "fov": 30,
                        "to_world": look(origin=[0, -3.46, 2], target=[0, 0, 0], up=[0, 0, 1]),
                        "film": {"type": "hdrfilm", "width": size, "height": size,
                                 "pixel_format": "rgb"},
                        "sampler": {"type": "independent", "sample_count": spp}},
             "plane": {"type": "rectangle", "bsdf": {"type": bsdf},
                       "to_world": mi.ScalarTransform4f().scale(2.0)},
             "env": {"type": "constant", "radiance": 1.0}}
    if polarizer:
        scene["filter"] = {"type": "rectangle", "bsdf": {"type": "polarizer", "theta": 45.0},
                           "to_world": look(origin=[0, -3.2, 1.85], target=[0, 0, 0],
                                            up=[0, 0, 1]).scale(0.5)}
    img = np.array(mi.render(mi.load_dict(scene), seed=0))
    return {k: img[..., 3 * i + 3: 3 * i + 6].mean(axis=-1) for i, k in enumerate("0123")}


def test_unrotated_frames_changes_a_render(polarized):
    """The frame error is no convention detail: S2 flips sign, and behind a polarizer the
    intensity of each half of the image moves by ~10 % (unrotated_frames.py's docstring)."""
    import runpy
    for name in ("diattenuating_lambert", "unrotated_frames"):
        runpy.run_path(str(DEFECTS / f"{name}.py"))
    good = _render_frames("pol_diattenuating_lambert", False)
    bad = _render_frames("defect_unrotated_frames", False)
    assert np.allclose(good["0"], bad["0"], rtol=1e-4, atol=1e-6)      # M00 is right
    assert np.abs(bad["2"] - good["2"]).mean() > 0.05 * good["0"].mean()
    good = _render_frames("pol_diattenuating_lambert", True)
    bad = _render_frames("defect_unrotated_frames", True)
    half = good["0"].shape[1] // 2
    left = bad["0"][:, :half].mean() / good["0"][:, :half].mean()
    right = bad["0"][:, half:].mean() / good["0"][:, half:].mean()
    assert left < 0.95 and right > 1.05, (left, right)


def test_dim_intensity_is_0_8_of_the_unpolarized_value(polarized):
    report = validate_bsdf("defect_dim_intensity", plugins=[DEFECTS / "dim_intensity.py"],
                           quick=True, seed=0, variant=POLARIZED, topics=["intensity"])
    row = next(r for r in report.rows if r.name.startswith("eval M00"))
    assert row.status == "fail" and row.measured == pytest.approx(0.2, abs=1e-5)
    assert row.details["reference_variant"] == "llvm_ad_spectral"
    m00, ref = np.array(row.details["polarized_m00"]), np.array(row.details["unpolarized"])
    assert m00 == pytest.approx(0.8 * ref, rel=1e-5)


@pytest.mark.parametrize("name", sorted(PLANTED))
def test_defects_pass_in_an_unpolarized_variant(name):
    """Why the topics exist: intensity-only checks see nothing wrong."""
    phonglab.register("llvm_ad_spectral")
    report = validate_bsdf(f"defect_{name}", plugins=[DEFECTS / f"{name}.py"], quick=True,
                           seed=0, variant="llvm_ad_spectral",
                           topics=["finite", "weight", "energy", "reciprocity"] + POLAR_TOPICS)
    assert report.passed, report.table(report.failing)
    for t in POLAR_TOPICS:
        rows = [r for r in report.rows if r.topic == t]
        assert len(rows) == 1 and rows[0].status == "skipped", t
        assert "not a polarized variant" in rows[0].reason


def test_loaded_object_skips_intensity(polarized):
    import mitsuba as mi
    report = validate_bsdf(mi.load_dict({"type": "diffuse"}), quick=True, topics=["intensity"])
    (row,) = report.rows
    assert row.status == "skipped" and "loaded object" in row.reason


def test_scalar_polarized_variant():
    phonglab.register("scalar_spectral_polarized")
    report = validate_bsdf("roughconductor", quick=True, seed=0,
                           variant="scalar_spectral_polarized", topics=POLAR_TOPICS)
    assert report.passed, report.table(report.failing)
    assert any(r.details.get("reference_variant") == "scalar_spectral" for r in report.rows)


# ----------------------------------------------------------------------------- criteria
def _random_jones(rng, n):
    return rng.normal(size=(n, 2, 2)) + 1j * rng.normal(size=(n, 2, 2))


def test_jones_matrices_are_realizable_and_on_the_cone_boundary():
    rng = np.random.default_rng(1)
    m = np.array([pol.jones_to_mueller(j) for j in _random_jones(rng, 40)])
    margin, _ = pol.stokes_margin(m)
    scale = np.abs(m).max(axis=(1, 2))
    assert np.all(np.abs(margin) <= 1e-9 * scale)          # pure states stay pure
    assert np.all(pol.cloude_min_eig(m) >= -1e-9 * scale)
    mix = m[:20] + m[20:]                                   # an ensemble: depolarizing, inside
    assert np.all(pol.stokes_margin(mix)[0] >= -1e-9 * np.abs(mix).max(axis=(1, 2)))
    assert np.all(pol.cloude_min_eig(mix) >= -1e-9 * np.abs(mix).max(axis=(1, 2)))


def test_criteria_on_known_matrices():
    over = np.zeros((4, 4))
    over[0, 0], over[1, 0] = 1.0, 1.5
    assert pol.stokes_margin(over)[0] == pytest.approx(-0.5, abs=1e-9)
    conj = np.diag([1.0, 1.0, 1.0, -1.0])                   # keeps the cone, no Jones mixture
    assert pol.stokes_margin(conj)[0] == pytest.approx(0.0, abs=1e-9)
    assert pol.cloude_min_eig(conj) == pytest.approx(-0.5, abs=1e-12)
    assert pol.stokes_margin(-np.eye(4))[0] < 0             # M00 < 0
    depol = np.diag([1.0, 0.0, 0.0, 0.0])
    assert pol.stokes_margin(depol)[0] == pytest.approx(1.0)
    assert pol.cloude_min_eig(depol) == pytest.approx(0.25)
    amplify_v = np.diag([1.0, 0.0, 0.0, 1.2])
    assert pol.stokes_margin(amplify_v)[0] == pytest.approx(-0.2, abs=1e-6)


def test_stokes_margin_cover_is_the_grids_covering_radius():
    """COVER bounds the chordal distance from any unit vector to the nearest grid point: the
    largest circumradius of the grid's convex-hull facets (its spherical Delaunay triangles)."""
    from scipy.spatial import ConvexHull
    grid = pol.fibonacci(pol.GRID)
    hull = ConvexHull(grid)
    radius = np.linalg.norm(hull.equations[:, None, :3] - grid[hull.simplices], axis=-1).max()
    assert radius <= pol.COVER < radius + 1e-3
    u = np.random.default_rng(4).normal(size=(20000, 3))
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    assert np.max(np.min(np.linalg.norm(u[:, None] - grid[None], axis=-1), axis=1)) <= radius


def test_stokes_margin_sign_unchanged_by_the_certified_skip():
    """Mixtures of Jones matrices and depolarizers, some certified positive without a search:
    the margin's sign is the sign of a dense brute-force minimum wherever that is clear."""
    rng = np.random.default_rng(5)
    jones = np.array([pol.jones_to_mueller(j) for j in _random_jones(rng, 60)])
    depol = np.zeros((60, 4, 4))
    depol[:, 0, 0] = np.abs(jones[:, 0, 0])
    mix = jones * rng.uniform(0, 1, (60, 1, 1)) + depol * rng.uniform(0, 1, (60, 1, 1))
    over = mix.copy()
    over[:, 1, 0] += 1.2 * over[:, 0, 0]                     # over-polarizing: negative margin
    m = np.concatenate([mix, over])
    margin, _ = pol.stokes_margin(m)
    dense = pol.fibonacci(40000)
    s = np.concatenate([np.ones((len(dense), 1)), dense], axis=1)
    brute = (np.einsum("nij,kj->nki", m, s)[..., 0]
             - np.linalg.norm(np.einsum("nij,kj->nki", m, s)[..., 1:], axis=-1)).min(axis=1)
    scale = np.abs(m).max(axis=(1, 2))
    clear = np.abs(brute) > 1e-3 * scale
    assert np.all(np.sign(margin[clear]) == np.sign(brute[clear]))
    assert np.sum(margin > 0) > 20 and np.sum(margin < 0) > 20


def test_jones_transpose_is_p_mt_p():
    """The identity behind the reciprocity form: M(Jᵀ) = P M(J)ᵀ P, P = diag(1, 1, 1, −1)."""
    p = np.diag([1.0, 1.0, 1.0, -1.0])
    for j in _random_jones(np.random.default_rng(2), 10):
        m = pol.jones_to_mueller(j)
        assert np.allclose(pol.jones_to_mueller(j.T), p @ m.T @ p, atol=1e-12)


def test_frames_match_mitsuba(polarized):
    import drjit as dr
    import mitsuba as mi
    rng = np.random.default_rng(3)
    d = rng.normal(size=(64, 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    t = rng.normal(size=(64, 3))
    t -= np.sum(t * d, axis=1, keepdims=True) * d
    t /= np.linalg.norm(t, axis=1, keepdims=True)
    dv, tv = (mi.Vector3f(*[mi.Float(c) for c in a.T.astype(np.float32)]) for a in (d, t))
    b_mi = mi.mueller.stokes_basis(dv)
    b_np = pol.stokes_basis(d.astype(np.float32).astype(np.float64))
    assert np.allclose(np.array([np.array(c) for c in b_mi]).T, b_np, atol=1e-5)
    r_mi = mi.mueller.rotate_stokes_basis(dv, b_mi, tv)
    dr.eval(r_mi)
    r_np = pol.rotate_stokes_basis(d, b_np, t)
    got = np.array([[np.broadcast_to(np.array(r_mi[i][j]), (64,)) for j in range(4)]
                    for i in range(4)]).transpose(2, 0, 1)
    assert np.allclose(got, r_np, atol=1e-4)


@pytest.mark.parametrize("q", [np.eye(4), np.diag([1.0, 1.0, 1.0, -1.0]),
                               np.diag([1.0, 1.0, -1.0, -1.0])])
def test_reciprocity_form_is_the_one_a_reciprocal_builtin_meets(polarized, q, monkeypatch):
    """roughconductor (Fresnel matrices per microfacet, physically reciprocal) passes with
    Q = diag(1, 1, −1, 1) (``test_controls_pass_every_topic``) and fails with the others."""
    monkeypatch.setattr(pol, "Q", q)
    report = validate_bsdf("roughconductor", quick=True, seed=0, variant=POLARIZED,
                           topics=["mueller_reciprocity"])
    row = next(r for r in report.rows if "reflection" in r.name)
    assert row.status == "fail" and row.measured > 10


def test_retarder_jump_is_caught_and_known(polarized):
    """mitsuba3#1963: present in 3.9.1; the continuity row sees it, only at wi.y = 0."""
    report = validate_bsdf({"type": "retarder", "theta": 30.0, "delta": 90.0}, quick=True,
                           seed=0, variant=POLARIZED, topics=["mueller_identities"])
    row = next(r for r in report.rows if "continuous" in r.name)
    assert row.status == "fail" and row.measured > 1.0
    assert np.all(np.abs(row.failing_lanes["wi"][:, 1]) <= 1e-5)
    report = validate_bsdf("diffuse", quick=True, seed=0, variant=POLARIZED,
                           topics=["mueller_identities"])
    row = next(r for r in report.rows if "continuous" in r.name)
    assert row.status == "skipped"                  # no delta lobe


def test_intensity_reloads_nested_values_and_skips_objects(polarized):
    import mitsuba as mi
    rgb = {"type": "rgb", "value": [0.2, 0.3, 0.4]}
    report = validate_bsdf("diffuse", params={"reflectance": rgb}, quick=True,
                           topics=["intensity"], variant=POLARIZED)
    assert [r.status for r in report.rows] == ["pass", "pass"], report.table()
    texture = mi.load_dict({"type": "checkerboard"})       # a Mitsuba object: no spec to rebuild
    report = validate_bsdf({"type": "diffuse", "reflectance": texture}, quick=True,
                           topics=["intensity"], variant=POLARIZED)
    (row,) = report.rows
    assert row.status == "skipped" and "does not load in llvm_ad_spectral" in row.reason


def test_intensity_reference_process_starts_once_per_run_and_ends(polarized, monkeypatch):
    """A sweep's points share one unpolarized reference process (intensity.session), which has
    ended, its folder removed, when the run returns -- and when a topic raises mid-run."""
    from pathlib import Path as P
    from phonglab.validate.bsdf import intensity

    started = []
    init = intensity.ReferenceServer.__init__

    def counting(self, *args, **kwargs):
        init(self, *args, **kwargs)
        started.append(self)

    monkeypatch.setattr(intensity.ReferenceServer, "__init__", counting)
    report = validate_bsdf("roughconductor", sweep=True, quick=True, seed=0, variant=POLARIZED,
                           topics=["intensity"])
    points = report.meta["sweep"]["points"]
    assert points > 2
    assert len([r for r in report.rows if r.status == "pass"]) == 2 * points, report.table()
    assert len(started) == 1 and started[0].requests == points
    assert started[0].proc.poll() is not None and not P(started[0].tmp.name).exists()

    started.clear()
    request = intensity.ReferenceServer.request
    calls = []

    def interrupted(self, spec, arrays):
        calls.append(spec)
        if len(calls) == 2:
            raise KeyboardInterrupt          # Ctrl-C while the second point is served
        return request(self, spec, arrays)

    monkeypatch.setattr(intensity.ReferenceServer, "request", interrupted)
    with pytest.raises(KeyboardInterrupt):
        validate_bsdf("roughconductor", sweep=True, quick=True, seed=0, variant=POLARIZED,
                      topics=["intensity"])
    assert len(started) == 1 and started[0].proc.poll() is not None
    assert not P(started[0].tmp.name).exists()
