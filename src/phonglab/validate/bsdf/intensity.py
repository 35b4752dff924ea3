r"""The ``intensity`` topic: M00 in a polarized variant against what the same plugin returns in
the matching unpolarized variant, direction by direction (the derivation and tolerances are in
:mod:`.polarization`'s docstring).  The unpolarized reference runs in a child process: it sets
that variant, registers phonglab's plugins, runs the ``--plugin`` files and loads the spec
again (:func:`reference`).
"""

from __future__ import annotations

import ast
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import mitsuba as mi
import numpy as np

import phonglab
from . import lanes
from ..roundoff import ABS_FLOOR, REL_TOL
from .polarization import eval_lanes, mueller_eval, mueller_sample, sizes, skipped, wavelengths
from .rows import ROUND_OFF, bounded_row, max_finite
from .topics import Row


# ----------------------------------------------------------------------------- intensity
def unpolarized_variant(variant: str) -> str:
    """``llvm_ad_spectral_polarized`` -> ``llvm_ad_spectral``."""
    return variant.replace("_polarized", "")


def provenance(bsdf, opts):
    """(spec for mi.load_dict or {"file": xml}, plugin files) of the BSDF under validation,
    or None when it was given as a loaded object.

    :func:`phonglab.validate.core.run` hands the topics the prepared target
    (``opts.source``, a :class:`phonglab.settings.Loaded`: its spec with the ``--set`` values
    merged, and the ``--plugin`` files run before it loaded).  A Python plugin registered by
    the caller's own code through ``core.load_plugins`` outside a run has no record of its file:
    its class's functions name the file it came from.
    """
    source = getattr(opts, "source", None)
    if source is None or source.plugin is not bsdf or source.spec is None:
        return None
    files = list(source.files)
    cls = type(bsdf)
    if not files and cls.__module__ == "__phonglab_plugin__":   # run by core.load_plugins
        for v in vars(cls).values():
            code = getattr(v, "__code__", None)
            if code is not None and Path(code.co_filename).is_file():
                files.append(str(Path(code.co_filename).resolve()))
                break
    return source.spec, files


_CHILD = r"""
import json, runpy, sys
import numpy as np
args = json.load(open(sys.argv[1]))
import phonglab
phonglab.register(args["variant"])
import mitsuba as mi
from phonglab import probe
for f in args["plugins"]:
    runpy.run_path(f, run_name="__phonglab_plugin__")
spec = args["spec"]
try:
    if set(spec) == {"file"}:
        bsdf = mi.load_string(open(spec["file"]).read())
    else:
        bsdf = mi.load_dict(spec)
except Exception as exc:
    print(str(exc).strip().splitlines()[-1] if str(exc).strip() else repr(exc), file=sys.stderr)
    sys.exit(3)
d = np.load(sys.argv[2])
ev = probe.eval(bsdf, d["wi"], d["wo"])
s = probe.sample(bsdf, d["swi"], d["u1"], d["u2"])
np.savez(sys.argv[3], eval=ev, wo=s.wo, weight=s.weight, pdf=s.pdf)
"""


class ReferenceUnavailable(RuntimeError):
    """The plugin cannot be loaded again in the unpolarized variant (the row is skipped)."""


def restored(spec: dict) -> dict:
    """A report's spec (:func:`phonglab.settings.load_plugin` writes a nested value as its repr,
    e.g. ``--set reflectance=0.2,0.3,0.4``'s ``{'type': 'rgb', ...}``) with such values parsed
    back where they are Python literals; anything else is kept (and may not load)."""
    out = {}
    for k, v in spec.items():
        if isinstance(v, str) and v[:1] in "{[":
            try:
                v = ast.literal_eval(v)
            except (ValueError, SyntaxError):
                pass
        out[k] = v
    return out


def reference(spec, files, variant, arrays) -> dict:
    """Run the unpolarized ``variant`` in a subprocess on ``arrays``; its eval and samples."""
    with tempfile.TemporaryDirectory(prefix="phonglab-pol-") as tmp:
        a, inp, out = (Path(tmp) / n for n in ("args.json", "in.npz", "out.npz"))
        a.write_text(json.dumps({"variant": variant, "spec": spec, "plugins": files}))
        np.savez(inp, **arrays)
        env = dict(os.environ)
        src = str(Path(phonglab.__path__[0]).resolve().parent)   # where phonglab came from
        env["PYTHONPATH"] = src + os.pathsep + env.get("PYTHONPATH", "")
        proc = subprocess.run([sys.executable, "-c", _CHILD, str(a), str(inp), str(out)],
                              capture_output=True, text=True, env=env, timeout=600)
        if proc.returncode != 0:
            tail = (proc.stderr.strip().splitlines() or ["no output"])[-1]
            if proc.returncode == 3:
                raise ReferenceUnavailable(f"the spec does not load in {variant}: {tail[:300]}")
            raise RuntimeError(f"the {variant} reference failed: {tail[:300]}")
        with np.load(out) as d:
            return {k: d[k] for k in d.files}


def intensity(bsdf, opts) -> list[Row]:
    if not mi.is_polarized:
        return skipped("intensity")
    variant = unpolarized_variant(mi.variant())
    if variant not in mi.variants():
        return [Row("intensity", "M00 = the unpolarized variant's value", None, None, None,
                    None, "skipped", f"this Mitsuba build has no {variant} variant to compare "
                    f"with", {})]
    prov = provenance(bsdf, opts)
    if prov is None:
        return [Row("intensity", "M00 = the unpolarized variant's value", None, None, None,
                    None, "skipped", "the BSDF was given as a loaded object: there is no spec "
                    f"to load it again in {variant}", {})]
    spec, files = prov
    wi, wo, r = eval_lanes(opts, "intensity")
    _, n_s = sizes(opts)
    swi, _ = lanes.incident(opts.cells(), n_s)
    u1, u2 = lanes.sample_values(r, len(swi))
    try:
        ref = reference(restored(spec), files, variant,
                        {"wi": wi, "wo": wo, "swi": swi, "u1": u1, "u2": u2})
    except ReferenceUnavailable as exc:
        return [Row("intensity", "M00 = the unpolarized variant's value", None, None, None,
                    None, "skipped", str(exc), {"spec": spec, "plugins": files})]
    ev = mueller_eval(bsdf, wi, wo)[..., 0, 0]
    lam = wavelengths()

    def rel_of(a, b):
        d = np.abs(a - b) / np.maximum(np.maximum(np.abs(a), np.abs(b)), ABS_FLOOR)
        return np.where(np.isfinite(a) & np.isfinite(b), d, np.nan)

    rel = rel_of(ev, ref["eval"]).max(axis=1)
    details = {"reference_variant": variant, "plugins": files,
               **_worst_scalar(rel, wi, wo, ev, ref["eval"], lam)}
    rows = [bounded_row("intensity", f"eval M00 = eval in {variant}", max_finite(rel), REL_TOL,
                        f"max relative |M00 − unpolarized eval| per lane and wavelength over "
                        f"random, mirror, straight-through and normal wo; {ROUND_OFF}",
                        details, lanes=(rel, {"wi": wi, "wo": wo}))]
    swo, w, spdf, _ = mueller_sample(bsdf, swi, u1, u2)
    w00 = w[..., 0, 0]
    same_wo = np.all(np.abs(swo - ref["wo"]) <= 1e-5, axis=1) | (
        ~np.any(w00 != 0, axis=1) & ~np.any(ref["weight"] != 0, axis=1))
    relw = np.maximum(rel_of(w00, ref["weight"]).max(axis=1),
                      np.where(same_wo, rel_of(spdf, ref["pdf"]), 1.0))
    relw = np.where(same_wo, relw, np.maximum(relw, 1.0))
    details = {"reference_variant": variant, "different_wo": int((~same_wo).sum()),
               **_worst_scalar(relw, swi, swo, w00, ref["weight"], lam)}
    rows.append(bounded_row("intensity", f"sample: wo, pdf, weight M00 = {variant}'s",
                            max_finite(relw), REL_TOL,
                            f"per sample (identical sample values, edge values included): the "
                            f"same wo (|Δ| ≤ 1e-5; a different wo counts 1), max relative "
                            f"difference of pdf and weight M00; {ROUND_OFF}",
                            details, lanes=(relw, {"wi": swi, "wo": swo})))
    return rows


def _worst_scalar(rel, wi, wo, a, b, lam) -> dict:
    finite = np.isfinite(rel)
    d = {"lanes": int(rel.size), "nonfinite_dropped": int((~finite).sum())}
    if finite.any():
        k = int(np.nanargmax(np.where(finite, rel, -1.0)))
        d.update(worst_wi=wi[k].tolist(), worst_wo=wo[k].tolist(),
                 polarized_m00=np.asarray(a[k]).tolist(), unpolarized=np.asarray(b[k]).tolist(),
                 wavelengths=[float(x) for x in lam])
    return d
