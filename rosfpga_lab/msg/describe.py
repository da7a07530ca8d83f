"""Human-readable views of message types and layouts (used by ``rosfpga-lab msg`` and notebooks)."""

from __future__ import annotations

from rosfpga_lab.msg.layout import FieldSpan
from rosfpga_lab.msg.registry import MsgRegistry


def show_fields(reg: MsgRegistry, type_name: str, indent: str = "  ") -> str:
    """The definition as ``rosmsg show`` prints it: constants, then fields, nested types indented.

    Args:
        reg: the registry holding the type.
        type_name: e.g. ``sensor_msgs/Image``.
        indent: indentation per nesting level.

    Returns:
        The text, one line per constant or field, ending with a newline.

    Raises:
        UnknownTypeError: the type (or a nested one) is not registered.
    """
    lines: list[str] = []

    def walk(name: str, depth: int) -> None:
        spec = reg.check(name)
        pad = indent * depth
        for c in spec.constants:
            lines.append(f"{pad}{c.type} {c.name}={c.value_text}")
        for f in spec.fields:
            lines.append(f"{pad}{f.type} {f.name}")
            if not f.is_builtin:
                walk(f.base_type, depth + 1)

    walk(type_name, 0)
    return "".join(line + "\n" for line in lines)


def show(reg: MsgRegistry, type_name: str, full_text: bool = True) -> str:
    """``show_fields`` plus the md5 sum and (optionally) the full text, for ``msg show``."""
    spec = reg.check(type_name)
    out = [f"# {spec.full_name}", f"# md5: {reg.md5(spec.full_name)}"]
    if spec.source:
        out.append(f"# from: {spec.source}")
    text = "\n".join(out) + "\n" + show_fields(reg, spec.full_name)
    if full_text:
        text += ("\n# full text (the message_definition a TCPROS connection header carries):\n"
                 + reg.full_text(spec.full_name) + ("" if reg.full_text(spec.full_name)
                                                    .endswith("\n") else "\n"))
    return text


def _short(value: object, width: int = 40) -> str:
    text = repr(value)
    if hasattr(value, "tobytes") and hasattr(value, "dtype"):
        arr = value  # numpy array
        text = f"<{arr.dtype} x {arr.size}>"  # type: ignore[attr-defined]
    return text if len(text) <= width else text[:width - 3] + "..."


def layout_table(spans: list[FieldSpan]) -> str:
    """A fixed-width table of spans: offset, size, role, type, path, value."""
    rows = [("offset", "size", "role", "type", "path", "value")]
    rows += [(str(s.offset), str(s.size), s.role, s.type, s.path or "-", _short(s.value))
             for s in spans]
    widths = [max(len(r[i]) for r in rows) for i in range(5)]
    out = []
    for r in rows:
        cells = [r[0].rjust(widths[0]), r[1].rjust(widths[1])] + \
            [r[i].ljust(widths[i]) for i in (2, 3, 4)] + [r[5]]
        out.append("  ".join(cells).rstrip())
    return "\n".join(out) + "\n"
