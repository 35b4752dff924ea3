r"""Where a validate run spends its time: per topic and per sweep point, the wall time split
into Dr.Jit kernel compilation, kernel execution and the rest (Python, tracing, numpy).

Dr.Jit records every kernel it launches while ``JitFlag.KernelHistory`` is set
(``dr.kernel_history()`` returns the records and clears them): its ``codegen_time`` and
``backend_time`` (ms: the IR generated and hashed at every launch, and the LLVM or CUDA
compile of a kernel that was neither in memory nor in the on-disk cache, ``cache_hit`` /
``cache_disk``) and its ``execution_time`` (ms).  Only JIT kernels count; host functions (the
copies to numpy) are part of "other".  :class:`Topic`
turns the flag on around one topic, drains the history before and after, and sums:

* ``compile_s``: codegen + backend time of the JIT kernels;
* ``execute_s``: the kernels' execution time;
* ``other_s``: wall − compile − execute: the plugin's Python code, Dr.Jit's tracing, numpy and
  phonglab's own bookkeeping;
* ``kernels``, ``compiled``: JIT kernels launched, and how many of them were compiled (found
  neither in memory nor in the disk cache).

Every report carries it (``meta["profile"]``: topic -> record; a sweep sums the points'
records per topic and keeps each point's total in ``meta["sweep"]["runs"]``);
``phonglab validate --profile`` prints it as a table.  In variants without a JIT (scalar) only
the wall time is measured.

The ``cost`` topic of every kind times the plugin against a baseline with
:func:`interleaved_medians`: each run once first (its kernels compiled), then the two timed
alternately so that both see the same machine load, the median of each kept.
"""

from __future__ import annotations

import statistics
import time

import drjit as dr
import mitsuba as mi

__all__ = ["Topic", "add", "interleaved_medians", "table", "total"]

FIELDS = ("seconds", "compile_s", "execute_s", "other_s", "kernels", "compiled")


class Topic:
    """``with Topic() as p: ...``: ``p.record`` holds the block's split (module docstring)."""

    def __init__(self):
        self.record: dict = {}

    def __enter__(self):
        self.jit = dr.is_jit_v(mi.Float)
        if self.jit:
            self.was = dr.flag(dr.JitFlag.KernelHistory)
            dr.kernel_history()                     # drop what came before
            dr.set_flag(dr.JitFlag.KernelHistory, True)
        self.t0 = time.perf_counter()
        return self

    def __exit__(self, *exc):
        wall = time.perf_counter() - self.t0
        compile_s = execute_s = 0.0
        kernels = compiled = 0
        if self.jit:
            for k in dr.kernel_history():
                if k.get("type") != dr.KernelType.JIT:   # host copies, reductions: transfers
                    continue
                kernels += 1
                execute_s += k.get("execution_time", 0.0) / 1e3
                # codegen (the IR and its hash) every launch; the backend only when compiled
                compile_s += (k.get("codegen_time", 0.0) + k.get("backend_time", 0.0)) / 1e3
                if not (k.get("cache_hit") or k.get("cache_disk")):
                    compiled += 1
            dr.set_flag(dr.JitFlag.KernelHistory, self.was)
        self.record = {"seconds": round(wall, 4), "compile_s": round(compile_s, 4),
                       "execute_s": round(execute_s, 4),
                       "other_s": round(max(0.0, wall - compile_s - execute_s), 4),
                       "kernels": kernels, "compiled": compiled}
        return False


def add(a: dict | None, b: dict | None) -> dict:
    """Two records summed field by field (a missing one counts 0)."""
    a, b = a or {}, b or {}
    return {f: round(a.get(f, 0) + b.get(f, 0), 4) for f in FIELDS}


def total(profile: dict) -> dict:
    """The records of every topic summed."""
    out: dict = {}
    for record in profile.values():
        out = add(out, record)
    return out


def table(profile: dict, runs=()) -> str:
    """The profile as text: one line per topic, then the total; each sweep point's total."""
    head = f"{'topic':<26}{'wall s':>9}{'compile s':>11}{'execute s':>11}{'other s':>9}" \
           f"{'kernels':>9}{'compiled':>10}"
    lines = ["where the time went (Dr.Jit kernel history; other = Python, tracing, numpy):", head]

    def line(name, r):
        return (f"{name:<26}{r['seconds']:>9.3f}{r['compile_s']:>11.3f}{r['execute_s']:>11.3f}"
                f"{r['other_s']:>9.3f}{r['kernels']:>9d}{r['compiled']:>10d}")

    for topic, r in profile.items():
        lines.append(line(topic, r))
    lines.append(line("total", total(profile)))
    timed = [r for r in runs if r.get("profile")]
    if len(timed) > 1:
        lines += ["", "per sweep point:", head]
        from ..verdict import point_label
        for r in timed:
            lines.append(line(point_label(r["point"])[:25], r["profile"]))
    return "\n".join(lines)


def interleaved_medians(fa, fb, repeats: int) -> tuple[float, float]:
    """Median seconds of ``fa(k)`` and ``fb(k)`` over k = 0 .. repeats − 1, timed alternately
    after one untimed run of each with k = −1 (compiling their kernels)."""
    fa(-1), fb(-1)
    ta, tb = [], []
    for k in range(repeats):
        for f, out in ((fa, ta), (fb, tb)):
            t0 = time.perf_counter()
            f(k)
            out.append(time.perf_counter() - t0)
    return statistics.median(ta), statistics.median(tb)
