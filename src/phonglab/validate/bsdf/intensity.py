r"""The ``intensity`` topic: M00 in a polarized variant against what the same plugin returns in
the matching unpolarized variant, direction by direction (the derivation and tolerances are in
:mod:`.polarization`'s docstring).  The unpolarized reference runs in a child process
(:class:`ReferenceServer`): it sets that variant, registers phonglab's plugins and runs the
``--plugin`` files once, then loads each spec it is sent again and answers with its eval and
samples (:func:`reference`).  One such process serves a whole validate run -- every point of
its sweep (:func:`session`): starting an interpreter and Mitsuba's variant is most of the cost
of a request.
"""

from __future__ import annotations

import ast
import contextlib
import json
import os
import select
import subprocess
import sys
import tempfile
from pathlib import Path

import mitsuba as mi
import numpy as np

import phonglab
from ... import probe
from . import lanes
from ..roundoff import ABS_FLOOR, REL_TOL
from .polarization import eval_lanes, sizes, skipped, wavelengths
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
    the caller's own code through ``loading.load_plugins`` outside a run has no record of its file:
    its class's functions name the file it came from.
    """
    source = getattr(opts, "source", None)
    if source is None or source.plugin is not bsdf or source.spec is None:
        return None
    files = list(source.files)
    cls = type(bsdf)
    if not files and cls.__module__ == "__phonglab_plugin__":   # run by loading.load_plugins
        for v in vars(cls).values():
            code = getattr(v, "__code__", None)
            if code is not None and Path(code.co_filename).is_file():
                files.append(str(Path(code.co_filename).resolve()))
                break
    return source.spec, files


_SERVER = r"""
import json, os, runpy, signal, sys, traceback
signal.signal(signal.SIGINT, signal.SIG_IGN)    # the validating process owns its lifetime
reply = os.fdopen(os.dup(1), "w", buffering=1)  # the protocol's channel: the original stdout
os.dup2(2, 1)                                   # what Mitsuba or a plugin prints: stderr
sys.stdout = sys.stderr
import numpy as np
variant, plugins = json.loads(sys.argv[1])
import phonglab
phonglab.register(variant)
import mitsuba as mi
from phonglab import probe
for f in plugins:
    runpy.run_path(f, run_name="__phonglab_plugin__")
for line in sys.stdin:
    req = json.loads(line)
    spec = req["spec"]
    try:
        if set(spec) == {"file"}:
            bsdf = mi.load_string(open(spec["file"]).read())
        else:
            bsdf = mi.load_dict(spec)
    except Exception as exc:
        text = str(exc).strip()
        reply.write(json.dumps({"unavailable": text.splitlines()[-1] if text else repr(exc)})
                    + "\n")
        continue
    try:
        d = np.load(req["in"])
        ev = probe.eval(bsdf, d["wi"], d["wo"])
        s = probe.sample(bsdf, d["swi"], d["u1"], d["u2"])
        np.savez(req["out"], eval=ev, wo=s.wo, weight=s.weight, pdf=s.pdf)
    except Exception as exc:
        traceback.print_exc()
        reply.write(json.dumps({"error": traceback.format_exception_only(exc)[-1].strip()})
                    + "\n")
        continue
    reply.write(json.dumps({"done": req["out"]}) + "\n")
"""

#: How long one request may take before the reference process is given up (seconds).
REQUEST_TIMEOUT = 600.0


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


class ReferenceServer:
    """One child interpreter in an unpolarized ``variant`` with the ``plugins`` files run,
    answering requests (a spec and arrays) for as long as it is open.

    The protocol is JSON lines: a request ``{"spec", "in", "out"}`` on the child's stdin (the
    arrays in the ``.npz`` file ``in``, the answers written to ``out``: binary, so the numbers
    are exact), one reply line on its stdout -- ``{"done"}``, ``{"unavailable": why}`` (the
    spec does not load there) or ``{"error": why}``.  The child writes everything else (Mitsuba's
    log, a plugin's prints) to a log file, whose last line a failure reports.  It ignores
    SIGINT: Ctrl-C reaches the validating process (routed there by
    :func:`phonglab.runtime.interrupts_routed`), which closes it (:meth:`close`); it also ends
    on its own when its stdin closes, so a validating process that dies takes it along."""

    def __init__(self, variant: str, plugins):
        self.variant = variant
        self.tmp = tempfile.TemporaryDirectory(prefix="phonglab-pol-")
        # appending: the child writes at the end whatever this handle has read
        self.log = open(Path(self.tmp.name) / "child.log", "a+")
        self.requests = 0
        env = dict(os.environ)
        src = str(Path(phonglab.__path__[0]).resolve().parent)   # where phonglab came from
        env["PYTHONPATH"] = src + os.pathsep + env.get("PYTHONPATH", "")
        self.proc = subprocess.Popen(
            [sys.executable, "-c", _SERVER, json.dumps([variant, list(plugins)])],
            stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=self.log, text=True, env=env)

    def _tail(self) -> str:
        self.log.flush()
        self.log.seek(0)
        lines = self.log.read().strip().splitlines()
        return (lines or ["no output"])[-1][:300]

    def _reply(self) -> dict:
        ready, _, _ = select.select([self.proc.stdout], [], [], REQUEST_TIMEOUT)
        line = self.proc.stdout.readline() if ready else ""
        if not line:
            if ready:
                self.proc.wait()
                raise RuntimeError(f"the {self.variant} reference failed: {self._tail()}")
            raise RuntimeError(f"the {self.variant} reference did not answer within "
                               f"{REQUEST_TIMEOUT:g} s")
        return json.loads(line)

    def request(self, spec, arrays) -> dict:
        """The unpolarized eval and samples of ``spec`` on ``arrays``."""
        self.requests += 1
        inp, out = (Path(self.tmp.name) / f"{n}{self.requests}.npz" for n in ("in", "out"))
        np.savez(inp, **arrays)
        self.proc.stdin.write(json.dumps({"spec": spec, "in": str(inp), "out": str(out)})
                              + "\n")
        self.proc.stdin.flush()
        answer = self._reply()
        inp.unlink()
        if "unavailable" in answer:
            raise ReferenceUnavailable(f"the spec does not load in {self.variant}: "
                                       f"{answer['unavailable'][:300]}")
        if "error" in answer:
            raise RuntimeError(f"the {self.variant} reference failed: {answer['error'][:300]}")
        with np.load(out) as d:
            result = {k: d[k] for k in d.files}
        out.unlink()
        return result

    @property
    def alive(self) -> bool:
        return self.proc.poll() is None

    def close(self) -> None:
        """End the child: its stdin closed (it leaves its loop), killed if it has not ended
        within 10 s; the folder removed."""
        try:
            if self.proc.stdin and not self.proc.stdin.closed:
                try:
                    self.proc.stdin.close()
                except OSError:              # it died first: the pipe is broken
                    pass
            try:
                self.proc.wait(timeout=10)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
        finally:
            if self.proc.stdout:
                self.proc.stdout.close()
            self.log.close()
            self.tmp.cleanup()


#: The open servers, by (variant, plugin files), while a :func:`session` is open.
_servers: dict[tuple, ReferenceServer] = {}
#: How many :func:`session` blocks are open (nested ones share the outermost's servers).
_depth = 0


@contextlib.contextmanager
def session():
    """For the block, one reference process per (variant, plugin files), started at the first
    request and reused by every later one -- every parameter point of a sweep -- and closed
    when the outermost block ends, however it ends (an exception, Ctrl-C).  The BSDF kind's
    part ``session`` (:mod:`phonglab.validate.kind`): :func:`phonglab.validate.core.run` opens
    one per point, :func:`phonglab.validate.sweep.run` one around all its points."""
    global _depth
    _depth += 1
    try:
        yield
    finally:
        _depth -= 1
        if _depth == 0:
            while _servers:
                _servers.popitem()[1].close()


def reference(spec, files, variant, arrays) -> dict:
    """The unpolarized ``variant``'s eval and samples of ``spec`` on ``arrays``, from the
    session's reference process (:func:`session`; outside one, a process for this request)."""
    key = (variant, tuple(files))
    server = _servers.get(key)
    if server is None or not server.alive:
        if server is not None:
            server.close()
        server = _servers[key] = ReferenceServer(variant, files)
    try:
        return server.request(spec, arrays)
    except ReferenceUnavailable:
        raise
    except BaseException:
        # a reply may still be pending (a timeout, Ctrl-C): this process cannot be reused
        _servers.pop(key, None)
        server.proc.kill()
        server.close()
        raise
    finally:
        if _depth == 0 and key in _servers:
            _servers.pop(key).close()


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
    ev = probe.mueller_eval(bsdf, wi, wo)[..., 0, 0]
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
    swo, w, spdf, _ = probe.mueller_sample(bsdf, swi, u1, u2)
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
