"""``--report PATH.html``: one self-contained HTML file of a validation report.

Contents: the table of rows (status coloured), the directional albedo against θ_i with its
band (from the ``energy`` row's details), lobe slices (eval and pdf in the plane of incidence),
and for each failing χ² cell the histogram beside the integrated pdf and the residual map
(obs − exp)/√exp on a diverging colour scale with symmetric limits.  Each row's topic links its
page of the docs site (the row's ``doc`` against :data:`.kind.DOCS_URL`).  Figures are matplotlib
PNGs embedded as base64 ``data:`` URIs; the file loads nothing from outside itself.
"""

from __future__ import annotations

import base64
import html
import io
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from ..engine.outputs import write_text  # noqa: E402
from ..verdict import Report, cells, evidence, header, point_label  # noqa: E402
from . import registry  # noqa: E402
from .kind import topic_url  # noqa: E402

COLOURS = {"pass": "#d8f0d8", "fail": "#f6d0d0", "KNOWN": "#f6ecc8", "skipped": "#e6e6e6",
           "advice": "#dce8f8"}
STYLE = ("body{font-family:sans-serif;margin:1.5em;max-width:1100px}"
         "table{border-collapse:collapse;font-size:13px}td,th{border:1px solid #bbb;"
         "padding:3px 6px;vertical-align:top}td.reason{font-size:11px;color:#333}"
         "img{max-width:100%}")


def _png(fig) -> str:
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=90, bbox_inches="tight")
    plt.close(fig)
    return "data:image/png;base64," + base64.b64encode(buf.getvalue()).decode("ascii")


def _img(uri: str, alt: str) -> str:
    return f'<p><img alt="{html.escape(alt)}" src="{uri}"></p>'


def _topic_link(row, text) -> str:
    """The topic cell: a link to the topic's page of the docs site (:func:`.kind.topic_url`)."""
    url = topic_url(row.doc)
    text = html.escape(str(text))
    return f'<a href="{html.escape(url)}">{text}</a>' if url else text


def _table(report: Report) -> str:
    swept = any(r.point is not None for r in report.rows)
    rows = ["<tr>" + "".join(f"<th>{h}</th>" for h in ("point",) * swept + header()
                             + ("reason",)) + "</tr>"]
    for r in report.rows:
        rows.append(f'<tr style="background:{COLOURS.get(r.status, "#fff")}">'
                    + (f"<td>{html.escape(point_label(r.point))}</td>" if swept else "")
                    + "".join(f"<td>{_topic_link(r, c) if i == 1 else html.escape(str(c))}</td>"
                              for i, c in enumerate(cells(r)))
                    + f'<td class="reason">{html.escape(r.reason)}'
                    + (f"<br><b>{html.escape(evidence(r))}</b>" if r.status == "fail"
                       and evidence(r) else "") + "</td></tr>")
    return "<table>" + "".join(rows) + "</table>"


def _albedo(d: dict) -> str:
    th, a, band = (np.array(d[k], dtype=float) for k in ("theta_deg", "albedo", "band"))
    fig, ax = plt.subplots(figsize=(6, 3.5))
    ax.fill_between(th, a - band, a + band, alpha=0.3, label="band (z·stderr + quadrature)")
    ax.plot(th, a, "o-", label="directional albedo")
    ax.axhline(1.0, color="k", lw=0.8, ls="--", label="1 (energy conservation)")
    ax.set_xlabel("θ_i (degrees)")
    ax.set_ylabel("albedo")
    ax.legend(fontsize=8)
    return _img(_png(fig), "albedo against incidence")


def _lobes(d: dict) -> str:
    t = np.array(d["theta_o_deg"])
    slices = d["slices"]
    fig, axes = plt.subplots(1, len(slices), figsize=(3.2 * len(slices), 3), squeeze=False)
    for ax, s in zip(axes[0], slices):
        ev, pd = np.array(s["eval"]), np.array(s["pdf"])
        ax.plot(t, ev, label="eval (f cos θ_o)")
        ax.plot(t, pd, ls="--", label="pdf")
        ax.axvline(-s["theta_i_deg"], color="grey", lw=0.5)
        ax.set_title(f"θ_i = {s['theta_i_deg']:g}°", fontsize=9)
        ax.set_xlabel("θ_o in the plane of incidence (°)", fontsize=8)
    axes[0][0].legend(fontsize=7)
    return _img(_png(fig), "lobe slices: eval and pdf")


def _chi2_cells(d: dict) -> str:
    out = []
    extent = (-180, 180, -1, 1)   # the bins' second coordinate is −cos θ_o: row 0 is cos θ_o = 1
    for cell in d.get("cells", []):
        if cell.get("status") != "fail" or "histogram" not in cell:
            continue
        hist, exp = np.array(cell["histogram"]), np.array(cell["expected"])
        res = np.array(cell["residual"], dtype=float) if "residual" in cell else None
        n = 2 if res is None else 3
        fig, axes = plt.subplots(1, n, figsize=(4.5 * n, 3.4), layout="constrained")
        vmax = max(hist.max(), exp.max(), 1e-12)
        for ax, img, title in ((axes[0], hist, "histogram of samples"),
                               (axes[1], exp, "expected (integrated pdf)")):
            im = ax.imshow(img, aspect="auto", origin="upper", vmin=0, vmax=vmax, extent=extent)
            ax.set_title(title, fontsize=9)
        fig.colorbar(im, ax=axes[:2].tolist())
        if res is not None:
            lim = float(np.nanmax(np.abs(res))) if np.isfinite(res).any() else 1.0
            im = axes[2].imshow(res, aspect="auto", origin="upper", cmap="RdBu_r", vmin=-lim,
                                vmax=lim, extent=extent)
            axes[2].set_title("residual (obs − exp)/√exp (blank: pooled/empty)", fontsize=9)
            fig.colorbar(im, ax=axes[2])
        for ax in axes:
            ax.set_xlabel("φ_o (°)")
            ax.set_ylabel("cos θ_o")
        fig.suptitle(f"χ² cell θ_i = {cell.get('theta_deg', 0):.1f}°, φ_i = "
                     f"{cell.get('phi', 0):.2f}: p = {cell.get('p_value', 0):.3g}", fontsize=10)
        out.append(_img(_png(fig), "chi2 histogram, expected and residual"))
    return "".join(out)


def render(report: Report) -> str:
    """The HTML text of ``report``."""
    m = report.meta
    # a report without "plugin" (a caller's own meta) keys the label by its kind's name
    name = m.get("plugin") or next((m[k.name] for k in registry.KINDS if k.name in m), "?")
    word = registry.by_name(m["kind"]).word + " " if m.get("kind") in registry.names() else ""
    title = f"phonglab validate: {word}{name} ({m.get('variant', '?')})"
    verdict = "PASSED" if report.passed else f"FAILED ({len(report.failing)} rows)"
    parts = [f"<!DOCTYPE html><html><head><meta charset='utf-8'><title>{html.escape(title)}"
             f"</title><style>{STYLE}</style></head><body>",
             f"<h1>{html.escape(title)}</h1><p><b>{verdict}</b>; seed {m.get('seed')}, "
             f"{'quick' if m.get('quick') else 'default'} sizes, {m.get('seconds')} s</p>",
             _table(report)]
    advice = (m.get("sweep") or {}).get("advice") or []
    if advice:
        parts += ["<h2>Advice</h2><p>A physical bound exceeded at a probed parameter value, "
                  "outside any declared or documented range (not a fail):</p><ul>"
                  + "".join(f"<li>{html.escape(a['topic'])}: {html.escape(a['text'])}</li>"
                            for a in advice) + "</ul>"]
    for r in report.rows:
        at = (f" at {html.escape(point_label(r.point))}" if r.point is not None else "")
        if r.topic == "energy" and "albedo" in r.details:
            parts += [f"<h2>Directional albedo{at}</h2>", _albedo(r.details)]
            if "lobes" in r.details:
                parts += [f"<h2>Lobe slices{at}</h2>", _lobes(r.details["lobes"])]
        if r.topic == "chi2" and r.status in ("fail", "KNOWN"):
            cells = _chi2_cells(r.details)
            if cells:
                parts += [f"<h2>Failing χ² cells{at} ({r.status})</h2>", cells]
    parts.append("</body></html>")
    return "\n".join(parts)


def write(report: Report, path) -> Path:
    path = Path(path)
    write_text(path, render(report))
    return path
