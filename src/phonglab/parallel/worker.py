r"""Preparing a Dask worker process for phonglab's jobs: kernel cache, variant, plugins.

:class:`PhonglabWorker` is the ``distributed.WorkerPlugin`` every :class:`~phonglab.parallel.Runner`
registers; its ``setup`` runs :func:`prepare_process` once in each worker process (and in
every worker that joins later, or that a nanny restarts after a crash).

**Kernel cache.**  Dr.Jit 1.5 keeps compiled kernels in ``$HOME/.drjit``: ``jitc_init``
(drjit-core ``src/init.cpp``), which runs when ``drjit`` is imported, reads
``getenv("HOME")`` once; there is neither an environment variable nor an API to move the
folder later.  So :func:`prepare_process` gives each worker process its own folder before it
imports Dr.Jit: it claims the first free slot ``<root>/worker-<k>`` (an exclusive ``flock``
on ``<slot>/.lock``, held for the life of the process: two live processes never share a slot,
and a restarted worker reuses a warm one), removes the slot's stale ``*.tmp`` files, points
``HOME`` there, imports Dr.Jit and Mitsuba, sets the variant, and puts ``HOME`` back.
``<root>`` is ``$PHONGLAB_WORKER_CACHE`` or ``~/.cache/phonglab/drjit-workers``.

Why a slot of its own, when Dr.Jit's writes are careful (``jitc_kernel_write``, drjit-core
``src/io.cpp``: the kernel goes to ``<hash>.tmp`` opened with ``O_CREAT | O_EXCL``, is
``link``-ed to its final name and the ``.tmp`` unlinked, so a reader never sees half a file
and two writers of one kernel cost one a warning): a process killed between creating the
``.tmp`` and unlinking it (a lost worker, which the cluster is built to survive) leaves a
``.tmp`` that makes every later write of that kernel fail, in every process sharing the
folder, forever.  Only the owner of a folder can safely delete it, and with a slot each
process owns one.  When Dr.Jit was imported before the plugin ran (a LocalCluster started
from a script that imports ``drjit`` or ``mitsuba`` at module level: the ``spawn`` start
method re-imports the main module in every worker) the folder is the shared ``~/.drjit``,
safe by the protocol above but without the clean-up; the report's ``kernel_cache`` is then
None.  ``phonglab``'s commands and ``dask worker`` never import Dr.Jit first.

**Threads.**  A LocalCluster of N workers on C cores sets Dr.Jit's thread pool to C // N
threads per process, but never fewer than :data:`phonglab.runtime.MIN_KERNEL_THREADS`, so N
processes do not start N·C kernel threads; on a hand-started cluster Dr.Jit keeps its default (all cores of the
machine) unless ``threads`` is given.  At one thread Mitsuba 3.9.1's OpenEXR reads and
writes wait forever (:data:`phonglab.runtime.MIN_KERNEL_THREADS` says why): a 2-worker cluster
on 2 cores hung on the first bitmap texture it loaded.
Results do not depend on the thread count (measured: the stability cells are bit-identical
with 1 and 2 Dr.Jit threads; the tests compare serial and distributed runs bit for bit).
After each job the worker puts Dr.Jit's kernel threads in Linux's ``SCHED_IDLE`` class
(:func:`phonglab.runtime.background_kernel_threads`): they run kernels on cores no other
process wants, and their spin between kernels (up to 20 ms after each) no longer takes a core
from another worker's Python thread.

**Ctrl-C.**  The workers of an embedded LocalCluster ignore SIGINT (``ignore_sigint``): a
terminal sends it to the whole process group, where each worker would print its own
KeyboardInterrupt traceback while the parent shuts the cluster down.  A hand-started
``dask worker`` keeps its own Ctrl-C.
"""

from __future__ import annotations

import fcntl
import os
import signal
import sys
import threading
from pathlib import Path
from typing import Any

from distributed import WorkerPlugin

from ..runtime import background_kernel_threads

#: Root of the per-process kernel-cache slots (``$PHONGLAB_WORKER_CACHE`` overrides it).
CACHE_ROOT_ENV = "PHONGLAB_WORKER_CACHE"
_held_lock: int | None = None          # the slot lock this process holds (kept open)
_report: dict[str, Any] | None = None  # what prepare_process did, once per process


def cache_root() -> Path:
    """Where the slots live: ``$PHONGLAB_WORKER_CACHE`` or ``~/.cache/phonglab/drjit-workers``."""
    env = os.environ.get(CACHE_ROOT_ENV)
    return Path(env) if env else Path.home() / ".cache" / "phonglab" / "drjit-workers"


def claim_slot(root: Path) -> Path:
    """The first folder ``root/worker-<k>`` no other live process holds (locked for life)."""
    global _held_lock
    k = 0
    while True:
        slot = root / f"worker-{k}"
        slot.mkdir(parents=True, exist_ok=True)
        fd = os.open(slot / ".lock", os.O_CREAT | os.O_RDWR, 0o600)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            os.close(fd)
            k += 1
            continue
        _held_lock = fd
        for stale in (slot / ".drjit").glob("*.tmp"):       # left by a killed owner
            stale.unlink(missing_ok=True)
        return slot


def prepare_process(variant: str, threads: int | None = None,
                    root: str | Path | None = None) -> dict[str, Any]:
    """Give this process its own Dr.Jit kernel cache, set ``variant``, register the plugins.

    Idempotent (the first call's report is returned again).  Returns what was done:
    ``kernel_cache`` (the folder Dr.Jit uses, or None when it had started before), ``variant``,
    ``threads``, ``pid``.
    """
    global _report
    if _report is not None:
        return _report
    started = "drjit" in sys.modules
    cache = None
    home = os.environ.get("HOME")
    if not started:
        slot = claim_slot(Path(root) if root else cache_root())
        os.environ["HOME"] = str(slot)
        cache = slot / ".drjit"
    try:
        import drjit as dr
        import mitsuba as mi

        from ..registration import register

        register(variant)
        if threads is not None:
            dr.set_thread_count(int(threads))
    finally:
        if home is None:
            os.environ.pop("HOME", None)
        else:
            os.environ["HOME"] = home
    _report = {"kernel_cache": str(cache) if cache else None, "variant": mi.variant(),
               "threads": dr.thread_count(), "pid": os.getpid()}
    return _report


class PhonglabWorker(WorkerPlugin):
    """Runs :func:`prepare_process` in every worker process of the cluster."""

    name = "phonglab"

    def __init__(self, variant: str, threads: int | None = None, root: str | None = None,
                 ignore_sigint: bool = False):
        self.variant, self.threads, self.root = variant, threads, root
        self.ignore_sigint = ignore_sigint

    def setup(self, worker) -> None:
        if self.ignore_sigint and threading.current_thread() is threading.main_thread():
            # An embedded worker: Ctrl-C is its parent's to handle (phonglab.parallel._connect).
            signal.signal(signal.SIGINT, signal.SIG_IGN)
        prepare_process(self.variant, self.threads, self.root)

    def transition(self, key, start, finish, *args, **kwargs) -> None:
        if finish == "memory":
            # after each job: the kernel threads its kernels started run in the background
            background_kernel_threads()


def worker_report() -> dict[str, Any] | None:
    """What :func:`prepare_process` did in this process (None: not prepared)."""
    return _report
