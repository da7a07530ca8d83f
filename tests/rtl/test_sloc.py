"""Table 1's Verilog column: the C++ rule applied to the RTL (``'`` opens no literal there)."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

from rosfpga_lab.hls.sloc import PAPER_TABLE1, SlocTable, format_table, sloc
from rosfpga_lab.rtl.sloc import COUNTED, EXHIBIT_DIR, count_verilog, verilog_sloc


def _plain_count(text: str) -> int:
    """An independent count for files without comment markers inside strings."""
    assert not re.search(r'"[^"\n]*(//|/\*)[^"\n]*"', text)
    text = re.sub(r"/\*.*?\*/", lambda m: "\n" * m.group(0).count("\n"), text, flags=re.S)
    text = re.sub(r"//[^\n]*", "", text)
    return sum(1 for line in text.splitlines() if line.strip())


def test_verilog_rule() -> None:
    text = (
        "// rfl_x -- a module\n"
        "module rfl_x (input a, output [7:0] q);  // ports\n"
        "\n"
        "    assign q = a ? 8'hFF : 0; /* a comment that\n"
        "       goes on */\n"
        "    /* only a comment */\n"
        "    localparam [8*5-1:0] S = \"a//b\";\n"
        "endmodule\n"
    )
    assert verilog_sloc(text) == 4
    assert sloc(text) == 5           # the C rule reads 8'hFF ... as a character literal


def test_the_exhibits_verilog_is_counted_file_by_file() -> None:
    """The default count is the exhibit's (the hand-written Image circuit, Table 1)."""
    table = count_verilog()
    for part, files in COUNTED.items():
        want = sum(_plain_count((EXHIBIT_DIR / f).read_text()) for f in files)
        assert getattr(table, part) == want > 50, part
    assert table.total == table.subscriber + table.publisher
    assert "rfl_top.v" in table.others and table.others["rfl_top.v"] == \
        _plain_count((EXHIBIT_DIR / "rfl_top.v").read_text())


def test_table_has_both_columns() -> None:
    text = format_table(SlocTable(60, 70, {}), verilog=SlocTable(400, 300, {"rfl_morph.v": 150}))
    rows = {line.split()[0]: line.split()[1:] for line in text.splitlines()[2:5]}
    assert rows["subscriber"] == ["60", "400", "57", "415"]
    assert rows["publisher"] == ["70", "300", "70", "445"]
    assert rows["total"] == ["130", "700", "127", "860"]
    assert PAPER_TABLE1["total"] == (127, 860)
    assert "rfl_morph.v" in text and "lab Verilog" in text.splitlines()[0]


def test_cli_without_rtl_counts_the_lab_verilog(tmp_path: Path) -> None:
    for name in ("subscriber.cpp", "layout.h", "publisher.cpp"):
        (tmp_path / name).write_text("int x;\n// c\nint y;\n")
    done = subprocess.run([sys.executable, "-m", "rosfpga_lab", "sloc", str(tmp_path)],
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    verilog = count_verilog()
    row = next(line.split() for line in done.stdout.splitlines() if line.startswith("total"))
    assert row == ["total", "6", str(verilog.total), "127", "860"]
    assert "the lab's exhibit, rosfpga_lab/rtl/exhibit" in done.stdout
