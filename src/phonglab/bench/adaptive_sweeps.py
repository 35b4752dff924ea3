r"""Bench part ``adaptive``: error against wall time for uniform, adaptive and planned renders.

Per scene of :attr:`Config.adaptive_scenes` (small resolutions), against a converged full-depth
reference (:func:`phonglab.engine.references.reference`, its noise subtracted from every error):

* **uniform**: the scene's own integrator through :func:`phonglab.engine.render.render_scene` (one
  pass, ``mi.render``) at the spp ladder of :attr:`Config.adaptive_spps`;
* **adaptive**: :func:`phonglab.engine.adaptive.render_adaptive` at the targets of
  :attr:`Config.adaptive_targets`, several seeds;
* **planned**: :func:`phonglab.planner.plan` at each target, then the render it chose
  (:mod:`phonglab.planner.execute`, as ``phonglab render --target-error`` runs it); its
  time is the render's plus the pilot's (``pilot_seconds``), i.e. what the user waits for.

Times are steady state (each configuration compiled once first) and measured side by side in
one process.  **Speed-up at equal error**: each adaptive (planned) render is followed by a
uniform render of the scene's integrator at its mean spp (the plan's uniform spp), so load
drift cancels within the pair; uniform sampling would need ``t_u (e_u/e)²`` to reach the
render's error e (noise ∝ 1/√time), and the speed-up ``t_u (e_u/e)² / t`` is reported per
seed and target (median and range).  On the furnace enclosure (every pixel the same variance) adaptive sampling cannot
win: its speed-up there measures its overhead, target >= 1/1.05.

**Guards** (:func:`guard_rows`): at one target, with and without the neighbourhood rule,
the fraction of pixels whose true error exceeds three standard errors (|x − r| >
3√(s² + s_r²): 0.27 % if the error estimate is honest and Gaussian) and the fraction whose
true relative error exceeds three times its budget e_p* (pixels stopped too early).

**Oracle** (:func:`oracle_row`): per scene of :attr:`Config.adaptive_oracle_scenes`,
at full depth (unbiased against the cached full-depth reference, so every error is noise), the
speed-up of the best per-pixel allocation, mean(u)/mean(√u)² (:func:`phonglab.engine.adaptive.
neyman_gain`) from a converged map of u, the relative variance one sample of each source
pixel adds to the image's relative MSE (a uniform render of :data:`ORACLE_MAP_SPP` samples
per pixel with the exact squared-weight filter sums: the filter spreads each sample over
several pixels, so the per-target-pixel mean(v)/mean(√v)² of ``oracle_speedup`` is the limit
only for a box filter), beside the
speed-up adaptive sampling achieves at the scene's planner target E (paired with uniform
renders as above, wall time included).  Targets: achieved >= :data:`ORACLE_SHARE` of the
cost-aware oracle mean(u)·mean(c)/mean(√(u c))² (c the cost map of
:meth:`phonglab.engine.wavefront.Wavefront.cost_map`) where it is >=
:data:`ORACLE_MATTERS`, cost <= :data:`OVERHEAD_TARGET` of uniform where it is 1.

Writes ``adaptive.json``, ``adaptive_error_time.png`` (one panel per scene, Pareto front
dashed) and ``adaptive_sppmap.png`` (image and spp map of gray_direct).
"""

from __future__ import annotations

import json
import statistics
import time
from pathlib import Path
from typing import Any

import numpy as np

from .. import planner
from ..engine import adaptive, metrics, references, render, scenes, spp_map, wavefront
from ..planner import execute
from ..runtime import quiet_mitsuba, set_variant
from .analysis import pareto_front
from .config import VARIANT, Config
from ..engine.outputs import write_json

#: The scene whose variance is the same in every pixel (the overhead measurement).
UNIFORM_SCENE = "check_furnace_enclosure"
#: Largest acceptable cost of adaptive sampling against uniform on :data:`UNIFORM_SCENE`.
OVERHEAD_TARGET = 1.05
#: Resolution of :data:`UNIFORM_SCENE` (40 bounces a sample: 32² is already a long render).
UNIFORM_SCENE_RES = 32


#: Samples per pixel of the oracle's variance map.
ORACLE_MAP_SPP = 256
#: Adaptive sampling should reach this share of the oracle's speed-up ...
ORACLE_SHARE = 0.8
#: ... wherever the oracle is at least this.
ORACLE_MATTERS = 1.3
#: Probe paths per pixel of the oracle rows' cost map (:meth:`phonglab.engine.wavefront.Wavefront.cost_map`).
ORACLE_COST_SPP = 16
#: Reference spp of the oracle rows (the planner bench's at 128², cached: its noise is
#: subtracted from every error; measured, 0.14–0.28 E on four of the seven scenes, 0.37 E on
#: glass_slab, 0.57 E on outdoor_envmap, 0.87 E on nb_sphere_row: docs/adaptive.md, issue 53).
ORACLE_REFERENCE_SPP = 4096


def scene_params(name: str, cfg: Config) -> dict[str, Any]:
    return {"res": UNIFORM_SCENE_RES if name == UNIFORM_SCENE else cfg.adaptive_res}


def _error(image, ref) -> float:
    return metrics.relative_rmse(image, ref.image, ref_stderr=ref.stderr)


def _timed(fn):
    t0 = time.perf_counter()
    out = fn()
    return out, time.perf_counter() - t0


def _planned(name: str, params: dict, target: float, ref, seed: int) -> dict:
    """plan() then the render it chose (:func:`phonglab.planner.execute.prepare`, the scene the
    pilot loaded): error and the time a user waits (pilot included)."""
    with quiet_mitsuba():
        plan = planner.plan(name, planner.PlanOptions(target, params=params))
    job = execute.prepare(plan)
    job.render(seed)                                        # compile
    result, seconds = _timed(lambda: job.render(seed))
    set_variant(VARIANT)                  # the plan may have switched to another variant
    return {"method": "planned", "target": target, "seed": seed, "render_seconds": seconds,
            "pilot_seconds": plan.pilot.seconds, "seconds": seconds + plan.pilot.seconds,
            "render": f"{plan.render.model} {plan.render.sampling}"
                      + (f" {plan.render.sampler}" if plan.render.sampler != "independent"
                         else ""),
            "variant": plan.variant,
            "uniform_spp": plan.uniform.spp,
            "max_depth": plan.max_depth,
            "error": execute.error_report(plan, result, ref).achieved}


def sweep_scene(name: str, cfg: Config, progress: bool = False) -> dict[str, Any]:
    """Every row of one scene, and its equal-error speed-ups."""
    params = scene_params(name, cfg)
    ref = references.reference(name, cfg.adaptive_reference_spp, params=params)
    info = scenes.inspect_scene(name, **params)
    with quiet_mitsuba():
        loaded = scenes.load_scene(info.path, VARIANT, **params)
    rows: list[dict[str, Any]] = []
    render.render_scene(loaded, 4, seed=999)
    for spp in cfg.adaptive_spps:
        for seed in range(cfg.adaptive_seeds):
            res, t = _timed(lambda: render.render_scene(loaded, spp, seed=10 + seed))
            rows.append({"method": "uniform", "spp": spp, "seed": seed, "seconds": t,
                         "error": _error(res.image, ref)})
    # compile at the smallest target: an easy one stops after the pilot, and the later passes'
    # kernels (Q masked to its pixels, or none) were then compiled inside a measured render
    adaptive.render_adaptive(loaded, min(cfg.adaptive_targets), seed=998)
    for target in cfg.adaptive_targets:
        for seed in range(cfg.adaptive_seeds):
            res, t = _timed(lambda: adaptive.render_adaptive(loaded, target, seed=20 + seed))
            row = {"method": "adaptive", "target": target, "seed": seed, "seconds": t,
                   "spp": res.total_spp, "passes": len(res.passes),
                   "estimated_error": res.estimated_error, "error": _error(res.image, ref)}
            rows.append(_paired(row, loaded, round(res.total_spp), 50 + seed, ref))
        if name != UNIFORM_SCENE and target in cfg.adaptive_planned_targets:
            p = _planned(name, params, target, ref, seed=30)
            rows.append(_paired(p, loaded, p["uniform_spp"], 60, ref))
    return {"scene": name, "params": params, "reference_spp": ref.spp, "rows": rows,
            "speedups": speedups(rows)}


def _paired(row: dict, loaded, spp: int, seed: int, ref) -> dict:
    """Add a uniform render of the scene's integrator at ``spp`` made right after the row's
    render (load drift cancels within the pair): its time and error."""
    res, t = _timed(lambda: render.render_scene(loaded, max(1, int(spp)), seed=seed))
    return dict(row, pair_spp=int(spp), pair_seconds=t, pair_error=_error(res.image, ref))


def speedups(rows: list[dict]) -> dict[str, dict[str, float]]:
    """Per method: median, min, max over rows of the equal-error speed-up against the paired
    uniform render: t_u (e_u/e)² / t, the time uniform sampling needs for the row's error e
    (noise ∝ 1/√time) over the row's time."""
    out = {}
    for method, key in (("adaptive", "seconds"), ("planned", "seconds"),
                        ("planned", "render_seconds")):
        ratios = [r["pair_seconds"] * (r["pair_error"] / r["error"]) ** 2 / r[key] for r in rows
                  if r["method"] == method and r["error"] > 0 and "pair_seconds" in r]
        if ratios:
            label = method if key == "seconds" else "planned_render_only"
            out[label] = {"median": statistics.median(ratios), "min": min(ratios),
                          "max": max(ratios), "n": len(ratios)}
    return out


def oracle_limits(loaded, integrator, target: float) -> dict[str, float]:
    """The sample and time oracles of a loaded scene (untimed): a :data:`ORACLE_MAP_SPP`
    variance map of u (every pixel the same count, with the exact sums) and a
    :data:`ORACLE_COST_SPP` cost map."""
    vmap = adaptive.render_adaptive(loaded, target, seed=70, min_spp=ORACLE_MAP_SPP,
                                    max_spp=ORACLE_MAP_SPP, integrator=integrator)
    costs = wavefront.Wavefront(loaded, integrator).cost_map(seed=71, spp=ORACLE_COST_SPP)
    return {"oracle": adaptive.neyman_gain(vmap.source_variance),
            "oracle_time": adaptive.neyman_gain(vmap.source_variance, costs),
            "map_spp": ORACLE_MAP_SPP}


def oracle_seed(loaded, integrator, target: float, ref, seed: int,
                decompose: bool = False) -> dict[str, Any]:
    """One timed seed of an oracle row: the adaptive render, then right after it ``mi.render``
    at its mean spp (the pair: load drift cancels within it); errors against ``ref`` (None:
    not computed).  ``decompose`` adds, after the pair, the two one-pass wavefront traces of
    :func:`cost_factors`: adaptive's final counts, and the same total spread evenly (neither
    with the exact sums Q)."""
    res, t = _timed(lambda: adaptive.render_adaptive(loaded, target, seed=80 + seed,
                                                     integrator=integrator))
    spp = max(1, round(res.total_spp))
    u, tu = _timed(lambda: render.render_scene(loaded, spp, seed=90 + seed,
                                               integrator=integrator))
    row = {"method": "adaptive", "target": target, "seed": seed, "seconds": t,
           "spp": res.total_spp, "passes": len(res.passes),
           "trace_seconds": sum(p["trace_seconds"] for p in res.passes),
           "pair_spp": spp, "pair_seconds": tu}
    if decompose:
        counts = res.spp.ravel().astype(np.int64)
        flat = np.full(counts.size, counts.sum() // counts.size, dtype=np.int64)
        flat[:counts.sum() - flat.sum()] += 1                 # the same total, spread evenly
        row["one_pass_seconds"] = _timed(
            lambda: wavefront.Wavefront(loaded, integrator).trace(counts, 2080 + seed))[1]
        row["one_pass_uniform_seconds"] = _timed(
            lambda: wavefront.Wavefront(loaded, integrator).trace(flat, 3080 + seed))[1]
    if ref is not None:
        row["error"], row["pair_error"] = _error(res.image, ref), _error(u.image, ref)
    return row


#: The factors of :func:`cost_factors`, in the order they multiply.
COST_FACTORS = ("wavefront", "placement", "passes", "host")


def cost_factors(rows: list[dict]) -> dict[str, Any]:
    """Adaptive's time over ``mi.render``'s at its mean spp as a product of four factors, of
    the medians over seeds of :func:`oracle_seed` rows made with ``decompose``:

    * wavefront = one pass of uniform counts / ``mi.render`` (its splats and moments);
    * placement = one pass of adaptive's final counts / one pass of uniform counts (what the
      pixels that get the samples cost: their paths);
    * passes = the render's own tracing / that one pass (several launches; Q over the pilot
      and over the edge pixels of later passes);
    * host = the whole render / its tracing (developing the image, estimates, allocation).
    """
    keys = ("seconds", "trace_seconds", "pair_seconds", "one_pass_seconds",
            "one_pass_uniform_seconds", "spp", "passes")
    m = {k: statistics.median(r[k] for r in rows) for k in keys}
    factors = {"wavefront": m["one_pass_uniform_seconds"] / m["pair_seconds"],
               "placement": m["one_pass_seconds"] / m["one_pass_uniform_seconds"],
               "passes": m["trace_seconds"] / m["one_pass_seconds"],
               "host": m["seconds"] / m["trace_seconds"]}
    return {"medians": m, "factors": factors, "total": m["seconds"] / m["pair_seconds"]}


def oracle_summary(limits: dict, rows: list[dict]) -> dict[str, Any]:
    """An oracle row's figures from its :func:`oracle_limits` and timed :func:`oracle_seed`
    rows: the speed-up achieved at equal time (:func:`speedups`), its share of each oracle,
    the two factors of the share (equal samples, cost per sample) and the row's target."""
    oracle, oracle_time = limits["oracle"], limits["oracle_time"]
    achieved = speedups(rows).get("adaptive", {})
    share = achieved.get("median", float("nan")) / oracle
    share_time = achieved.get("median", float("nan")) / oracle_time
    # The two factors of the share: how well the samples were placed (equal samples, the
    # oracle's own terms) and what adaptive's samples cost against uniform's (they sit in the
    # noisy pixels, whose paths may be longer or shorter than the image's mean).
    by_samples = statistics.median((r["pair_error"] / r["error"]) ** 2 * r["pair_spp"] / r["spp"]
                                   for r in rows)
    cost = statistics.median((r["seconds"] / r["spp"]) / (r["pair_seconds"] / r["pair_spp"])
                             for r in rows)
    if oracle_time >= ORACLE_MATTERS:
        goal, met = f">= {ORACLE_SHARE} of the time oracle", bool(share_time >= ORACLE_SHARE)
    elif oracle_time < 1.05:
        overhead = 1.0 / achieved.get("median", float("nan"))
        goal, met = f"cost <= {OVERHEAD_TARGET}x uniform", bool(overhead <= OVERHEAD_TARGET)
    else:
        goal, met = "none (oracle below 1.3x)", None
    return {"oracle": oracle, "oracle_time": oracle_time, "map_spp": limits["map_spp"],
            "achieved": achieved, "share": share, "share_time": share_time,
            "equal_samples": by_samples, "sample_cost": cost, "goal": goal, "met": met}


def oracle_row(name: str, target: float, params: dict, cfg: Config) -> dict[str, Any]:
    """The oracle's speed-up and adaptive sampling's at ``target``, both at full depth."""
    ref = references.reference(name, ORACLE_REFERENCE_SPP, params=params)
    info = scenes.inspect_scene(name, **params)
    with quiet_mitsuba():
        loaded = scenes.load_scene(info.path, VARIANT, **params)
    integ = scenes.path_integrator(-1, info)
    limits = oracle_limits(loaded, integ, target)
    render.render_scene(loaded, 4, seed=999, integrator=integ)                 # compile
    adaptive.render_adaptive(loaded, target, seed=998, integrator=integ)  # every pass's kernel
    rows = [oracle_seed(loaded, integ, target, ref, seed) for seed in range(cfg.adaptive_seeds)]
    return {"scene": name, "params": params, "target": target, "reference_spp": ref.spp,
            **oracle_summary(limits, rows), "rows": rows}


def guard_rows(name: str, cfg: Config, target: float) -> list[dict[str, Any]]:
    """What the neighbourhood guard does: early-stopped pixels with and without it."""
    params = scene_params(name, cfg)
    ref = references.reference(name, cfg.adaptive_reference_spp, params=params)
    with quiet_mitsuba():
        loaded = scenes.load_scene(name, VARIANT, **params)
    out = []
    for guard in (True, False):
        for seed in range(cfg.adaptive_seeds):
            r = adaptive.render_adaptive(loaded, target, seed=40 + seed, neighbourhood=guard)
            d = r.image.astype(np.float64) - ref.image
            z = np.abs(d) / np.sqrt(r.stderr.astype(np.float64) ** 2 + ref.stderr ** 2 + 1e-30)
            true_rel = np.sqrt(np.mean(d * d / (ref.image ** 2 + metrics.REL_EPS), axis=2))
            est_rel = np.sqrt(wavefront.relative_error_map(r.image, r.stderr.astype(np.float64) ** 2))
            out.append({"scene": name, "neighbourhood": guard, "seed": seed, "target": target,
                        "error": _error(r.image, ref), "spp": r.total_spp,
                        "frac_z_above_3": float(np.mean(z > 3)),
                        "frac_true_above_3x_estimate": float(np.mean(true_rel > 3 * est_rel)),
                        "frac_at_min_spp": float(np.mean(r.spp == adaptive.MIN_SPP))})
    return out


def chart(data: dict, out: Path) -> Path:
    """adaptive_error_time.png: one log-log panel per scene, Pareto front dashed."""
    from matplotlib.figure import Figure
    from matplotlib.ticker import NullFormatter

    scenes_ = data["scenes"]
    fig = Figure(figsize=(4.2 * len(scenes_), 3.6), layout="constrained")
    axes = fig.subplots(1, len(scenes_), squeeze=False)[0]
    style = {"uniform": "o", "adaptive": "s", "planned": "^"}
    for ax, sc in zip(axes, scenes_):
        pts = []
        for method, marker in style.items():
            rows = [r for r in sc["rows"] if r["method"] == method and r["error"] > 0]
            if rows:
                ax.plot([r["seconds"] for r in rows], [r["error"] for r in rows], marker,
                        ms=4, alpha=0.8, label=method + (" (pilot incl.)" if method == "planned"
                                                          else ""))
                pts += [(r["seconds"], r["error"]) for r in rows]
        front = pareto_front(pts)
        if front:
            ft, fe = zip(*front)
            ax.step(ft, fe, where="post", color="k", lw=0.8, ls="--", label="Pareto front")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.xaxis.set_minor_formatter(NullFormatter())
        ax.yaxis.set_minor_formatter(NullFormatter())
        ax.set_xlabel("wall time [s] (steady state; planned: + pilot)")
        ax.set_ylabel("relative RMSE")
        ax.set_title(f"{sc['scene']} ({sc['params']['res']}²)", fontsize=9)
        ax.grid(True, which="both", alpha=0.25)
        ax.legend(fontsize=7)
    path = out / "adaptive_error_time.png"
    fig.savefig(path, dpi=110)
    return path


def sppmap_figure(cfg: Config, out: Path, target: float) -> Path:
    """adaptive_sppmap.png: gray_direct's adaptive image beside its spp map."""
    with quiet_mitsuba():
        loaded = scenes.load_scene("gray_direct", VARIANT, res=max(cfg.adaptive_res, 64))
    r = adaptive.render_adaptive(loaded, target, seed=1)
    return spp_map.write_spp_png(out / "adaptive_sppmap.png", r.spp, r.image)


def sweep_adaptive(out: Path, cfg: Config, progress: bool = False) -> dict[str, Any]:
    """Run the part; writes adaptive.json and the two figures into ``out``."""
    out = Path(out)
    data: dict[str, Any] = {"scenes": [sweep_scene(n, cfg, progress)
                                       for n in cfg.adaptive_scenes]}
    target = cfg.adaptive_targets[len(cfg.adaptive_targets) // 2]
    data["guards"] = [g for n in cfg.adaptive_scenes if n != UNIFORM_SCENE
                      for g in guard_rows(n, cfg, target)]
    data["oracle"] = [oracle_row(n, e, p, cfg) for n, (e, p) in cfg.adaptive_oracle_scenes.items()]
    uniform = next(s for s in data["scenes"] if s["scene"] == UNIFORM_SCENE)
    over = uniform["speedups"].get("adaptive", {}).get("median", float("nan"))
    data["overhead"] = {"scene": UNIFORM_SCENE, "cost_vs_uniform": 1.0 / over,
                        "target": OVERHEAD_TARGET, "met": bool(1.0 / over <= OVERHEAD_TARGET)}
    data["charts"] = [str(chart(data, out)), str(sppmap_figure(cfg, out, target))]
    write_json(out / "adaptive.json", data, indent=2, end="\n")
    return data


def report_section(out: Path, rel: str = ".") -> list[str]:
    """The BENCHMARKS.md section of this part (empty when it did not run); ``rel`` is the
    folder of the figures relative to the Markdown file."""
    path = Path(out) / "adaptive.json"
    if not path.is_file():
        return []
    data = json.loads(path.read_text())
    L = ["\n## Adaptive sampling: error against time\n",
         "`phonglab.bench.adaptive_sweeps` (docs/adaptive.md): uniform (`mi.render`), adaptive "
         "(`phonglab.engine.adaptive`) and planned (`planner.plan` + its render, pilot included) renders "
         "against a converged reference; steady-state times side by side in one process. "
         "Speed-up at equal error = t_u (e_u/e)²/t against a uniform render made right after "
         "at the same mean spp (the plan's uniform spp for planned); median [min–max] over "
         "seeds and targets.\n",
         "| scene | adaptive speed-up | planned: render only | planned: pilot included |",
         "|---|---|---|---|"]
    for sc in data["scenes"]:
        cells = []
        for m in ("adaptive", "planned_render_only", "planned"):
            s = sc["speedups"].get(m)
            cells.append(f"{s['median']:.2f}x [{s['min']:.2f}–{s['max']:.2f}]" if s else "—")
        L.append(f"| {sc['scene']} ({sc['params']['res']}²) | " + " | ".join(cells) + " |")
    o = data["overhead"]
    L.append(f"\nUniform-variance scene ({o['scene']}): adaptive costs {o['cost_vs_uniform']:.3f}x "
             f"uniform at equal error (target <= {o['target']}: {'met' if o['met'] else 'missed'}).\n")
    L += ["| scene | neighbourhood guard | error | mean spp | pixels |x−r| > 3σ | "
          "pixels true error > 3x estimate |", "|---|---|---|---|---|---|"]
    for g in data["guards"]:
        L.append(f"| {g['scene']} | {'on' if g['neighbourhood'] else 'off'} | {g['error']:.4f} | "
                 f"{g['spp']:.1f} | {100 * g['frac_z_above_3']:.2f} % | "
                 f"{100 * g['frac_true_above_3x_estimate']:.2f} % |")
    if data.get("oracle"):
        L += ["\n### Adaptive sampling against its limit (issue 28)\n",
              "Oracle: the speed-up of the best per-pixel allocation at equal samples, "
              "mean(u)/mean(√u)² with u_q the relative variance one sample of source pixel q "
              "adds to the image's relative MSE through the film's filter (Neyman allocation "
              "for phonglab's relative MSE; `adaptive.neyman_gain`), from a "
              f"{ORACLE_MAP_SPP}-spp variance map; achieved: adaptive sampling at the scene's "
              "planner target E against a uniform render of the same mean spp, wall time "
              "included (median [min–max] over seeds). Both at full depth, against the cached "
              "full-depth reference, so the errors are noise only. The share splits into two "
              "factors: the speed-up at equal samples ((e_u/e)² at the same mean spp: how "
              "well the samples were placed, the oracle's own terms) and the cost of one of "
              "adaptive's samples over one of uniform's (they sit in the noisy pixels, whose "
              "paths may cost more or less than the image's mean; the oracle counts samples, "
              "not time). The time oracle is the limit at equal time, "
              "mean(u)·mean(c)/mean(√(u c))², c_q the cost of one sample of pixel q "
              "(`phonglab.engine.cost`: a + the rays of path's camera path); where it is 1 "
              "(no pixel can be sampled more cheaply for its variance) only the overhead "
              "target applies.\n",
              "| scene | E | oracle (samples) | oracle (time) | achieved (equal time) | "
              "achieved / time oracle | equal samples | cost per sample vs uniform | target "
              "| met |",
              "|---|---|---|---|---|---|---|---|---|---|"]
        for o in data["oracle"]:
            a = o["achieved"]
            got = f"{a['median']:.2f}x [{a['min']:.2f}–{a['max']:.2f}]" if a else "—"
            met = "—" if o["met"] is None else ("**met**" if o["met"] else "**missed**")
            size = "×".join(str(o["params"][k]) for k in ("width", "height")) \
                if "width" in o["params"] else f"{o['params']['res']}²"
            L.append(f"| {o['scene']} ({size}) | {o['target']} | {o['oracle']:.2f}x | "
                     f"{o.get('oracle_time', float('nan')):.2f}x | {got} | "
                     f"{o.get('share_time', float('nan')):.2f} | {o['equal_samples']:.2f}x | "
                     f"{o['sample_cost']:.2f}x | {o['goal']} | {met} |")
    L += ["", f"![error against time]({rel}/adaptive_error_time.png)", "",
          f"![adaptive image and spp map]({rel}/adaptive_sppmap.png)", ""]
    return L
