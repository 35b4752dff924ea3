"""Check every conformance finding's citation against Mitsuba 3.9.1's source.

    python scripts/check_citations.py --src DIR        # a v3.9.1 source tree (checkout/archive)
    python scripts/check_citations.py --mirror GITDIR [--rev REV]    # a git repository holding
                                                       # the release (REV: MITSUBA_COMMIT)
    python scripts/check_citations.py --headers DIR    # only the headers: DIR/mitsuba/... holds
                                                       # include/mitsuba/... (the wheel's include)
    python scripts/check_citations.py                  # $MITSUBA_SRC, else the mirror at
                                                       # MIRROR if present, else the wheel's headers

Every :class:`~phonglab.validate.conformance.Finding` of every kind (bsdf, emitter, integrator,
phase: ``phonglab.validate.registry``) cites ``path:LINE`` and stores an ``excerpt`` of the code
there: the line must hold the excerpt (runs of whitespace compared as one space).  Every other
``file.ext:N`` or ``file.ext:N-M`` (and ``file.ext:N, M-K``) its cause, measured and expected
texts quote -- and the explanations of the validator issues -- must name lines that exist in
that file and are not blank (a bare name such as ``path.cpp`` is looked up by its name, next to
the finding's own file first).  A ``plugins/...`` or ``src/phonglab/...`` path is phonglab's
own file, read from this repository.  Citations of files the tree does not hold (a ``.cpp``
against the headers alone) are skipped and counted.  Exit 1 with the list of mismatches.
"""

from __future__ import annotations

import argparse
import os
import re
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
#: Where this workplace keeps a bare mirror of mitsuba-renderer/mitsuba3 (holds tag v3.9.1).
MIRROR = Path("/work/.mirror/mitsuba-renderer+mitsuba3/repo")
OWN = ("plugins/", "src/phonglab/")

#: ``file.ext:N``, ``file.ext:N-M`` and further ``, K`` / ``, K-L`` of the same file.
REF = re.compile(r"(?<![\w/.-])((?:[\w.-]+/)*[\w-]+\.(?:cpp|h|py)):(\d+)(?:-(\d+))?"
                 r"((?:,\s*\d+(?:-\d+)?(?![\d.]))*)")
CONTINUED = re.compile(r"(\d+)(?:-(\d+))?")


def norm(text: str) -> str:
    """Runs of whitespace as one space, ends stripped."""
    return " ".join(text.split())


class DirTree:
    """A source tree in a folder (a checkout or an archive of the release)."""

    def __init__(self, root):
        self.root = Path(root)
        self.name = str(root)
        self._index = None

    def lines(self, path: str):
        p = self.root / path
        return p.read_text(errors="replace").splitlines() if p.is_file() else None

    def files(self) -> list[str]:
        if self._index is None:
            self._index = [os.path.relpath(os.path.join(d, f), self.root)
                           for top in ("src", "include") if (self.root / top).is_dir()
                           for d, _, fs in os.walk(self.root / top) for f in fs]
        return self._index


class GitTree:
    """A revision of a git repository (bare or not), read with ``git show REV:path``."""

    def __init__(self, gitdir, rev):
        self.gitdir, self.rev = str(gitdir), rev
        self.name = f"{gitdir}@{rev}"
        self._index = None
        self._cache = {}

    def _git(self, *args):
        return subprocess.run(["git", "-C", self.gitdir, *args], capture_output=True,
                              text=True, errors="replace")

    def lines(self, path: str):
        if path not in self._cache:
            r = self._git("show", f"{self.rev}:{path}")
            self._cache[path] = r.stdout.splitlines() if r.returncode == 0 else None
        return self._cache[path]

    def files(self) -> list[str]:
        if self._index is None:
            r = self._git("ls-tree", "-r", "--name-only", self.rev)
            if r.returncode != 0:
                raise SystemExit(f"check_citations: cannot list {self.name}: {r.stderr.strip()}")
            self._index = r.stdout.splitlines()
        return self._index


class HeaderTree(DirTree):
    """The headers alone, as the mitsuba wheel ships them: ``DIR/mitsuba/...`` is the source
    tree's ``include/mitsuba/...``; anything else is not in it."""

    def lines(self, path: str):
        if not path.startswith("include/"):
            return None
        p = self.root / path[len("include/"):]
        return p.read_text(errors="replace").splitlines() if p.is_file() else None

    def files(self) -> list[str]:
        if self._index is None:
            self._index = ["include/" + os.path.relpath(os.path.join(d, f), self.root)
                           for d, _, fs in os.walk(self.root) for f in fs]
        return self._index


def wheel_headers() -> Path | None:
    """The include folder of the installed mitsuba wheel (found without importing it)."""
    import importlib.util

    spec = importlib.util.find_spec("mitsuba")     # once imported, an alias module's spec
    places = list(spec.submodule_search_locations or []) if spec else []
    places += [Path(spec.origin).parent] if spec and spec.origin else []
    for loc in places:
        if (Path(loc) / "include" / "mitsuba").is_dir():
            return Path(loc) / "include"
    return None


@dataclass
class Result:
    mismatches: list
    checked: int          #: citations checked (lines read)
    skipped: list         #: citations of files the tree does not hold
    findings: int


def _own(path: str):
    p = REPO / path
    return p.read_text(errors="replace").splitlines() if p.is_file() else None


def _lines(tree, path: str):
    return _own(path) if path.startswith(OWN) else tree.lines(path)


def _resolve(tree, name: str, near: str):
    """The tree path of a cited file: ``name`` itself when it holds a folder, else the file of
    that name next to ``near`` (the finding's own file), else the one file of that name;
    (None, why) when there is none or several."""
    if "/" in name:
        return name, ""
    if near and not near.startswith(OWN):
        beside = str(Path(near).parent / name)
        if _lines(tree, beside) is not None:
            return beside, ""
    hits = [f for f in tree.files() if f.rsplit("/", 1)[-1] == name]
    if len(hits) == 1:
        return hits[0], ""
    return None, ("no file of that name" if not hits
                  else f"several files of that name: {', '.join(sorted(hits)[:4])}")


def references(text: str):
    """(file, first, last, the cited text) for each ``file.ext:N[-M][, K[-L]...]`` in text."""
    for m in REF.finditer(text):
        name = m.group(1)
        spans = [(int(m.group(2)), int(m.group(3) or m.group(2)))]
        spans += [(int(a), int(b or a)) for a, b in CONTINUED.findall(m.group(4) or "")]
        for a, b in spans:
            yield name, a, b, m.group(0)


def check(tree, findings, issues=()) -> Result:
    """Every excerpt and quoted line of ``findings`` (and of ``issues``' explanations) against
    ``tree`` (:class:`DirTree`, :class:`GitTree` or :class:`HeaderTree`)."""
    bad, skipped, checked = [], [], 0

    def line_ok(who, path, a, b, cited):
        nonlocal checked
        lines = _lines(tree, path)
        if lines is None:
            skipped.append(f"{who}: {cited} ({path} not in {tree.name})")
            return
        checked += 1
        for n in {a, b}:
            if not 1 <= n <= len(lines) or a > b:
                bad.append(f"{who}: {cited}: {path} has {len(lines)} lines")
                return
            if not lines[n - 1].strip():
                bad.append(f"{who}: {cited}: line {n} of {path} is blank")

    for f in findings:
        who = f.key
        path, _, line = f.source.rpartition(":")
        first, _, last = line.partition("-")
        first, last = int(first), int(last or first)
        lines = _lines(tree, path)
        if lines is None:
            skipped.append(f"{who}: {f.source} (not in {tree.name})")
        elif not f.excerpt:
            bad.append(f"{who}: {f.source}: no excerpt")
        else:
            checked += 1
            held = norm(" ".join(lines[first - 1:last])) if 1 <= first <= last <= len(lines) else None
            if held is None:
                bad.append(f"{who}: {f.source}: {path} has {len(lines)} lines")
            elif norm(f.excerpt) not in held:
                bad.append(f"{who}: {f.source} does not hold {f.excerpt!r}; it reads {held!r}")
        for text in (f.cause, f.measured, f.expected):
            for name, a, b, cited in references(text):
                where, why = _resolve(tree, name, path)
                if where is None:      # the headers alone lack every .cpp: not a mismatch
                    (skipped if isinstance(tree, HeaderTree) else bad).append(
                        f"{who}: {cited}: {why}")
                    continue
                line_ok(who, where, a, b, cited)
    for v in issues:
        for name, a, b, cited in references(v.explanation):
            where, why = _resolve(tree, name, "")
            if where is None:
                (skipped if isinstance(tree, HeaderTree) else bad).append(
                    f"validator issue {v.key}: {cited}: {why}")
                continue
            line_ok(f"validator issue {v.key}", where, a, b, cited)
    return Result(bad, checked, skipped, len(findings))


def every_finding():
    """(findings, validator issues) of every kind's conformance table."""
    sys.path.insert(0, str(REPO / "src"))
    from phonglab.validate import registry

    findings, issues = [], []
    for kind in registry.names():
        cat = registry.catalogue(kind)
        findings += list(cat.findings)
        issues += list(cat.validator_issues)
    return findings, issues


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    where = ap.add_mutually_exclusive_group()
    where.add_argument("--src", type=Path, help="a Mitsuba v3.9.1 source tree (folder)")
    where.add_argument("--mirror", type=Path, help="a git repository holding the release")
    where.add_argument("--headers", type=Path,
                       help="an include folder (DIR/mitsuba/...): the headers only")
    ap.add_argument("--rev", help="the revision in --mirror (default: MITSUBA_COMMIT, v3.9.1)")
    ap.add_argument("-v", "--verbose", action="store_true", help="list the skipped citations")
    args = ap.parse_args(argv)
    findings, issues = every_finding()
    from phonglab.validate.conformance import MITSUBA_COMMIT

    if args.src:
        tree = DirTree(args.src)
    elif args.mirror:
        tree = GitTree(args.mirror, args.rev or MITSUBA_COMMIT)
    elif args.headers:
        tree = HeaderTree(args.headers)
    elif os.environ.get("MITSUBA_SRC"):
        tree = DirTree(os.environ["MITSUBA_SRC"])
    elif MIRROR.is_dir():
        tree = GitTree(MIRROR, args.rev or MITSUBA_COMMIT)
    else:
        headers = wheel_headers()
        if headers is None:
            ap.error("no source: give --src, --mirror or --headers (no mitsuba wheel found)")
        tree = HeaderTree(headers)
    res = check(tree, findings, issues)
    for m in res.mismatches:
        print(m)
    if args.verbose:
        for s in res.skipped:
            print("skipped:", s)
    print(f"{res.findings} findings, {len(issues)} validator issues: {res.checked} citations "
          f"checked against {tree.name}, {len(res.mismatches)} mismatches, "
          f"{len(res.skipped)} skipped (not in that tree)")
    return 1 if res.mismatches else 0


if __name__ == "__main__":
    sys.exit(main())
