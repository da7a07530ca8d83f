"""The registry of message types: definitions in, md5 sums and full texts out.

How this works: a :class:`MsgRegistry` maps ``pkg/Name`` to a parsed :class:`MsgSpec`. The lab
ships comment-free definitions of every Noetic std_msgs, sensor_msgs and geometry_msgs type
under ``definitions/PKG/msg/NAME.msg``; more can be loaded from folders laid out the same way.
The md5 sum and the full text (``message_definition`` of a TCPROS header) are computed as
genmsg's ``compute_md5_text``/``compute_full_text`` do:

* md5 text: constants first (``TYPE NAME=VALUE_TEXT``), then fields (``TYPE NAME``), a nested
  message type (array or not) written as the md5 of that type; lines joined by ``\\n``;
* full text: the type's own text, then for every dependency (depth-first, first occurrence
  kept) a line of 80 ``=``, ``MSG: pkg/Type`` and that type's text.

Sums and derived codecs are cached and the caches are cleared whenever a definition changes.
"""

from __future__ import annotations

import difflib
import functools
import hashlib
from collections.abc import Callable, Iterable
from pathlib import Path
from typing import Any

from rosfpga_lab.msg.builtins import BUILTIN_TYPES, HEADER, HEADER_FULL_NAME
from rosfpga_lab.msg.errors import MsgDefinitionError, MsgError, UnknownTypeError
from rosfpga_lab.msg.limits import (
    MAX_MSG_FILE_BYTES, MAX_MSG_FILES, MAX_NESTING_DEPTH, MAX_SEARCH_DEPTH,
)
from rosfpga_lab.msg.parser import MsgSpec, bare_type, is_legal_base_name, parse_msg, split_full_text

#: Folder of the definitions the lab ships (``PKG/msg/NAME.msg``).
DEFINITIONS_DIR = Path(__file__).resolve().parent / "definitions"
SHIPPED_PACKAGES = ("std_msgs", "sensor_msgs", "geometry_msgs", "rosgraph_msgs", "roscpp")
FULL_TEXT_SEPARATOR = "=" * 80



def _primitive_hint(base_type: str) -> str:
    """``" -- did you mean the primitive 'float32'?"`` when a type's bare name is a likely
    misspelling of one (``flaot32`` is read as the message type ``my_msgs/flaot32``)."""
    bare = base_type.rsplit("/", 1)[-1]
    near = difflib.get_close_matches(bare.lower(), BUILTIN_TYPES, n=1, cutoff=0.7)
    return f" -- did you mean the primitive {near[0]!r}?" if near else ""

class MsgRegistry:
    """Message types by name, with genmsg-exact md5 sums and full texts.

    A new registry is empty; :meth:`with_defaults` gives one with the shipped packages.
    Registering a type that exists replaces its definition (the later one wins).
    """

    def __init__(self) -> None:
        self._specs: dict[str, MsgSpec] = {}
        self._searched: list[str] = []
        self._frozen = False
        self._direct = 0  # types registered with add()/add_full_text() rather than from files
        #: Caches of values derived from the definitions (md5, codecs); cleared on change.
        self._derived: dict[tuple[str, str], Any] = {}

    # -- building ---------------------------------------------------------------------
    @classmethod
    def with_defaults(cls) -> "MsgRegistry":
        """A new registry holding the shipped packages (:data:`SHIPPED_PACKAGES`)."""
        reg = cls()
        reg.load_path(DEFINITIONS_DIR, label="the lab's shipped definitions")
        return reg

    def _check_mutable(self) -> None:
        if self._frozen:
            raise MsgError("this registry is shared and read-only (default_registry()); "
                           "use MsgRegistry.with_defaults() for one you can add types to")

    def freeze(self) -> "MsgRegistry":
        """Make the registry read-only (used for the shared default registry)."""
        self._frozen = True
        return self

    def add(self, full_name: str, text: str, source: str | None = None, *,
            _loading_file: bool = False) -> MsgSpec:
        """Parse ``text`` as the definition of ``full_name`` and register it.

        Args:
            full_name: ``pkg/Name``.
            text: ``.msg`` text, kept as is for the full text.
            source: file path or label used in error messages.

        Returns:
            The registered spec.

        Raises:
            MsgDefinitionError: the text or name is malformed.
            MsgError: the registry is read-only.
        """
        self._check_mutable()
        spec = parse_msg(text, full_name, source)
        if full_name not in self._specs and not _loading_file:
            self._direct += 1
        self._specs[full_name] = spec
        self._derived.clear()
        return spec

    def load_file(self, path: str | Path, full_name: str | None = None) -> MsgSpec:
        """Register one ``.msg`` file; its type defaults to ``PKG/NAME`` from ``PKG/msg/NAME.msg``."""
        path = Path(path)
        if full_name is None:
            full_name = f"{path.parent.parent.name}/{path.stem}"
        try:
            size = path.stat().st_size
            if size > MAX_MSG_FILE_BYTES:
                raise MsgDefinitionError(
                    f"file is {size} bytes, more than the limit of {MAX_MSG_FILE_BYTES}", str(path))
            text = path.read_bytes().decode("utf-8")
        except UnicodeDecodeError as exc:
            raise MsgDefinitionError(f"not UTF-8 text ({exc.reason} at byte {exc.start})",
                                     str(path)) from None
        except OSError as exc:
            raise MsgDefinitionError(f"cannot read: {exc.strerror or exc}", str(path)) from None
        return self.add(full_name, text, str(path), _loading_file=True)

    def load_path(self, root: str | Path, label: str | None = None) -> list[str]:
        """Register every ``PKG/msg/NAME.msg`` under ``root``.

        ``root`` may be a package folder itself (it has a ``msg/`` folder) or any folder above
        packages (a catkin ``src`` folder, a metapackage): like rospkg, the search descends up
        to MAX_SEARCH_DEPTH levels, skips hidden folders, and stops at a package.

        Args:
            root: the folder.
            label: how error messages name this place (default: the path).

        Returns:
            Names of the types registered, sorted.

        Raises:
            MsgError: ``root`` is not a folder, or holds more than MAX_MSG_FILES files.
            MsgDefinitionError: a file is malformed (names file and line).
        """
        self._check_mutable()
        root = Path(root)
        if not root.is_dir():
            raise MsgError(f"message path {str(root)!r} is not a folder "
                           "(expected PKG/msg/NAME.msg files under it)")
        files = [f for pkg in _find_packages(root) for f in sorted((pkg / "msg").glob("*.msg"))]
        if len(files) > MAX_MSG_FILES:
            raise MsgError(f"{root}: {len(files)} .msg files, more than MAX_MSG_FILES={MAX_MSG_FILES}")
        self._searched.append(label or str(root))
        return sorted(self.load_file(f).full_name for f in files)

    # -- lookup -----------------------------------------------------------------------
    def __contains__(self, name: object) -> bool:
        return isinstance(name, str) and name in self._specs

    def __len__(self) -> int:
        return len(self._specs)

    def types(self, package: str | None = None) -> list[str]:
        """Sorted type names, optionally of one package."""
        return sorted(n for n, s in self._specs.items() if package is None or s.package == package)

    def packages(self) -> list[str]:
        """Sorted package names."""
        return sorted({s.package for s in self._specs.values()})

    def _where(self) -> str:
        places = list(self._searched)
        if self._direct:
            places.append(f"{self._direct} type(s) registered with add()")
        return ", ".join(places) if places else "nothing (empty registry)"

    def resolve(self, name: str, package: str | None = None) -> str:
        """The full name ``name`` refers to.

        Accepted: ``pkg/Name``, ``pkg/msg/Name``, ``Header`` (std_msgs/Header), ``Name`` in
        ``package``, or a ``Name`` only one loaded package has.

        Raises:
            UnknownTypeError: nothing (or more than one type) matches; says where it looked.
        """
        name = name.strip()
        if bare_type(name) in BUILTIN_TYPES:
            raise UnknownTypeError(f"{name!r} is a builtin type, not a message type", name)
        if name == HEADER:
            name = HEADER_FULL_NAME
        parts = name.split("/")
        if len(parts) == 3 and parts[1] == "msg":  # 'pkg/msg/Name' (rosbags, ROS 2 style)
            name = f"{parts[0]}/{parts[2]}"
        if "/" in name:
            if name in self._specs:
                return name
            candidates = [name]
        elif package is not None:
            full = f"{package}/{name}"
            if full in self._specs:
                return full
            candidates = [full]
        else:
            matches = [n for n, s in self._specs.items() if s.short_name == name]
            if len(matches) == 1:
                return matches[0]
            if len(matches) > 1:
                raise UnknownTypeError(
                    f"message type {name!r} is ambiguous: {', '.join(sorted(matches))}; "
                    "give the package (PKG/Name)", name, tuple(self._searched))
            raise UnknownTypeError(
                f"unknown message type {name!r}: no loaded package has a type of that name; "
                f"searched: {self._where()}", name, tuple(self._searched))
        pkg = candidates[0].split("/")[0]
        hint = ""
        if pkg not in self.packages():
            hint = f" (no package {pkg!r} is loaded; add its folder with --msg-path / load_path)"
        raise UnknownTypeError(
            f"unknown message type {candidates[0]!r}{hint}; searched: {self._where()}",
            candidates[0], tuple(self._searched))

    def get(self, name: str, package: str | None = None) -> MsgSpec:
        """The spec of ``name`` (see :meth:`resolve` for the accepted forms).

        Raises:
            UnknownTypeError: no such type.
        """
        return self._specs[self.resolve(name, package)]

    def _dep_spec(self, spec: MsgSpec, field_index: int) -> MsgSpec:
        f = spec.fields[field_index]
        if f.base_type in self._specs:
            return self._specs[f.base_type]
        where = f"{spec.source}:{f.line}" if spec.source else f"line {f.line}"
        raise UnknownTypeError(
            f"unknown message type {f.base_type!r}, used by field {f.name!r} of {spec.full_name} "
            f"({where}){_primitive_hint(f.base_type)}; searched: {self._where()}", f.base_type,
            tuple(self._searched))

    def nested(self, spec: MsgSpec) -> list[tuple[int, MsgSpec]]:
        """(field index, spec) of every message-typed field of ``spec``.

        Raises:
            UnknownTypeError: a field's type is not registered.
        """
        return [(i, self._dep_spec(spec, i)) for i, f in enumerate(spec.fields)
                if f.base_type not in BUILTIN_TYPES]

    def cached(self, kind: str, name: str, build: Callable[[], Any]) -> Any:
        """A value derived from the definitions, built once until a definition changes."""
        key = (kind, name)
        if key not in self._derived:
            self._derived[key] = build()
        return self._derived[key]

    def check(self, name: str) -> MsgSpec:
        """Resolve ``name`` and check its whole dependency tree exists and is not recursive.

        Raises:
            UnknownTypeError: a type in the tree is missing.
            MsgDefinitionError: the tree is recursive or nests deeper than MAX_NESTING_DEPTH.
        """
        spec = self.get(name)
        self.cached("check", spec.full_name, lambda: self._check_tree(spec, ()))
        return spec

    def _check_tree(self, spec: MsgSpec, stack: tuple[str, ...]) -> bool:
        if spec.full_name in stack:
            cycle = " -> ".join(stack[stack.index(spec.full_name):] + (spec.full_name,))
            raise MsgDefinitionError(f"recursive message definition: {cycle}", spec.source)
        if len(stack) >= MAX_NESTING_DEPTH:
            raise MsgDefinitionError(
                f"message types nest deeper than MAX_NESTING_DEPTH={MAX_NESTING_DEPTH}: "
                + " -> ".join(stack), spec.source)
        for _i, dep in self.nested(spec):
            self._check_tree(dep, stack + (spec.full_name,))
        return True

    # -- genmsg's sums and texts --------------------------------------------------------
    def md5_text(self, name: str) -> str:
        """The text genmsg hashes for ``name`` (compute_md5_text)."""
        spec = self.check(name)
        lines = [f"{c.type} {c.name}={c.value_text}" for c in spec.constants]
        nested = dict(self.nested(spec))
        for i, f in enumerate(spec.fields):
            if i in nested:
                lines.append(f"{self.md5(nested[i].full_name)} {f.name}")
            else:
                lines.append(f"{f.type} {f.name}")
        return "\n".join(lines).strip()

    def md5(self, name: str) -> str:
        """The md5 sum of ``name`` as genmsg computes it (hex string).

        Raises:
            UnknownTypeError: ``name`` or a type it uses is not registered.
        """
        full = self.resolve(name)
        return self.cached("md5", full, lambda: hashlib.md5(self.md5_text(full).encode()).hexdigest())

    def dependencies(self, name: str) -> list[str]:
        """Every message type ``name`` uses, in genmsg's full-text order (depth-first, unique)."""
        spec = self.check(name)
        out: list[str] = []

        def walk(s: MsgSpec) -> None:
            for _i, dep in self.nested(s):
                if dep.full_name not in out:
                    out.append(dep.full_name)
                walk(dep)

        walk(spec)
        return out

    def full_text(self, name: str) -> str:
        """The full definition text (``message_definition``), as genmsg compute_full_text builds it."""
        spec = self.check(name)

        def build() -> str:
            parts = [spec.text, "\n"]
            for dep in self.dependencies(spec.full_name):
                parts += [FULL_TEXT_SEPARATOR, "\n", f"MSG: {dep}\n", self._specs[dep].text, "\n"]
            return "".join(parts)[:-1]

        return self.cached("full_text", spec.full_name, build)

    def add_full_text(self, full_name: str, full_text: str, source: str | None = None) -> list[str]:
        """Register every type in a full text (e.g. a ``message_definition`` received over TCPROS).

        Returns:
            The names registered, top-level type first.
        """
        names = []
        for dep, text in split_full_text(full_text):
            self.add(dep or full_name, text, source or f"<full text of {full_name}>")
            names.append(dep or full_name)
        return names


def _find_packages(root: Path, depth: int = 0) -> list[Path]:
    """Package folders (with a ``msg/`` folder and a legal name) at or under ``root``."""
    if (root / "msg").is_dir():
        return [root] if is_legal_base_name(root.name) else []
    if depth >= MAX_SEARCH_DEPTH:
        return []
    found: list[Path] = []
    try:
        children = sorted(p for p in root.iterdir() if p.is_dir() and not p.name.startswith("."))
    except OSError:
        return []
    for child in children:
        found += _find_packages(child, depth + 1)
    return found


@functools.cache
def default_registry() -> MsgRegistry:
    """The shared, read-only registry of the shipped std_msgs, sensor_msgs and geometry_msgs."""
    return MsgRegistry.with_defaults().freeze()


def registry_with(paths: Iterable[str | Path]) -> MsgRegistry:
    """The shipped definitions plus every folder of ``paths`` (default registry if none)."""
    paths = list(paths)
    if not paths:
        return default_registry()
    reg = MsgRegistry.with_defaults()
    for p in paths:
        reg.load_path(p)
    return reg
