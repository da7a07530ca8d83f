"""Parse ROS 1 ``.msg`` text into a :class:`MsgSpec`, following genmsg's rules exactly.

How this works: the text is split on ``\\n``. On each line everything from the first ``#`` is a
comment; a line empty after that is skipped. A line whose comment-free part contains ``=`` is a
constant, every other line a field ``TYPE NAME`` (type and name separated by spaces; genmsg does
not split on tabs). Quirks kept on purpose, because the md5 sum depends on them:

* a ``string`` constant's value is the rest of the *original* line after the first ``=``, so
  ``#`` and anything after it belong to the value; the value is stripped of surrounding
  whitespace (``string S = a # b`` has the value ``a # b``);
* constant values are recorded with their text (``val_text``) as written, stripped, which is
  what goes into the md5 text (``int8 X = +01`` hashes as ``int8 X=+01``);
* a field type without a package is resolved in the message's own package, except builtins and
  the bare ``Header``, which means ``std_msgs/Header`` (only exactly ``Header``, not ``Header[]``).

:func:`strip_comments` defines the comment-free text the lab ships (see its docstring).
"""

from __future__ import annotations

import ast
import re
from dataclasses import dataclass, field

from rosfpga_lab.msg.builtins import (
    BUILTIN_TYPES, FLOAT_TYPES, HEADER, HEADER_FULL_NAME, PRIMITIVE_TYPES, integer_bounds,
)
from rosfpga_lab.msg.errors import MsgDefinitionError

COMMENT_CHAR = "#"
CONST_CHAR = "="
SEP = "/"

_BASE_NAME = re.compile(r"^[A-Za-z]\w*$")


def is_legal_base_name(name: str) -> bool:
    """genmsg's rule for field names, package names and short type names."""
    return bool(_BASE_NAME.fullmatch(name))


def bare_type(type_name: str) -> str:
    """``'geometry_msgs/Point[3]'`` -> ``'geometry_msgs/Point'``."""
    i = type_name.find("[")
    return type_name if i < 0 else type_name[:i]


def split_full_name(full_name: str) -> tuple[str, str]:
    """Split ``'pkg/Name'``; raise ValueError unless it is exactly two legal names."""
    parts = full_name.split(SEP)
    if len(parts) != 2 or not all(is_legal_base_name(p) for p in parts):
        raise ValueError(f"{full_name!r} is not a message type name of the form 'package/Name'")
    return parts[0], parts[1]


@dataclass(frozen=True)
class Field:
    """One field of a message.

    Attributes:
        name: field name.
        type: type as genmsg stores it after resolution, e.g. ``uint8[]``, ``std_msgs/Header``,
            ``geometry_msgs/Point[3]``.
        base_type: ``type`` without the array suffix.
        is_array: True for ``T[]`` and ``T[N]``.
        array_length: N for ``T[N]``, None otherwise.
        line: 1-based line in the definition text (0 if unknown).
    """

    name: str
    type: str
    base_type: str
    is_array: bool = False
    array_length: int | None = None
    line: int = 0

    @property
    def is_builtin(self) -> bool:
        """True if the element type is a builtin (including time and duration)."""
        return self.base_type in BUILTIN_TYPES


@dataclass(frozen=True)
class Constant:
    """One constant declaration.

    Attributes:
        type: a primitive type (``int8`` ... ``string``, ``bool``, ``char``, ``byte``).
        name: constant name.
        value: the value as Python int, float, bool or str.
        value_text: the value as written, stripped (what the md5 text uses).
        line: 1-based line in the definition text.
    """

    type: str
    name: str
    value: int | float | bool | str
    value_text: str
    line: int = 0


@dataclass(frozen=True)
class MsgSpec:
    """A parsed message definition.

    Attributes:
        full_name: ``pkg/Name``.
        package: ``pkg``.
        short_name: ``Name``.
        fields: fields in declaration order.
        constants: constants in declaration order.
        text: the definition text exactly as given (it goes into the full text).
        source: file path or label the text came from (None if unknown).
    """

    full_name: str
    package: str
    short_name: str
    fields: tuple[Field, ...]
    constants: tuple[Constant, ...]
    text: str
    source: str | None = field(default=None, compare=False)

    @property
    def field_names(self) -> list[str]:
        """Field names in order (genpy's ``__slots__``)."""
        return [f.name for f in self.fields]

    @property
    def field_types(self) -> list[str]:
        """Field types in order (genpy's ``_slot_types``)."""
        return [f.type for f in self.fields]

    @property
    def has_header(self) -> bool:
        """True if the first field is ``std_msgs/Header header`` (genmsg's rule)."""
        return bool(self.fields) and self.fields[0].type == HEADER_FULL_NAME \
            and self.fields[0].name == "header"


def _strip_line(line: str) -> str:
    return line.split(COMMENT_CHAR)[0].strip()


def _split_words(clean: str) -> list[str]:
    return [s for s in (x.strip() for x in clean.split(" ")) if s]


def _convert_constant(type_name: str, text: str) -> int | float | bool | str:
    """genmsg's convert_constant_value; raises ValueError with a reason."""
    if type_name in FLOAT_TYPES:
        return float(text)
    if type_name == "string":
        return text.strip()
    if type_name == "bool":
        try:
            return bool(ast.literal_eval(text.strip()))
        except (ValueError, SyntaxError):
            raise ValueError("expected a literal such as True, False, 1 or 0") from None
    low, high = integer_bounds(type_name)
    value = int(text)
    if not low <= value <= high:
        raise ValueError(f"{value} is out of range for {type_name} ({low}..{high})")
    return value


def _parse_constant(orig: str, clean: str, lineno: int, source: str | None) -> Constant:
    words = _split_words(clean)
    type_name = words[0]
    if type_name not in PRIMITIVE_TYPES:
        raise MsgDefinitionError(
            f"{type_name!r} is not a legal constant type (constants must be one of "
            f"{', '.join(PRIMITIVE_TYPES)}; arrays, time and messages cannot be constants)",
            source, lineno, orig)
    if type_name == "string":
        idx = orig.find(CONST_CHAR)
        name = orig[orig.find(" ") + 1:idx].strip()
        value_text = orig[idx + 1:]
    else:
        parts = [x.strip() for x in " ".join(words[1:]).split(CONST_CHAR)]
        if len(parts) != 2:
            raise MsgDefinitionError("a constant needs exactly one '=' (TYPE NAME=VALUE)",
                                     source, lineno, orig)
        name, value_text = parts
    if not is_legal_base_name(name):
        raise MsgDefinitionError(f"{name!r} is not a legal constant name", source, lineno, orig)
    try:
        value = _convert_constant(type_name, value_text)
    except (ValueError, SyntaxError, TypeError, MemoryError, RecursionError) as exc:
        raise MsgDefinitionError(f"invalid {type_name} constant value {value_text.strip()!r}: {exc}",
                                 source, lineno, orig) from None
    return Constant(type_name, name, value, value_text.strip(), lineno)


def _parse_array_suffix(type_name: str) -> tuple[str, bool, int | None] | None:
    """Split ``T[]``/``T[N]``; None if the suffix is malformed."""
    base = bare_type(type_name)
    suffix = type_name[len(base):]
    if not suffix:
        return base, False, None
    if suffix == "[]":
        return base, True, None
    m = re.fullmatch(r"\[([0-9]+)\]", suffix)
    if m is None:
        return None
    return base, True, int(m.group(1))


def _parse_field(orig: str, clean: str, package: str, lineno: int,
                 source: str | None) -> Field:
    words = _split_words(clean)
    if len(words) != 2:
        hint = " (genmsg separates type and name with spaces, not tabs)" if "\t" in clean else ""
        raise MsgDefinitionError(f"expected 'TYPE NAME', found {len(words)} word(s){hint}",
                                 source, lineno, orig)
    type_name, name = words
    if not is_legal_base_name(name):
        raise MsgDefinitionError(
            f"{name!r} is not a legal field name (a letter, then letters, digits or '_')",
            source, lineno, orig)
    base = bare_type(type_name)
    parts = base.split(SEP)
    if len(parts) > 2 or not all(map(is_legal_base_name, parts)):
        raise MsgDefinitionError(f"{type_name!r} is not a legal field type", source, lineno, orig)
    if type_name.count("[") > 1:
        raise MsgDefinitionError(f"{type_name!r}: only one-dimensional arrays are supported",
                                 source, lineno, orig)
    parsed = _parse_array_suffix(type_name)
    if parsed is None:
        raise MsgDefinitionError(f"{type_name!r} has a malformed array suffix (use T[] or T[N])",
                                 source, lineno, orig)
    base, is_array, length = parsed
    if SEP not in type_name:
        if type_name == HEADER:
            type_name, base = HEADER_FULL_NAME, HEADER_FULL_NAME
        elif base not in BUILTIN_TYPES:
            type_name = f"{package}{SEP}{type_name}"
            base = f"{package}{SEP}{base}"
    return Field(name, type_name, base, is_array, length, lineno)


def parse_msg(text: str, full_name: str, source: str | None = None) -> MsgSpec:
    """Parse ``.msg`` text.

    Args:
        text: the definition, exactly as in the file.
        full_name: ``pkg/Name`` of the type; field types without a package resolve in ``pkg``.
        source: file path or label used in error messages.

    Returns:
        The parsed specification (its ``text`` is ``text`` unchanged).

    Raises:
        MsgDefinitionError: malformed name, line or duplicate field (names source and line).
    """
    try:
        package, short = split_full_name(full_name)
    except ValueError as exc:
        raise MsgDefinitionError(str(exc), source) from None
    fields: list[Field] = []
    constants: list[Constant] = []
    seen: dict[str, int] = {}
    for lineno, orig in enumerate(text.split("\n"), start=1):
        clean = _strip_line(orig)
        if not clean:
            continue
        item: Field | Constant
        if CONST_CHAR in clean:
            constant = _parse_constant(orig, clean, lineno, source)
            constants.append(constant)
            item = constant
        else:
            field = _parse_field(orig, clean, package, lineno, source)
            fields.append(field)
            item = field
        if item.name in seen:
            raise MsgDefinitionError(
                f"duplicate name {item.name!r} (first declared on line {seen[item.name]})",
                source, lineno, orig)
        seen[item.name] = lineno
    return MsgSpec(full_name, package, short, tuple(fields), tuple(constants), text, source)


def strip_comments(text: str) -> str:
    """The comment-free form of a definition, as the lab ships std/sensor/geometry msgs.

    Rule, per line of ``text.split('\\n')``: a ``string`` constant line is kept whole (its
    ``#`` belongs to the value); on any other line everything from the first ``#`` is removed.
    Then trailing whitespace is removed, and lines left empty are dropped. The kept lines are
    joined with ``\\n`` and end with ``\\n`` (an empty definition stays ``''``). Leading and
    inner whitespace is kept, so the result parses to the same fields, constants and md5.

    Args:
        text: definition text with comments.

    Returns:
        The stripped text.
    """
    kept = []
    for line in text.split("\n"):
        clean = _strip_line(line)
        if not clean:
            continue
        if CONST_CHAR in clean and _split_words(clean)[0] == "string":
            kept.append(line.rstrip())
        else:
            kept.append(line.split(COMMENT_CHAR)[0].rstrip())
    return "".join(line + "\n" for line in kept)


def split_full_text(full_text: str) -> list[tuple[str | None, str]]:
    """Split a full text (``message_definition``) into ``(type or None, text)`` sections.

    The first section is the top-level type (its name is not in the text, so ``None``); the
    others come from the ``MSG: pkg/Type`` lines after each 80-``=`` separator.

    Args:
        full_text: as built by genmsg's compute_full_text.

    Returns:
        List of (type name or None, definition text).

    Raises:
        MsgDefinitionError: a section after a separator lacks its ``MSG:`` line.
    """
    sep = "\n" + "=" * 80 + "\n"
    parts = full_text.split(sep)
    out: list[tuple[str | None, str]] = [(None, parts[0])]
    for i, part in enumerate(parts[1:], start=1):
        head, _nl, body = part.partition("\n")
        if not head.startswith("MSG: "):
            raise MsgDefinitionError(f"section {i} of the full text does not start with 'MSG: '",
                                     "<full text>")
        out.append((head[5:].strip(), body))
    return out
