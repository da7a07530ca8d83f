"""What a student's `./lab.sh test` does not install into the lab's virtual environment.

Run by .ci/bare-machine with the virtual environment's own Python (python -I .ci/venv-extras.py
REPO): the extras `./lab.sh test` installs are the ones lab.sh names ([test], then [ros2]);
every other extra of pyproject.toml ([synth], [course]) is not there on a student's machine. Each
distribution those other extras bring (with their own requirements, transitively), and that the
installed extras do not bring too, is hidden: this prints, one a line,

    extras NAME...      the extras installed, then a line "hidden NAME..." of the others
    dist NAME VERSION   a distribution to hide
    file PATH           each of its files (its RECORD: modules, programs, data, its .dist-info),
                        less any file another installed distribution lists too
    module NAME         its top-level modules (no other distribution ships them): must not import
    program NAME        its programs (entry points and scripts in bin/): must be gone from PATH

Only distributions installed here are listed; the lists come from pyproject.toml, lab.sh and the
distributions' metadata, so a new package in an extra is hidden with no edit here.
"""

from __future__ import annotations

import importlib.metadata as md
import os
import re
import sys
import sysconfig
import tomllib
from pathlib import Path

try:
    from packaging.requirements import Requirement
    from packaging.utils import canonicalize_name
except ImportError:  # pragma: no cover - pip always vendors it
    from pip._vendor.packaging.requirements import Requirement  # type: ignore[no-redef]
    from pip._vendor.packaging.utils import canonicalize_name  # type: ignore[no-redef]


def lab_sh_extras(lab_sh: str, known: set[str]) -> set[str]:
    """The extras lab.sh installs: each ``[a,b]`` group of its code made only of extras' names."""
    found: set[str] = set()
    for line in lab_sh.splitlines():
        code = line.split("#", 1)[0] if not line.lstrip().startswith("#") else ""
        for group in re.findall(r"\[([A-Za-z0-9_,.-]+)\]", code):
            names = {canonicalize_name(n) for n in group.split(",")}
            if names <= known:
                found |= names
    return found


def closure(requirements: list[str], extras: set[str]) -> set[str]:
    """Installed distributions (canonical names) ``requirements`` bring, transitively; markers
    are evaluated for ``extras`` (the requested extras of the project itself)."""
    seen: dict[str, set[str]] = {}
    todo = [(Requirement(r), extras) for r in requirements]
    while todo:
        req, parent_extras = todo.pop()
        if req.marker and not any(req.marker.evaluate({"extra": e}) for e in parent_extras | {""}):
            continue
        name = canonicalize_name(req.name)
        wanted = {canonicalize_name(e) for e in req.extras}
        if name in seen and wanted <= seen[name]:
            continue
        try:
            dist = md.distribution(name)
        except md.PackageNotFoundError:
            continue   # not installed here (a marker's platform, or an optional one)
        seen[name] = seen.get(name, set()) | wanted
        todo += [(Requirement(r), seen[name]) for r in dist.requires or []]
    return set(seen)


def main(repo: Path) -> None:
    project = tomllib.loads((repo / "pyproject.toml").read_text())["project"]
    extras = {canonicalize_name(k): v for k, v in project["optional-dependencies"].items()}
    installed = lab_sh_extras((repo / "lab.sh").read_text(), set(extras))
    if "test" not in installed:
        sys.exit(f"venv-extras: found no [test] extra in {repo / 'lab.sh'}'s install commands")
    others = sorted(set(extras) - installed)
    kept = closure(list(project["dependencies"]) + [r for e in installed for r in extras[e]],
                   installed)
    # What a fresh virtual environment holds before lab.sh installs anything (ensurepip's).
    kept |= {"pip", "setuptools"}
    hide = closure([r for e in others for r in extras[e]], set(others)) - kept
    print("extras", *sorted(installed))
    print("hidden", *others)

    dists = {canonicalize_name(d.metadata["Name"]): d for d in md.distributions()}
    owned_elsewhere: set[Path] = set()
    tops_elsewhere: set[str] = set()
    site = Path(sysconfig.get_paths()["purelib"]).resolve()
    scripts = Path(sysconfig.get_paths()["scripts"]).resolve()

    def files(dist: md.Distribution) -> list[Path]:
        base = Path(dist.locate_file("")).resolve()   # its RECORD's paths are relative to it
        return [Path(os.path.normpath(base / f)) for f in dist.files or []]

    def top(path: Path) -> str | None:
        """The top-level module a file of site-packages belongs to, or None."""
        try:
            first = path.relative_to(site).parts[0]
        except ValueError:
            return None
        if first.endswith((".dist-info", ".egg-info", ".data", ".pth")) or first == "__pycache__":
            return None
        name = first.split(".")[0] if "." in first else first
        return name if name.isidentifier() else None

    for name, dist in dists.items():
        if name not in hide:
            for path in files(dist):
                owned_elsewhere.add(path)
                tops_elsewhere.add(top(path) or "")
    for name in sorted(hide):
        dist = dists[name]
        print("dist", dist.metadata["Name"], dist.version)
        modules: set[str] = set()
        programs = {ep.name for ep in dist.entry_points
                    if ep.group in ("console_scripts", "gui_scripts")}
        for path in files(dist):
            if path in owned_elsewhere:
                continue
            print("file", path)
            if path.parent == scripts:
                programs.add(path.name)
            module = top(path)
            if module and module not in tops_elsewhere:
                modules.add(module)
        for module in sorted(modules):
            print("module", module)
        for program in sorted(programs):
            print("program", program)


if __name__ == "__main__":
    main(Path(sys.argv[1]).resolve())
