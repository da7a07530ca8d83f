"""Source lines as the paper's Table 1 counts them: non-comment, non-blank lines.

How this works: a small scanner walks the C/C++ text once, dropping ``//`` and ``/* */``
comments (but not comment markers inside string or character literals); a line counts when
anything but white space is left. Preprocessor lines (``#include``, ``#pragma HLS``) count: they
are code an HLS designer writes. Verilog has the same comments and string literals, so the same
rule counts the RTL (:mod:`rosfpga_lab.rtl.sloc`), with one difference: ``'`` starts no
character literal there (it is part of sized numbers such as ``8'hFF``).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

from rosfpga_lab.hls.errors import HlsError

#: The paper's Table 1: lines of the subscriber and publisher, HLS C/C++ and hand-written Verilog.
PAPER_TABLE1 = {"subscriber": (57, 415), "publisher": (70, 445), "total": (127, 860)}
#: Generated files counted as the subscriber and the publisher: the walkers, and the walk they
#: both step through (``layout.h``, the per-message part), counted with the subscriber (as
#: ``rfl_layout.vh`` is on the Verilog side, :mod:`rosfpga_lab.rtl.sloc`).
COUNTED = {"subscriber": ("subscriber.cpp", "layout.h"), "publisher": ("publisher.cpp",)}
#: Other generated C/C++ files, listed beside the table (not in the paper's count).
OTHERS = ("connection_headers.cpp", "ros_node.h", "stream_filter.cpp", "ros_fpga_node.cpp",
          "csim_testbench.cpp")


def sloc(text: str, char_literals: bool = True) -> int:
    """Count the non-comment, non-blank lines of C/C++ (or Verilog) source text.

    Args:
        char_literals: ``'`` opens a character literal (C/C++); False for Verilog.
    """
    quotes = "\"'" if char_literals else "\""
    count = 0
    in_block = False
    for line in text.splitlines():
        code = []
        i, n = 0, len(line)
        quote = ""
        while i < n:
            c = line[i]
            if in_block:
                if line.startswith("*/", i):
                    in_block = False
                    i += 2
                else:
                    i += 1
                continue
            if quote:
                code.append(c)
                if c == "\\" and i + 1 < n:
                    code.append(line[i + 1])
                    i += 2
                    continue
                if c == quote:
                    quote = ""
                i += 1
                continue
            if line.startswith("//", i):
                break
            if line.startswith("/*", i):
                in_block = True
                i += 2
                continue
            if c in quotes:
                quote = c
            code.append(c)
            i += 1
        if "".join(code).strip():
            count += 1
    return count


@dataclass(frozen=True)
class SlocTable:
    """Line counts of one generated project.

    Attributes:
        subscriber, publisher: lines of the counted files.
        others: ``{file: lines}`` for the other generated C/C++ files present.
    """

    subscriber: int
    publisher: int
    others: dict[str, int]

    @property
    def total(self) -> int:
        return self.subscriber + self.publisher


def count_files(root: Path, counted: Mapping[str, Sequence[str]], others: Sequence[str],
                count: Callable[[str], int], missing: Callable[[Path], Exception]) -> SlocTable:
    """Table 1's counts of one folder: the ``counted`` files of the subscriber and the publisher
    (each must exist, else ``missing(path)`` is raised) and those of ``others`` that are there,
    each file counted with ``count`` (the C++ rule, or the Verilog one)."""
    counts = {}
    for part, files in counted.items():
        total = 0
        for name in files:
            path = root / name
            if not path.is_file():
                raise missing(path)
            total += count(path.read_text(encoding="utf-8"))
        counts[part] = total
    present = {name: count((root / name).read_text(encoding="utf-8"))
               for name in others if (root / name).is_file()}
    return SlocTable(counts["subscriber"], counts["publisher"], present)


def count_sloc(project_dir: str | Path) -> SlocTable:
    """Count the lines of a generated project.

    Raises:
        HlsError: the directory lacks a counted file (subscriber.cpp, layout.h, publisher.cpp).
    """
    root = Path(project_dir)
    return count_files(root, COUNTED, OTHERS, sloc, lambda path: HlsError(
        f"{path} not found: is {root} a directory written by 'rosfpga-lab generate'?"))


def format_table(table: SlocTable, title: str = "", verilog: SlocTable | None = None) -> str:
    """The table beside the paper's figures, as text.

    Args:
        verilog: the lab's Verilog of the same subscriber and publisher
            (:func:`rosfpga_lab.rtl.sloc.count_verilog`), shown as a second column.
    """
    rows = ["subscriber", "publisher", "total"]
    head = f"{'':<12}{'generated HLS C++':>18}"
    if verilog is not None:
        head += f"{'lab Verilog':>13}"
    head += f"{'paper HLS C/C++':>17}{'paper Verilog':>15}"
    lines = [title] if title else []
    lines += [head, "-" * len(head)]
    for name in rows:
        hls, paper_verilog = PAPER_TABLE1[name]
        line = f"{name:<12}{getattr(table, name):>18}"
        if verilog is not None:
            line += f"{getattr(verilog, name):>13}"
        lines.append(line + f"{hls:>17}{paper_verilog:>15}")
    for label, counts in (("C/C++", table), ("Verilog", verilog)):
        if counts is not None and counts.others:
            lines.append("")
            lines.append(f"{label} not in the paper's count (non-comment, non-blank lines):")
            for name, n in counts.others.items():
                lines.append(f"  {name:<24}{n:>6}")
    return "\n".join(lines)
