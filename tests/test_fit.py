"""phonglab.fit (BRDF space): recovery, AD gradient, energy conservation, the CLI, the table.

Tolerances.  The data of a BRDF-space fit carry no Monte Carlo noise: target and model are
evaluated on the same quadrature nodes, so the quadrature error cancels and the true
parameters x* minimize the discrete objective exactly (loss 0).  What is left is float32
round-off of ``eval`` (relative ε₃₂ = 2⁻²⁴ per operation, at most C = 64 operations deep:
loss floor (C ε₃₂)² ≈ 1.5e-11) and the optimizer's stopping rule (ftol = 1e-12 absolute for a
loss below 1).  So a fit is accepted when its loss is at most L_max = 1e-9, and near x* the
loss is the quadratic ½ dᵀ H d (d = x − x*, H its Hessian), whence the largest |d_k| with
loss ≤ L_max is √(2 L_max (H⁻¹)_kk): that is each parameter's tolerance, H measured by a
central difference of the AD gradient at x*.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from phonglab.cli import main
from phonglab.physics import roughness
from phonglab.physics.quadrature import lobe_width

EPS32 = 2.0 ** -24
LOSS_MAX = 1e-9


@pytest.fixture
def fitlib(variant_llvm_rgb):
    from phonglab.fit import objective, optimize
    return objective, optimize


def _phong_objective(objective, kd, ks, p):
    import mitsuba as mi
    bsdf = mi.load_dict({"type": "phong", "diffuse_reflectance": kd,
                         "specular_reflectance": ks, "exponent": p})
    dirs = objective.fit_directions(lobe_width(p))
    return objective.Objective(objective.PHONG, dirs, objective.luminance_eval(bsdf, dirs))


def _hessian(obj, x, idx, h=1e-4):
    """Central difference of the AD gradient: H[idx, idx] at x."""
    n = len(idx)
    H = np.zeros((n, n))
    for a, k in enumerate(idx):
        e = np.zeros(len(x))
        e[k] = h
        gp, gm = obj.loss_and_grad(x + e)[1], obj.loss_and_grad(x - e)[1]
        H[a] = (gp - gm)[list(idx)] / (2 * h)
    return 0.5 * (H + H.T)


def test_folk_rules_invert_the_bench_rule():
    for p in (1.0, 10.0, 30.0, 1000.0):
        assert roughness.phong_exponent(roughness.beckmann_alpha(p)) == pytest.approx(p, rel=1e-12)
        assert roughness.blinn_phong_exponent(roughness.beckmann_alpha(p)) == pytest.approx(
            4 * p, rel=1e-12)


@given(alpha=st.floats(1e-3, 1.0))
def test_folk_rules_round_trip(alpha):
    """α → p → α and α → p_h = 4p: each rule inverts the other (float64 round-off only)."""
    p = roughness.phong_exponent(alpha)
    assert roughness.beckmann_alpha(p) == pytest.approx(alpha, rel=1e-12)
    assert roughness.blinn_phong_exponent(alpha) == pytest.approx(4 * p, rel=1e-12, abs=1e-12)


@pytest.mark.parametrize("truth,start", [((0.3, 0.4, 30.0), (0.6, 0.1, 8.0)),
                                         ((0.1, 0.7, 200.0), (0.4, 0.4, 50.0))])
def test_recovers_a_known_phong(fitlib, truth, start):
    objective, optimize = fitlib
    r = optimize.fit("phong", {"diffuse_reflectance": truth[0], "specular_reflectance": truth[1],
                               "exponent": truth[2]}, start=start)
    assert r.rel_l2 ** 2 <= LOSS_MAX
    obj = _phong_objective(objective, *truth)
    x_true = objective.PHONG.variables(truth)
    tol = np.sqrt(2 * LOSS_MAX * np.diag(np.linalg.inv(_hessian(obj, x_true, [0, 1, 2]))))
    x_fit = objective.PHONG.variables(r.fitted)
    assert np.all(np.abs(x_fit - x_true) <= tol), (x_fit, x_true, tol)
    assert r.start == pytest.approx(list(start))


def test_ad_gradient_matches_central_difference(fitlib):
    """|AD − FD(h)| ≤ truncation + round-off: truncation ≈ |FD(h) − FD(2h)| (an h² error
    quadruples with 2h, so it is a third of the difference; taken whole), round-off of the
    loss δL ≤ 2 C ε₃₂ Σ w |Δg| |g| / T² gives ≤ δL/h in the difference quotient (twice, taken)."""
    objective, _ = fitlib
    import mitsuba as mi
    target = mi.load_dict({"type": "roughconductor", "alpha": 0.2, "distribution": "ggx"})
    dirs = objective.fit_directions(lobe_width(12.0))
    obj = objective.Objective(objective.PHONG, dirs, objective.luminance_eval(target, dirs))
    h = 1e-3
    for x in ([0.7, 0.6, math.log(8.0)], [0.9, 0.3, math.log(30.0)], [0.4, 0.9, math.log(2.0)]):
        x = np.array(x)
        loss, grad = obj.loss_and_grad(x)
        g_m = obj.values(x)
        delta_loss = 2 * 64 * EPS32 * np.sum(dirs.weight * np.abs(g_m - obj.target) * np.abs(g_m)) / obj.norm
        for k in range(3):
            e = np.zeros(3)
            e[k] = 1.0
            fd_h = (obj.loss(x + h * e) - obj.loss(x - h * e)) / (2 * h)
            fd_2h = (obj.loss(x + 2 * h * e) - obj.loss(x - 2 * h * e)) / (4 * h)
            tol = abs(fd_h - fd_2h) + 2 * delta_loss / h
            assert abs(grad[k] - fd_h) <= tol, (x, k, grad[k], fd_h, tol)
            assert abs(grad[k]) > 10 * tol   # the comparison is not vacuous


def test_diffuse_target_fits_no_glossy_lobe(fitlib):
    objective, optimize = fitlib
    r = optimize.fit("diffuse", {"reflectance": 0.6}, start=(0.3, 0.3, 10.0))
    assert r.rel_l2 ** 2 <= LOSS_MAX
    kd, ks, p = r.fitted
    obj = _phong_objective(objective, 0.6, 0.0, 10.0)
    x = objective.PHONG.variables((0.6, 1e-3, p))   # inside the box for the difference
    H = _hessian(obj, x, [0, 1])
    tol = np.sqrt(2 * LOSS_MAX * np.diag(np.linalg.inv(H)))
    # k_s = t s: |k_s| ≤ (t + tol_t) tol_s around s* = 0.
    assert ks <= (0.6 + tol[0]) * tol[1], (r.fitted, tol)
    assert abs(kd - 0.6) <= tol[0] + 0.6 * tol[1]


@settings(max_examples=6, deadline=None, derandomize=True, database=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])  # the variant is set once
@given(target=st.sampled_from(["roughconductor", "roughplastic", "principled", "phong",
                               "diffuse"]),
       alpha=st.floats(0.04, 0.7), t=st.floats(0.0, 1.0), s=st.floats(0.0, 1.0),
       q=st.floats(math.log(0.01), math.log(1e4)))
def test_fit_stays_energy_conserving_and_finite(variant_llvm_rgb, target, alpha, t, s, q):
    from phonglab.fit import objective, optimize
    params = {"roughconductor": {"alpha": alpha}, "roughplastic": {"alpha": alpha},
              "principled": {"roughness": math.sqrt(alpha)},
              "phong": {"exponent": roughness.phong_exponent(alpha)}, "diffuse": {}}[target]
    start = objective.PHONG.physical((t, s, q))
    r = optimize.fit(target, params, start=start, maxiter=25)
    kd, ks, p = r.fitted
    values = [*r.fitted, r.rel_l2, *r.residual, *r.albedo_fit, *r.albedo_target]
    assert all(math.isfinite(v) for v in values), r
    assert kd >= 0 and ks >= 0 and kd + ks <= 1.0 + 1e-12
    assert objective.P_MIN * (1 - 1e-9) <= p <= objective.P_MAX * (1 + 1e-9)
    assert r.rel_l2 <= r.rel_l2_start + 1e-12
    assert all(a <= 1.0 + 1e-5 for a in r.albedo_fit)


def test_cli_fit_prints_and_writes_json(tmp_path, capsys, variant_llvm_rgb):
    out = tmp_path / "fit.json"
    assert main(["fit", "roughconductor", "--set", "alpha=0.2", "--json", str(out),
                 "--report", str(tmp_path / "fit.txt")]) == 0
    text = capsys.readouterr().out
    assert "fitted  k_d = " in text and "relative L2" in text and "worst direction" in text
    data = json.loads(out.read_text())
    assert data["target_params"] == {"alpha": 0.2}
    kd, ks, p = data["fitted"]
    assert kd + ks <= 1 and p > data["start"][2]   # the highlight narrows from the folk rule
    assert data["rel_l2"] < data["rel_l2_start"]
    assert (tmp_path / "fit.txt").read_text().strip() == text.strip()


def test_cli_fit_set_grammar(tmp_path, capsys, variant_llvm_rgb):
    """--set takes phonglab.settings' grammar: a number, a string, a colour, an int."""
    out = tmp_path / "fit.json"
    assert main(["fit", "roughplastic", "--set", "alpha=0.2", "--set", "distribution=ggx",
                 "--set", "diffuse_reflectance=0.2, 0.3, 0.4", "--set", "nonlinear=true",
                 "--maxiter", "20", "--json", str(out)]) == 0
    data = json.loads(out.read_text())
    assert data["target_params"] == {"alpha": 0.2, "distribution": "ggx", "nonlinear": True,
                                     "diffuse_reflectance": {"type": "rgb",
                                                             "value": [0.2, 0.3, 0.4]}}
    assert data["alpha"] == pytest.approx(0.2)
    assert main(["fit", "roughconductor", "--set", "alpha=1", "--maxiter", "5",
                 "--json", str(out)]) == 0                    # an int where Mitsuba wants a float
    data = json.loads(out.read_text())
    assert data["target_params"] == {"alpha": 1} and data["alpha"] == 1.0
    capsys.readouterr()


@pytest.mark.parametrize("argv,needle", [
    (["fit", "nosuchbsdf"], "Plugin \"nosuchbsdf\" not found"),
    (["fit", "roughconductor", "--set", "alpha"], "--set expects NAME=VALUE"),
    (["fit", "roughconductor", "--set", "foo=1"], "does not read the parameter foo"),
    (["fit", "roughconductor", "--set", "alpha=-0.5"], "outside (0, 1]"),
    (["fit", "roughconductor", "--set", "alpha=0"], "outside (0, 1]"),   # ZeroDivisionError
    (["fit", "roughconductor", "--set", "alpha=1,2"], "give one number or three"),
    (["fit", "conductor"], "reflects nothing that eval can see"),
    (["fit", "roughconductor", "--variant", "scalar_rgb"], "*_ad_rgb"),
    (["fit", "roughconductor", "--maxiter", "0"], "--maxiter"),
])
def test_cli_bad_input_is_one_sentence(argv, needle, capsys, tmp_path):
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.startswith("phonglab: error: ") and needle in err and len(err.splitlines()) == 1


def test_cli_refuses_a_folder_as_json_before_fitting(tmp_path, capsys):
    assert main(["fit", "roughconductor", "--json", str(tmp_path)]) == 2
    assert "is a folder" in capsys.readouterr().err


def test_table_row_and_markdown(fitlib, tmp_path):
    from phonglab.fit import table
    rows = table.rows(alphas=(0.2,), materials=(("roughplastic", "ggx"),))
    (row,) = rows
    assert row["p_phong_rule"] == pytest.approx(12.0) and row["p_blinn_rule"] == pytest.approx(48.0)
    assert 0 <= row["residual_normal"] < row["residual_grazing"]   # Phong fails at grazing
    page = tmp_path / "page.md"
    page.write_text(f"x\n{table.BEGIN}\nold\n{table.END}\ny\n")
    table.replace_table(page, table.markdown_table(rows))
    text = page.read_text()
    assert "old" not in text and f"| {row['p']:.1f} |" in text and text.endswith(f"{table.END}\ny\n")


@pytest.mark.slow
def test_docs_table_is_the_command_output(variant_llvm_rgb):
    """docs/fitting.md shows exactly what `make fitting-table` computes."""
    from pathlib import Path

    from phonglab.fit import table
    doc = (Path(__file__).resolve().parents[1] / "docs" / "fitting.md").read_text()
    assert table.markdown_table(table.rows()) in doc


def test_timing_record_and_bench_section(tmp_path):
    """The benchmark of `phonglab fit roughconductor --set alpha=0.2`, at one repeat."""
    from types import SimpleNamespace

    from phonglab.bench.report import fitting_section
    from phonglab.bench import fit_timing
    assert fit_timing.main(["--repeats", "1", "--out", str(tmp_path / "fit.json")]) == 0
    record = json.loads((tmp_path / "fit.json").read_text())
    assert record["repeats"] == 1 and record["wall_min_s"] == record["wall_median_s"] > 0
    assert record["met"] == (record["wall_median_s"] < 60)
    text = "\n".join(fitting_section(SimpleNamespace(out=tmp_path)))
    assert record["command"] in text and f"{record['wall_median_s']:.2f}" in text
    assert fitting_section(SimpleNamespace(out=tmp_path / "none")) == []
