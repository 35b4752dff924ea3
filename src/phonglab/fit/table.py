r"""The table of docs/fitting.md: phong fitted to Beckmann and GGX roughconductor and roughplastic.

For each material and α ∈ :data:`ALPHAS` it runs :func:`phonglab.fit.optimize.fit` and lists the
fitted exponent against the two folk rules, the residual r(θ_i) at normal (0°) and grazing
(:data:`~phonglab.fit.optimize.GRAZING_DEG`) incidence, the overall relative L2 and the albedo
difference a_fit − a_target at both angles.  ``python -m phonglab.fit.table --json J --markdown M``
(``make fitting-table``) writes the numbers (JSON) and the page that shows them; every number on
the page comes from that run (the table from the JSON's rows, and the example report of
``phonglab fit roughconductor --set alpha=0.2``).
"""

from __future__ import annotations

import argparse
from pathlib import Path

from .. import registration
from ..physics.roughness import blinn_phong_exponent, phong_exponent
from .optimize import GRAZING_DEG, fit, format_result
from ..engine.outputs import write_json

ALPHAS = (0.05, 0.1, 0.2, 0.3, 0.5)
#: (target plugin, distribution)
MATERIALS = (("roughconductor", "beckmann"), ("roughconductor", "ggx"),
             ("roughplastic", "beckmann"), ("roughplastic", "ggx"))


def rows(alphas=ALPHAS, materials=MATERIALS) -> list[dict]:
    """One dict per (material, α): the fit and the folk rules."""
    out = []
    for target, dist in materials:
        for alpha in alphas:
            r = fit(target, {"alpha": float(alpha), "distribution": dist})
            i0, ig = r.report_deg.index(0.0), r.report_deg.index(GRAZING_DEG)
            out.append({
                "target": target, "distribution": dist, "alpha": alpha,
                "k_d": r.fitted[0], "k_s": r.fitted[1], "p": r.fitted[2],
                "p_phong_rule": phong_exponent(alpha), "p_blinn_rule": blinn_phong_exponent(alpha),
                "rel_l2": r.rel_l2, "residual_normal": r.residual[i0],
                "residual_grazing": r.residual[ig],
                "albedo_diff_normal": r.albedo_fit[i0] - r.albedo_target[i0],
                "albedo_diff_grazing": r.albedo_fit[ig] - r.albedo_target[ig],
                "albedo_target_grazing": r.albedo_target[ig], "seconds": r.seconds,
                "worst": r.worst})
    return out


def markdown_table(table: list[dict]) -> str:
    """The rows as a Markdown table."""
    head = ("| target | D | α | fitted p | p = (1/α²−1)/2 | fitted ÷ rule | p_h = 2/α²−2 | k_d | k_s "
            f"| rel. L2 | r(0°) | r({GRAZING_DEG:g}°) | Δa(0°) | Δa({GRAZING_DEG:g}°) | worst θ_i, θ_o |\n"
            "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n")
    lines = [f"| {r['target']} | {r['distribution']} | {r['alpha']:g} | {r['p']:.1f} "
             f"| {r['p_phong_rule']:.1f} | {r['p'] / r['p_phong_rule']:.2f} "
             f"| {r['p_blinn_rule']:.1f} | {r['k_d']:.3f} "
             f"| {r['k_s']:.3f} | {r['rel_l2']:.3f} | {r['residual_normal']:.3f} "
             f"| {r['residual_grazing']:.3f} | {r['albedo_diff_normal']:+.3f} "
             f"| {r['albedo_diff_grazing']:+.3f} "
             f"| {r['worst']['theta_i_deg']:.0f}°, {r['worst']['theta_o_deg']:.0f}° |" for r in table]
    return head + "\n".join(lines) + "\n"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--json", required=True, help="where to write the numbers")
    ap.add_argument("--markdown", default=None,
                    help="a Markdown file whose table between the markers is replaced")
    args = ap.parse_args(argv)
    registration.register()
    table = rows()
    Path(args.json).parent.mkdir(parents=True, exist_ok=True)
    write_json(args.json, table, indent=1, end="\n")
    if args.markdown:
        example = format_result(fit(*EXAMPLE))
        replace_table(Path(args.markdown), markdown_table(table))
        replace_table(Path(args.markdown), "```\n" + example + "\n```\n", EXAMPLE_MARKERS)
    return 0


BEGIN, END = "<!-- fitting-table: begin -->", "<!-- fitting-table: end -->"
#: The example report the page shows (``phonglab fit roughconductor --set alpha=0.2``).
EXAMPLE = ("roughconductor", {"alpha": 0.2})
EXAMPLE_MARKERS = ("<!-- fitting-example: begin -->", "<!-- fitting-example: end -->")


def replace_table(path: Path, table: str, markers: tuple[str, str] = (BEGIN, END)) -> None:
    """Replace the text between the two markers in ``path`` with ``table``."""
    text = path.read_text()
    start, stop = text.index(markers[0]) + len(markers[0]), text.index(markers[1])
    path.write_text(text[:start] + "\n" + table + text[stop:])


if __name__ == "__main__":
    raise SystemExit(main())
