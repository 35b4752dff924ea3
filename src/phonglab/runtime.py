"""The runtime: a libLLVM Dr.Jit 1.5 can use, the best JIT backend, the Mitsuba variant, and
the memory this process may still allocate (:func:`available_memory`, which bounds films,
check sizes and worker counts before they are allocated).

Dr.Jit's LLVM backend loads ``libLLVM`` lazily, the first time an ``llvm_*``
variant is used, from ``DRJIT_LIBLLVM_PATH`` or from the system's default
search.  Two facts decide what phonglab does here:

* Dr.Jit 1.5 aborts the whole process with libLLVM 15 and 16 (``LLVM ERROR:
  Cannot select: fmaximum/fminimum``); no Python exception can catch that.
  libLLVM 14 and older is refused by Dr.Jit itself ("could not be found").
  Debian's ``libllvm19`` works.
* Python BSDFs are traced once into the kernel in ``llvm_*`` variants and cost
  nothing extra there, but are ~150x slower in ``scalar_*`` variants.

So :func:`configure` pins ``DRJIT_LIBLLVM_PATH`` to the newest usable library
it finds (never 15 or 16) before Dr.Jit needs it, and :func:`default_variant`
falls back to ``scalar_rgb`` with a loud warning when none is usable.

The backend order is ``cuda`` (Dr.Jit finds a CUDA device) > ``llvm`` (a usable libLLVM) >
``scalar`` (:func:`available_backend`); :func:`variant_for` names the variant of a colour
model on a backend, stepping up (mono → rgb → spectral) where Mitsuba builds none.
Every "unknown variant" in phonglab is reported by :func:`check_variant`.

Mitsuba is imported lazily here: this module runs at ``import phonglab``, before Dr.Jit may
load libLLVM, so it must not import Mitsuba itself.
"""

from __future__ import annotations

import contextlib
import glob
import io
import os
import re
import resource
import signal
import sys
import threading
import warnings
from dataclasses import dataclass
from pathlib import Path

from .errors import PhonglabError

#: Major versions Dr.Jit 1.5 crashes with (process abort, not an exception).
BROKEN_MAJORS = frozenset({15, 16})
#: Dr.Jit 1.5 refuses anything older than this.
MIN_MAJOR = 17

ENV = "DRJIT_LIBLLVM_PATH"

_SEARCH_GLOBS = (
    "/usr/lib/x86_64-linux-gnu/libLLVM*.so*",
    "/usr/lib/aarch64-linux-gnu/libLLVM*.so*",
    "/usr/lib/llvm-*/lib/libLLVM*.so*",
    "/usr/lib64/libLLVM*.so*",
    "/usr/local/lib/libLLVM*.so*",
    "/opt/homebrew/opt/llvm/lib/libLLVM.dylib",
    "/usr/local/opt/llvm/lib/libLLVM.dylib",
)


class SlowFallbackWarning(UserWarning):
    """No usable libLLVM: phonglab runs in a ``scalar_*`` variant (~150x slower)."""


class BackendFallbackWarning(UserWarning):
    """The asked-for JIT backend cannot start (no CUDA device): a working one is used instead."""


@dataclass(frozen=True)
class LLVMChoice:
    """The outcome of :func:`configure`."""

    path: str | None      #: library pinned in DRJIT_LIBLLVM_PATH, or None
    major: int | None     #: its major version when it could be read
    source: str           #: "environment", "search" or "none"
    reason: str           #: one sentence for the user

    @property
    def usable(self) -> bool:
        return self.path is not None and (self.major is None or _major_ok(self.major))


def _major_ok(major: int) -> bool:
    return major >= MIN_MAJOR and major not in BROKEN_MAJORS


def library_major(path: str | os.PathLike) -> int | None:
    """Major version of a libLLVM file, read from its (resolved) file name.

    ``libLLVM-19.so``, ``libLLVM.so.19.1``, ``libLLVM-15.so.1`` and
    ``/usr/lib/llvm-18/lib/libLLVM.so`` all carry it.
    """
    names = [Path(path).name]
    try:
        names.append(Path(path).resolve().name)
    except OSError:
        pass
    names.append(str(path))
    for name in names:
        m = re.search(r"libLLVM[-.](?:so\.)?(\d+)", name) or re.search(r"llvm-(\d+)", name)
        if m:
            return int(m.group(1))
    return None


#: The first bytes of a shared library: ELF, and Mach-O (32/64-bit, either byte order, fat).
_LIBRARY_MAGIC = (b"\x7fELF", b"\xfe\xed\xfa\xce", b"\xfe\xed\xfa\xcf", b"\xce\xfa\xed\xfe",
                  b"\xcf\xfa\xed\xfe", b"\xca\xfe\xba\xbe")


def is_shared_library(path: str | os.PathLike) -> bool:
    """Whether ``path`` is a file that starts like a shared library (a folder, a text file or
    an unreadable file is not); whether it is libLLVM only loading it tells."""
    try:
        with open(path, "rb") as f:
            return f.read(4) in _LIBRARY_MAGIC
    except OSError:
        return False


def candidates() -> list[tuple[int, str]]:
    """Usable libLLVM files on this machine, newest first, as (major, path)."""
    found: dict[str, tuple[int, str]] = {}
    for pattern in _SEARCH_GLOBS:
        for p in glob.glob(pattern):
            major = library_major(p)
            if major is None or not _major_ok(major) or not os.path.isfile(p):
                continue
            real = os.path.realpath(p)
            # Prefer the shortest name of one real file (the .so link a user would type).
            if real not in found or len(p) < len(found[real][1]):
                found[real] = (major, p)
    return sorted(found.values(), key=lambda mp: (-mp[0], mp[1]))


_choice: LLVMChoice | None = None


def configure(force: bool = False) -> LLVMChoice:
    """Pin ``DRJIT_LIBLLVM_PATH`` to a usable libLLVM, once per process.

    A path the user set is respected (with a warning when its version is one
    Dr.Jit 1.5 crashes with); otherwise the newest usable library found is
    pinned, so that an older libLLVM on the machine is never picked.
    """
    global _choice
    if _choice is not None and not force:
        return _choice
    user = os.environ.get(ENV)
    if user:
        major = library_major(user)
        if not os.path.exists(user):
            _choice = LLVMChoice(None, major, "environment",
                                 f"{ENV}={user} does not exist; install Debian's libllvm19 "
                                 f"(apt-get install -y libllvm19) or unset {ENV}")
        elif os.path.isdir(user):
            _choice = LLVMChoice(None, major, "environment",
                                 f"{ENV}={user} is a folder; point {ENV} at the libLLVM file "
                                 f"itself (e.g. {user.rstrip('/')}/libLLVM-19.so), or unset it")
        elif major is not None and not _major_ok(major):
            _choice = LLVMChoice(None, major, "environment",
                                 f"{ENV}={user} is libLLVM {major}, which Dr.Jit 1.5 cannot use "
                                 f"(it aborts with 15 and 16, refuses < {MIN_MAJOR}); install "
                                 f"libllvm19 and point {ENV} at it")
        elif not is_shared_library(user):
            _choice = LLVMChoice(None, major, "environment",
                                 f"{ENV}={user} is not a shared library (no ELF or Mach-O "
                                 f"header), so Dr.Jit cannot load it; point {ENV} at a libLLVM "
                                 f"such as Debian's libLLVM-19.so, or unset it")
        else:
            _choice = LLVMChoice(user, major, "environment", f"using {user} from {ENV}")
        return _choice
    found = candidates()
    if found:
        major, path = found[0]
        os.environ[ENV] = path
        _choice = LLVMChoice(path, major, "search", f"pinned {ENV}={path} (libLLVM {major})")
    else:
        _choice = LLVMChoice(None, None, "none",
                             "no usable libLLVM (>= 17, not 15/16) found; install it with "
                             "`apt-get install -y libllvm19` (Debian/Ubuntu) or run `make setup`")
    return _choice


def default_variant(color: str = "rgb") -> str:
    """The variant phonglab uses when none is set: ``llvm_ad_<color>``.

    Falls back to ``scalar_<color>`` with a :class:`SlowFallbackWarning` when no
    usable libLLVM exists; never silently.
    """
    choice = configure()
    if choice.usable:
        return f"llvm_ad_{color}"
    warnings.warn(
        f"phonglab: the LLVM backend is unusable ({choice.reason}). Falling back to "
        f"scalar_{color}: Python plugins run about 150x slower there.",
        SlowFallbackWarning, stacklevel=2)
    return f"scalar_{color}"


@contextlib.contextmanager
def deferred_interrupt():
    """Hold Ctrl-C (SIGINT) until the block is done, then raise ``KeyboardInterrupt``.

    Setting a variant imports Mitsuba's C++ modules and runs the variant callbacks (which
    register phonglab's plugins); a ``KeyboardInterrupt`` raised inside that import surfaces
    as ``SystemError: <built-in function __import__> returned a result with an exception
    set`` and can leave the variant half set.  Only in the main thread, and only where
    Python's own handler is installed (a caller's handler is left alone).
    """
    if (threading.current_thread() is not threading.main_thread()
            or signal.getsignal(signal.SIGINT) is not signal.default_int_handler):
        yield
        return
    caught: list = []
    previous = signal.signal(signal.SIGINT, lambda *frame: caught.append(frame))
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)
    if caught:
        raise KeyboardInterrupt


@contextlib.contextmanager
def interrupts_routed():
    """Take Ctrl-C (SIGINT) on a thread of phonglab's own for the block: Mitsuba never sees it.

    Mitsuba 3.9.1's ``Integrator.render`` binding installs a C signal handler for the length
    of each render (``ScopedSignalHandler``: the handler is the lambda that
    src/render/python/integrator_v.cpp:37 passes to ``signal``) whose first statement calls
    ``Log`` (line 38) -- a mutex, string formatting, ``malloc`` -- from inside the handler,
    which POSIX does not allow (not async-signal-safe): a Ctrl-C that lands on a thread
    holding one of those locks can deadlock the process.  tests/repro/sigint_handler_logs.py
    shows the ``Log`` call running in the handler, not a hang.  The same line 37 stores
    ``signal``'s return value in ``sigint_handler_prev`` only after the handler is installed:
    a Ctrl-C in between re-installs the old value (line 42) and re-raises (line 43), and in a
    process's first render that value is still null (line 26: ``SIG_DFL``), which kills the
    process outright (exit -2, no message).  So for the block SIGINT
    is blocked in the main thread -- and so in every thread started inside it (Dr.Jit's and
    Mitsuba's workers, tqdm's, Dask's), which inherit the mask -- and a listener thread takes
    it with ``sigwait`` and hands it to the main thread as ``_thread.interrupt_main()``: no C
    handler runs at all, and Python raises ``KeyboardInterrupt`` at the main thread's next
    bytecode, or calls the Python handler then installed (:func:`deferred_interrupt`'s).

    Costs, stated: a render pass in a JIT variant is not interruptible from Python in any case
    (the kernel runs to its end); a ``scalar_*`` pass, which Mitsuba's handler would cancel
    midway, ends first.  A main thread blocked in a system call (``time.sleep``, waiting
    for a child) is not woken: the interrupt is raised when the call returns.  Children started
    inside the block inherit the blocked mask (phonglab's own commands route it again; embedded
    Dask workers ignore SIGINT anyway).  Only in the main thread, and only where Python's own
    handler is installed.
    """
    if (threading.current_thread() is not threading.main_thread()
            or signal.getsignal(signal.SIGINT) is not signal.default_int_handler):
        yield
        return
    import _thread

    sigint = {signal.SIGINT}
    old = signal.pthread_sigmask(signal.SIG_BLOCK, sigint)   # the listener inherits it
    done = threading.Event()

    def listen():
        while True:
            signal.sigwait(sigint)
            if done.is_set():
                return
            _thread.interrupt_main()

    listener = threading.Thread(target=listen, name="phonglab-interrupts", daemon=True)
    listener.start()
    try:
        yield
    finally:
        done.set()
        signal.pthread_kill(listener.ident, signal.SIGINT)      # wakes sigwait, not main
        listener.join()
        signal.pthread_sigmask(signal.SIG_SETMASK, old)


class PluginExited(BaseException):
    """``os._exit(status)`` called while :func:`exits_intercepted` held (by a plugin file,
    at import or in a method).  A BaseException, so a plugin's ``except Exception`` does not
    swallow it; ``status`` is what it asked for."""

    def __init__(self, status):
        super().__init__(status)
        self.status = status


@contextlib.contextmanager
def exits_intercepted():
    """For the block, ``os._exit`` in this process raises :class:`PluginExited` instead of
    ending it.

    Why: ``os._exit(0)`` ends the process at once, with status 0, no output and no cleanup:
    a plugin file that calls it at import (or in ``eval``) turned ``phonglab validate`` into
    a green CI step that judged nothing.  No handler can catch it, so for the block the
    function itself is replaced (monkeypatched in the ``os`` module, which a plugin's ``os``
    and ``from os import _exit`` both read); the command then reports the call as the
    plugin's, one sentence or one failing row, never exit 0.  A forked child (multiprocessing,
    ``--workers``) inherits the replacement, so it calls the real ``os._exit`` when it is not
    this process, which is how those children end.  A plugin that stored ``os._exit`` before
    the block, or ends the process another way (a signal, a C ``exit``), is not caught.
    """
    real, pid = os._exit, os.getpid()

    def intercepted(status, *args):
        if os.getpid() != pid:
            real(status, *args)
        raise PluginExited(status)

    os._exit = intercepted
    try:
        yield
    finally:
        os._exit = real


@contextlib.contextmanager
def closed_stdout_tolerated():
    """For the block, a reader that goes away (``phonglab validate ... | head -3``) ends the
    output quietly: the first write that meets the closed pipe points standard output at
    ``os.devnull`` and the command goes on, so its files are still written and it exits with
    its verdict's own status -- not 1 with a ``BrokenPipeError`` traceback (Python ignores
    SIGPIPE, so the write fails with EPIPE instead of ending the process)."""
    stream = sys.stdout
    if stream is None or not hasattr(stream, "fileno"):
        yield
        return
    try:
        fd = stream.fileno()
    except (OSError, ValueError, io.UnsupportedOperation):      # captured (pytest, StringIO)
        yield
        return
    sys.stdout = tolerant = _PipeTolerant(stream, fd)
    try:
        yield
    finally:
        sys.stdout = stream
        with contextlib.suppress(OSError, ValueError):
            tolerant.flush()     # what is still buffered, else Python's exit meets the pipe


class _PipeTolerant:
    """Standard output whose writes and flushes, once its pipe is closed, go to os.devnull."""

    def __init__(self, stream, fd: int):
        self._stream, self._fd = stream, fd

    def _closed(self) -> None:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, self._fd)              # the buffered rest now goes nowhere
        os.close(devnull)

    def write(self, text):
        try:
            return self._stream.write(text)
        except BrokenPipeError:
            self._closed()
            return len(text)

    def flush(self):
        try:
            self._stream.flush()
        except BrokenPipeError:
            self._closed()
            with contextlib.suppress(BrokenPipeError, OSError):
                self._stream.flush()

    def __getattr__(self, name):
        return getattr(self._stream, name)


def set_variant(variant: str | None = None) -> str:
    """Set a Mitsuba variant, the default one when ``variant`` is None.

    A JIT variant that fails to start falls back to the best backend that works, with a
    warning naming both: ``cuda_*`` without a CUDA device becomes ``llvm_ad_*`` (same images up
    to float rounding, on the CPU) when libLLVM is usable, and ``llvm_*`` without a usable
    libLLVM becomes ``scalar_*`` (:class:`SlowFallbackWarning`: ~150x slower).  A Ctrl-C on
    the way is raised once the variant is set (:func:`deferred_interrupt`).
    """
    with deferred_interrupt():
        return _set_variant(variant)


def _set_variant(variant: str | None) -> str:
    import mitsuba as mi

    configure()
    variant = check_variant(variant or default_variant())
    try:
        mi.set_variant(variant)
        return variant
    except ImportError as exc:
        if not variant.startswith(("llvm_", "cuda_")):
            raise
        why = exc
    rest = variant.split("_", 1)[1]                       # "ad_rgb", "ad_spectral_polarized"
    if variant.startswith("cuda_") and configure().usable and f"llvm_{rest}" in mi.variants():
        fallback = f"llvm_{rest}"
        try:
            mi.set_variant(fallback)
            warnings.warn(f"phonglab: {variant} is unusable ({why}). Using {fallback} instead: "
                          f"the same computation on the CPU's LLVM backend.",
                          BackendFallbackWarning, stacklevel=2)
            return fallback
        except ImportError as exc:
            why = exc
    fallback = "scalar_" + rest.removeprefix("ad_")
    warnings.warn(f"phonglab: {variant} is unusable ({why}). Falling back to {fallback}: "
                  f"Python plugins run about 150x slower there.",
                  SlowFallbackWarning, stacklevel=2)
    mi.set_variant(check_variant(fallback))
    return fallback


def check_variant(variant: str) -> str:
    """``variant`` when this Mitsuba build has it, else :class:`ValueError` naming the choices."""
    import mitsuba as mi

    if variant not in mi.variants():
        raise ValueError(
            f"unknown Mitsuba variant {variant!r}; choose one of {', '.join(mi.variants())}")
    return variant


def available_backend() -> tuple[str, str]:
    """The best JIT backend that works on this machine, and why: cuda > llvm > scalar.

    ``cuda`` needs Mitsuba's ``cuda_*`` variants and a CUDA device Dr.Jit can initialise
    (``drjit.has_backend``); ``llvm`` needs a libLLVM Dr.Jit 1.5 can use (:func:`configure`).
    """
    import drjit as dr
    import mitsuba as mi

    variants = set(mi.variants())
    cuda_why = "Mitsuba has no cuda_* variants"
    if any(v.startswith("cuda_") for v in variants):
        try:
            if dr.has_backend(dr.JitBackend.CUDA):
                return "cuda", "Dr.Jit found a CUDA device (cuda > llvm > scalar)"
            cuda_why = "no CUDA device or driver (drjit.has_backend(CUDA) is False)"
        except Exception as exc:  # pragma: no cover - depends on the driver
            cuda_why = f"CUDA failed to initialise ({exc})"
    choice = configure()
    if choice.usable and any(v.startswith("llvm_") for v in variants):
        try:
            if dr.has_backend(dr.JitBackend.LLVM):
                return "llvm", f"LLVM JIT usable; {cuda_why}"
        except Exception:  # pragma: no cover
            pass
    return "scalar", (f"no JIT backend: {cuda_why}; LLVM: {choice.reason} (scalar runs Python "
                      f"BSDFs about 150x slower)")


def variant_for(color: str, backend: str, polarized: bool = False) -> tuple[str, list[str]]:
    """The Mitsuba variant for a colour model and backend, stepping up when one is not built.

    Mitsuba builds no ``*_rgb_polarized`` and (here) no ``scalar_mono``: the next richer colour
    model is used then (mono -> rgb -> spectral), with a note.

    Returns:
        (variant, notes); raises :class:`phonglab.errors.PlanError` when none exists.
    """
    import mitsuba as mi

    from .errors import PlanError

    available = set(mi.variants())
    notes: list[str] = []
    order = ["mono", "rgb", "spectral"]
    for c in order[order.index(color):]:
        name = f"{backend}_ad_{c}" if backend != "scalar" else f"scalar_{c}"
        if polarized:
            name += "_polarized"
        if name in available:
            if c != color:
                notes.append(f"{color} needs {backend}_{color}{'_polarized' if polarized else ''}, "
                             f"which this Mitsuba lacks: using {name}")
            return name, notes
    raise PlanError(f"no Mitsuba variant for {color} on the {backend} backend"
                    f"{' with polarization' if polarized else ''} (have: "
                    f"{', '.join(sorted(available))}); install a Mitsuba build with one.")


@contextlib.contextmanager
def quiet_mitsuba():
    """Silence Mitsuba's warnings (mono's "film set to luminance") inside the block."""
    import mitsuba as mi

    logger = mi.logger()
    old = logger.log_level()
    logger.set_log_level(mi.LogLevel.Error)
    try:
        yield
    finally:
        logger.set_log_level(old)


def available_memory() -> int | None:
    """Bytes this process may still allocate: MemAvailable, capped by RLIMIT_AS (None if unknown)."""
    limits = []
    try:
        with open("/proc/meminfo") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    limits.append(int(line.split()[1]) * 1024)
    except OSError:
        pass
    soft, _ = resource.getrlimit(resource.RLIMIT_AS)
    if soft != resource.RLIM_INFINITY:
        limits.append(soft)
    return min(limits) if limits else None


def require_memory(need: int, what: str, fix, *, why: str = "", error=None,
                   have: int | None = None) -> None:
    """The one memory guard, before anything is allocated: one sentence ("``what`` would need
    about N GiB of memory``why`` but M GiB is available; ``fix``") raised as ``error`` (default
    :class:`~phonglab.errors.PhonglabError`) when ``need`` bytes exceed ``have`` (default
    :func:`available_memory`; nothing when it is unknown).  ``fix`` may be a function of the
    bytes available."""
    have = available_memory() if have is None else have
    if have is None or need <= have:
        return
    fix = fix(have) if callable(fix) else fix
    raise (error or PhonglabError)(f"{what} would need about {need / 2**30:.1f} GiB of memory"
                                   f"{why} but {have / 2**30:.1f} GiB is available; {fix}")


#: The fewest Dr.Jit kernel threads phonglab runs with.  At one thread Dr.Jit starts no worker
#: thread (drjit-core's ``jit_llvm_set_thread_count`` counts the caller as one), and Mitsuba
#: 3.9.1's OpenEXR reads and writes then wait forever: bitmap.cpp:972 runs an OpenEXR task in
#: the caller only when ``pool_size() == 0``, and nanothread's ``pool_size()`` counts the
#: caller, so the task is queued for a worker that does not exist
#: (``tests/repro/exr_one_thread_hang.py``).  Dr.Jit's default is the cores the process may
#: run on (nanothread's ``core_count``: the affinity mask), one in a one-CPU container.
MIN_KERNEL_THREADS = 2


def kernel_threads_floor() -> int:
    """Give Dr.Jit at least :data:`MIN_KERNEL_THREADS` threads; return the count.

    The threads this adds are born in the background (``SCHED_IDLE``, inherited from the
    short-lived thread that asks for them: nanothread starts its workers with the default
    ``PTHREAD_INHERIT_SCHED``), because they exist for OpenEXR's tasks only: on one core a
    normal worker would take half of it from the caller for its spin after each kernel
    (:func:`background_kernel_threads`).  Where the platform has no such class they are
    normal threads.
    """
    import drjit as dr

    count = dr.thread_count()
    if count >= MIN_KERNEL_THREADS:
        return count

    def add():
        idle = getattr(os, "SCHED_IDLE", None)
        if idle is not None:
            with contextlib.suppress(OSError):
                os.sched_setscheduler(0, idle, os.sched_param(0))    # this thread only
        dr.set_thread_count(MIN_KERNEL_THREADS)

    helper = threading.Thread(target=add, name="phonglab-kernel-threads")
    helper.start()
    helper.join()
    return dr.thread_count()


#: How nanothread names Dr.Jit's kernel worker threads: ``"nt [%u]"`` (nanothread.cpp,
#: ``pthread_setname_np``), read back from ``/proc/self/task/*/comm``.  A worker takes the name
#: when it first runs (measured: one that has not yet run a kernel's block reads "python"); a
#: worker that never ran is parked, and parked threads do not spin.
KERNEL_THREAD_PREFIX = "nt ["


def background_kernel_threads() -> int:
    """Put Dr.Jit's kernel worker threads of this process in Linux's ``SCHED_IDLE`` class;
    return how many there are (0 where the platform has no such class).

    Why: a Dr.Jit worker thread spins for up to 20 ms looking for work after each kernel
    (nanothread's queue.cpp: ``NANOTHREAD_MAX_IDLE_MS 20.0``, then it parks).  A process alone
    on the machine loses nothing to that -- the spin takes a core nobody else wants -- but
    where several phonglab processes share the cores (a LocalCluster's workers, pytest-xdist's
    workers) each one's spin takes a core from another's Python thread.  In ``SCHED_IDLE``
    (sched(7)) a thread runs only on a core no normal thread wants: the kernels still use
    every idle core (the calling thread runs its share of each kernel's blocks in any case,
    nanothread's ``task_wait``), and the spin no longer competes.  Measured on 2 cores: two
    processes each validating ``roughconductor`` three times at default sizes took 15.0 and
    14.4 s side by side, 11.9 and 11.4 s with their workers in the class; one process alone
    9.9 s either way (10.0, 10.7: noise).  Setting Dr.Jit's thread count to 1 would remove
    the spin too, but makes Mitsuba 3.9.1 wait forever on OpenEXR files
    (``tests/repro/exr_one_thread_hang.py``); here the worker still exists and runs OpenEXR's
    tasks whenever a core is free (the caller sleeps on them).  Cost: where normal threads
    of other processes fill every core, a kernel runs on the calling thread alone, and an
    OpenEXR task waits for the class's small share (weight 3 against 1024, sched(7)) -- slow,
    never stopped.

    The threads start with Dr.Jit's first kernel or :func:`drjit.set_thread_count`; a thread
    started later needs another call (idempotent, ~0.1 ms).
    """
    idle = getattr(os, "SCHED_IDLE", None)
    if idle is None:
        return 0
    count = 0
    for tid in kernel_thread_ids():
        try:
            if os.sched_getscheduler(tid) != idle:
                os.sched_setscheduler(tid, idle, os.sched_param(0))
            count += 1
        except OSError:                      # a thread that ended meanwhile
            continue
    return count


def kernel_thread_ids() -> list[int]:
    """The thread ids of this process's Dr.Jit kernel threads (named :data:`KERNEL_THREAD_PREFIX`
    in ``/proc/self/task``; none where there is no such folder)."""
    tasks = Path("/proc/self/task")
    if not tasks.is_dir():
        return []
    out = []
    for task in tasks.iterdir():
        try:
            if (task / "comm").read_text().startswith(KERNEL_THREAD_PREFIX):
                out.append(int(task.name))
        except (OSError, ValueError):        # a thread that ended meanwhile
            continue
    return out
