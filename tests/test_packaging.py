"""An installed phonglab is the whole phonglab: the distribution ships every subpackage and
every file the package reads at run time.

Default tier: the packages setup.py finds (none listed by hand) against src/; every data file
under src/phonglab declared as package data; the shipped scenes found with importlib.resources
inside the package, with every file they name beside them; no module reaching out of its
package folder.  Slow tier: the wheel built from the checkout, installed with
constraints.txt into a fresh venv, and the commands a user runs, from a folder outside the
checkout (the only proof that nothing is read from the source tree).
"""

from __future__ import annotations

import fnmatch
import os
import re
import runpy
import shutil
import subprocess
import sys
import textwrap
import time
import tomllib
import xml.etree.ElementTree as ET
from importlib import resources
from pathlib import Path

import pytest

import phonglab
from phonglab.engine import references
from phonglab.engine.scenes import SCENES_DIR, scene_path

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = Path(phonglab.__file__).resolve().parent
SETUPTOOLS = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]
#: The packages the distribution ships (setup.py finds them).
PACKAGES = runpy.run_path(str(ROOT / "setup.py"), run_name="setup")["PACKAGES"]
#: Modules allowed to name a path outside their package, and why: nothing there is read.
OUTSIDE_ALLOWED = {
    "src/phonglab/engine/references.py": "the reference cache defaults to the checkout's .bench_cache/ when "
                     "phonglab runs from one (a write location; the user's cache otherwise)",
    "src/phonglab/validate/kind.py": "a report links the docs site the checkout's make docs built "
                     "(a link, never read; $PHONGLAB_DOCS_URL or no link otherwise)",
}


def test_every_subpackage_ships():
    """Every package under src/ and phonglab.plugins (plugins/) is one the distribution ships:
    found by setup.py, so a new one (a validator kind's folder) needs no list edited."""
    src = ROOT / "src"
    found = {".".join(p.parent.relative_to(src).parts) for p in src.rglob("__init__.py")}
    missing = sorted((found | {"phonglab.plugins"}) - set(PACKAGES))
    assert not missing, f"setup.py's find leaves out {missing}"
    assert not [p for p in PACKAGES if "__pycache__" in p]
    assert "packages" not in SETUPTOOLS, "pyproject.toml lists packages; setup.py finds them"


def test_every_package_shipped_exists():
    """A package moved away but still named breaks `pip install` (and so `make setup`) on a
    fresh clone: "package directory 'src/phonglab/validate/builtins' does not exist"."""
    dirs = {p: ROOT / d for p, d in SETUPTOOLS["package-dir"].items() if p}
    gone = sorted(p for p in PACKAGES
                  if not dirs.get(p, ROOT / "src" / Path(*p.split("."))).is_dir())
    assert not gone, f"{gone} are shipped but have no folder"


def _declared(path: Path) -> bool:
    """Whether pyproject's package-data ships ``path`` (a file under src/phonglab)."""
    rel = path.relative_to(ROOT / "src")
    package = ".".join(rel.parent.parts)
    if package not in PACKAGES:
        return False
    globs = SETUPTOOLS.get("package-data", {}).get(package, [])
    return any(fnmatch.fnmatch(rel.name, g) for g in globs)


def test_every_data_file_in_the_package_is_declared_package_data():
    """A file added beside the code (a scene, a texture) that pyproject does not declare
    would work from the checkout and be missing from the wheel."""
    data = [p for p in (ROOT / "src" / "phonglab").rglob("*")
            if p.is_file() and p.suffix not in (".py", ".pyc") and "__pycache__" not in p.parts]
    assert data, "no data files found under src/phonglab (the scenes moved?)"
    missing = [str(p.relative_to(ROOT)) for p in data if not _declared(p)]
    assert not missing, (f"declare {missing} in [tool.setuptools.package-data] of "
                         f"pyproject.toml, or the wheel leaves them out")


def test_shipped_scenes_resolve_inside_the_package_with_importlib_resources():
    assert SCENES_DIR == Path(str(resources.files("phonglab") / "scenes_xml"))
    assert SCENES_DIR.resolve().is_relative_to(PACKAGE)
    path = scene_path("cornell_phong")
    assert path.resolve().is_relative_to(PACKAGE) and path.is_file()
    assert scene_path("cornell_phong.xml") == path


@pytest.mark.parametrize("scene", sorted(p.name for p in SCENES_DIR.glob("*.xml")))
def test_every_file_a_shipped_scene_names_is_shipped_beside_it(scene):
    """Textures, environment maps and includes are named relative to the scene file; each
    must lie inside the package and be declared, or the installed scene cannot load."""
    path = SCENES_DIR / scene
    for el in ET.parse(path).getroot().iter():
        name = el.get("value") if el.get("name") == "filename" else (
            el.get("filename") if el.tag == "include" else None)
        if name is None or "$" in name:
            continue
        target = (path.parent / name).resolve()
        assert target.is_file(), f"{scene} names {name}, which does not exist"
        assert target.is_relative_to(PACKAGE), f"{scene} names {name}, outside the package"
        assert _declared(target), f"{scene} names {name}, not declared as package data"


def test_the_reference_cache_is_the_checkouts_or_the_users(monkeypatch, tmp_path):
    """An installed package's folder may not be writable: its cache is the user's."""
    monkeypatch.delenv("PHONGLAB_CACHE", raising=False)
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    assert references.default_cache_dir() == ROOT / ".bench_cache"
    site = tmp_path / "venv" / "lib" / "python3.11" / "site-packages" / "phonglab"
    monkeypatch.setattr(references, "__file__", str(site / "references.py"))
    assert references.default_cache_dir() == tmp_path / "xdg" / "phonglab"
    monkeypatch.setenv("PHONGLAB_CACHE", str(tmp_path / "mine"))
    assert references.default_cache_dir() == tmp_path / "mine"


_OUTSIDE = re.compile(r"parents\[\d+\]|\.parent\.parent|REPO_ROOT|\"\.\./|'\.\./")


def test_no_module_reads_a_path_outside_its_package():
    """``Path(__file__).parents[2] / "scenes_xml"`` worked in the checkout only."""
    found = []
    for root in (ROOT / "src" / "phonglab", ROOT / "plugins"):
        for f in root.rglob("*.py"):
            for n, line in enumerate(f.read_text().splitlines(), 1):
                if (_OUTSIDE.search(line)
                        and str(f.relative_to(ROOT)) not in OUTSIDE_ALLOWED):
                    found.append(f"{f.relative_to(ROOT)}:{n}: {line.strip()}")
    assert not found, "ship the file as package data and find it with importlib.resources:\n" \
        + "\n".join(found)


# ------------------------------------------------------------------------------------------
# Slow tier: the wheel in a fresh venv
# ------------------------------------------------------------------------------------------

MYBSDF = '''\
"""A Lambertian BSDF, f = rho/pi, with cosine-weighted sampling."""

import drjit as dr
import mitsuba as mi


class MyBSDF(mi.BSDF):
    PARAMETER_RANGES = {"reflectance": (0.0, 1.0)}

    def __init__(self, props):
        mi.BSDF.__init__(self, props)
        self.reflectance = mi.Float(props.get("reflectance", 0.5))
        self.m_components = [mi.BSDFFlags.DiffuseReflection | mi.BSDFFlags.FrontSide]
        self.m_flags = self.m_components[0]

    def traverse(self, callback):
        callback.put("reflectance", self.reflectance, mi.ParamFlags.Differentiable)

    def _lit(self, si, wo):
        return (mi.Frame3f.cos_theta(si.wi) > 0) & (mi.Frame3f.cos_theta(wo) > 0)

    def eval(self, ctx, si, wo, active=True):
        value = self.reflectance * dr.inv_pi * mi.Frame3f.cos_theta(wo)
        return dr.select(self._lit(si, wo), mi.Spectrum(value), 0.0)

    def pdf(self, ctx, si, wo, active=True):
        return dr.select(self._lit(si, wo), mi.warp.square_to_cosine_hemisphere_pdf(wo), 0.0)

    def eval_pdf(self, ctx, si, wo, active=True):
        return self.eval(ctx, si, wo, active), self.pdf(ctx, si, wo, active)

    def sample(self, ctx, si, sample1, sample2, active=True):
        bs = dr.zeros(mi.BSDFSample3f)
        bs.wo = mi.warp.square_to_cosine_hemisphere(sample2)
        bs.pdf = self.pdf(ctx, si, bs.wo)
        bs.eta = 1.0
        bs.sampled_type = mi.UInt32(int(mi.BSDFFlags.DiffuseReflection))
        bs.sampled_component = mi.UInt32(0)
        value = self.eval(ctx, si, bs.wo) / dr.select(bs.pdf > 0, bs.pdf, 1.0)
        return bs, dr.select(bs.pdf > 0, value, 0.0)

    def eval_diffuse_reflectance(self, si, active=True):
        return mi.Spectrum(self.reflectance)

    def to_string(self):
        return "MyBSDF[]"


mi.register_bsdf("mybsdf", lambda props: MyBSDF(props))
'''

TEST_MYBSDF = '''\
from pathlib import Path

from phonglab.testing import assert_bsdf_valid

HERE = Path(__file__).parent


def test_mybsdf_is_physical():
    assert_bsdf_valid("mybsdf", plugins=[HERE / "mybsdf.py"], quick=True)
'''


def _run(args, cwd, env, timeout=600):
    t0 = time.perf_counter()
    p = subprocess.run([str(a) for a in args], cwd=cwd, env=env, capture_output=True,
                       text=True, timeout=timeout)
    assert p.returncode == 0, (f"{' '.join(map(str, args))} exited {p.returncode} in {cwd}:\n"
                               f"{p.stdout[-3000:]}\n{p.stderr[-3000:]}")
    print(f"{time.perf_counter() - t0:6.1f} s  {' '.join(map(str, args))}")
    return p


@pytest.mark.slow
def test_the_wheel_in_a_fresh_venv_works_from_outside_the_checkout(tmp_path):
    """README's "Install into your own environment", command for command.  The source is
    the checkout's tracked and untracked-not-ignored files, copied: an in-tree build/ left
    by an earlier build cannot slip a file into the wheel."""
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "VIRTUAL_ENV")}
    env["PHONGLAB_CACHE"] = str(tmp_path / "cache")
    files = subprocess.run(["git", "ls-files", "-z", "--cached", "--others", "--exclude-standard"],
                           cwd=ROOT, capture_output=True, check=True).stdout.decode().split("\0")
    src = tmp_path / "src"
    for name in filter(None, files):
        if (ROOT / name).is_file():
            (src / name).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(ROOT / name, src / name)
    wheels, venv, work = tmp_path / "wheels", tmp_path / "venv", tmp_path / "work"
    work.mkdir()
    _run([sys.executable, "-m", "pip", "wheel", "--no-deps", "-q", "-w", wheels, src], tmp_path, env)
    wheel = next(wheels.glob("phonglab-*.whl"))
    _run([sys.executable, "-m", "venv", venv], tmp_path, env)
    bin_ = venv / "bin"
    _run([bin_ / "python", "-m", "pip", "install", "-q", "-c", ROOT / "constraints.txt",
          wheel, "pytest"], tmp_path, env)

    where = _run([bin_ / "python", "-c", "import phonglab, phonglab.engine.scenes as s; "
                  "print(phonglab.__file__); print(s.scene_path('textured_room'))"], work, env)
    module, scene = where.stdout.split()
    assert Path(module).is_relative_to(venv) and Path(scene).is_relative_to(venv), where.stdout
    _run([bin_ / "phonglab", "doctor"], work, env)
    _run([bin_ / "phonglab", "check", "--no-progress"], work, env)
    r = _run([bin_ / "phonglab", "render", "cornell_phong", "--spp", "4", "-D", "res=32",
              "-o", "out/cornell.exr"], work, env)
    assert (work / "out" / "cornell.exr").is_file() and (work / "out" / "cornell.png").is_file()
    assert str(venv) in r.stdout, r.stdout        # the scene came from the installed package
    # A scene whose textures are named relative to it.
    _run([bin_ / "phonglab", "render", "textured_room", "--spp", "1", "-D", "res=16",
          "-o", "out/room.exr"], work, env)
    _run([bin_ / "phonglab", "plan", "gray_direct", "-D", "res=16"], work, env)
    _run([bin_ / "phonglab", "compare-models", "exponent_series", "--spp", "1",
          "--path-spp", "4", "-o", "out/models"], work, env)
    (work / "mybsdf.py").write_text(MYBSDF)
    (work / "test_mybsdf.py").write_text(TEST_MYBSDF)
    _run([bin_ / "phonglab", "validate", "mybsdf", "--plugin", "mybsdf.py", "--quick"], work, env)
    _run([bin_ / "python", "-m", "pytest", "-q", "-p", "no:cacheprovider", "test_mybsdf.py"],
         work, env)


def test_readme_install_section_is_the_tested_commands():
    """README's section names the commands the slow test runs, so the two cannot drift."""
    text = (ROOT / "README.md").read_text()
    m = re.search(r"## Install into your own environment\n(.*?)\n## ", text, re.S)
    assert m, "README.md has no '## Install into your own environment' section"
    section = m.group(1)
    for command in ("pip wheel --no-deps", "-m venv", "pip install -c constraints.txt",
                    "phonglab doctor", "phonglab check",
                    "phonglab render cornell_phong --spp 4",
                    "phonglab validate mybsdf --plugin mybsdf.py --quick",
                    "assert_bsdf_valid", "pytest test_mybsdf.py"):
        assert command in section, f"README's install section lacks {command!r}"
    assert textwrap.dedent(TEST_MYBSDF).strip().splitlines()[-1].strip() in section
