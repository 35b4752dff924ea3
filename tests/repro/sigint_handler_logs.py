"""Mitsuba 3.9.1: the SIGINT handler of a render calls Log, which a signal handler must not.

src/render/python/integrator_v.cpp (commit 478e193a): each ``Integrator.render`` call from
Python installs ``ScopedSignalHandler`` (lines 30-49), whose handler is the lambda passed to
``signal`` on line 37.  Its first statement, line 38, is
``Log(Warn, "Received interrupt signal, winding down..")`` -- a mutex, string formatting and
``malloc`` -- then ``integrator->cancel()``, ``signal(SIGINT, sigint_handler_prev)`` and
``raise(SIGINT)`` (lines 39-43).  None of these but ``signal``/``raise`` is async-signal-safe
(POSIX signal-safety(7)): a Ctrl-C landing on a thread that holds the logger's mutex or an
allocator lock can deadlock the process.  ``sigint_handler_prev`` is also assigned only after
``signal()`` returns (line 37): a Ctrl-C in between re-installs its old value, null (SIG_DFL,
line 26) in a process's first render, and the re-raise kills the process with no Python
cleanup.  What it costs a render: nothing while no Ctrl-C comes; a possible deadlock or a
killed process when one does.  phonglab routes SIGINT itself (runtime.interrupts_routed).

This script shows that the handler runs ``Log`` from signal context (its message is printed
during a render); it does not produce a hang, which depends on where the signal lands.

Run: python tests/repro/sigint_handler_logs.py  -> exit 1 while the behaviour is present
(the handler ran Log from signal context: its message is printed during a render).
"""
import subprocess
import sys
import textwrap

#: Python source: ``fire_during_render()`` starts a thread that sends SIGINT to the process
#: the moment the C handler of SIGINT is no longer the one installed when it was called, i.e.
#: while a render's own handler is installed (glibc's struct sigaction, Linux).
FIRE_DURING_RENDER = textwrap.dedent('''
    import ctypes, os, signal, threading, time
    libc = ctypes.CDLL(None)
    class Sigaction(ctypes.Structure):
        _fields_ = [("handler", ctypes.c_void_p), ("mask", ctypes.c_ulong * 16),
                    ("flags", ctypes.c_int), ("restorer", ctypes.c_void_p)]
    def c_handler():
        sa = Sigaction()
        libc.sigaction(signal.SIGINT, None, ctypes.byref(sa))
        return sa.handler
    def fire_during_render():
        before = c_handler()
        def fire():
            while c_handler() == before:
                time.sleep(0.0005)
            os.kill(os.getpid(), signal.SIGINT)
        threading.Thread(target=fire, daemon=True).start()
''')

CHILD = FIRE_DURING_RENDER + textwrap.dedent('''
    try:                                   # phonglab pins a libLLVM that Dr.Jit can use
        import phonglab.runtime
        phonglab.runtime.configure()
    except ImportError:
        pass
    import drjit as dr
    import mitsuba as mi
    mi.set_variant("llvm_ad_rgb")
    scene = mi.load_dict(mi.cornell_box())
    fire_during_render()
    try:
        dr.eval(mi.render(scene, spp=64))
    except BaseException as exc:          # KeyboardInterrupt, or Dr.Jit's wrapper of it
        print("render raised", type(exc).__name__, flush=True)
    print("integrator cancelled:", scene.integrator().should_stop(), flush=True)
''')

if __name__ == "__main__":
    try:
        done = subprocess.run([sys.executable, "-c", CHILD], capture_output=True, text=True,
                              timeout=120)
    except subprocess.TimeoutExpired:
        print("the render hung after a Ctrl-C (a deadlock in Mitsuba's SIGINT handler)")
        sys.exit(1)
    out = done.stdout + done.stderr
    logged = "Received interrupt signal" in out
    print(f"Mitsuba's handler ran Log from signal context: {logged}; exit {done.returncode}; "
          + " ".join(ln for ln in out.splitlines() if "cancelled" in ln or "raised" in ln))
    sys.exit(1 if logged or done.returncode < 0 else 0)
