"""phonglab: Lambert and modified-Phong BSDFs for Mitsuba 3, and the checks that ground them in physics.

Importing phonglab sets no Mitsuba variant; :func:`register` does that work::

    import mitsuba as mi, phonglab
    from phonglab.engine.scenes import scene_path
    phonglab.register()                 # llvm_ad_rgb unless a variant is already set
    scene = mi.load_file(str(scene_path("cornell_phong")))   # a scene shipped with phonglab

It pins ``DRJIT_LIBLLVM_PATH`` to a libLLVM Dr.Jit 1.5 can use (see
:mod:`phonglab.runtime`) before Dr.Jit loads one.
"""

__version__ = "0.1.0"

from . import runtime  # noqa: E402  (pins libLLVM before anything imports Dr.Jit)

runtime.configure()

from .registration import register, registered_variants  # noqa: E402
__all__ = ["register", "registered_variants", "__version__"]
