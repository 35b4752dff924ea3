"""The one thing pyproject.toml cannot say: which packages the distribution ships.

Every package under src/ is found, not listed (setuptools' namespace find: the data folders
phonglab.scenes_xml and phonglab.scenes_xml.textures have no ``__init__.py``), so a new
subpackage -- a validator kind's folder -- ships without an edit here; and phonglab.plugins,
which lives in plugins/ (pyproject's package-dir), is added by name, since a find under src/
cannot see it.  Everything else is pyproject.toml's.
"""

from setuptools import find_namespace_packages, setup

#: The packages of the distribution.
PACKAGES = sorted(find_namespace_packages("src", include=["phonglab", "phonglab.*"],
                                          exclude=["*.__pycache__"]) + ["phonglab.plugins"])

if __name__ == "__main__":
    setup(packages=PACKAGES)
