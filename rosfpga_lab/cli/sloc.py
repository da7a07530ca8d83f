"""``rosfpga-lab sloc DIR``: the paper's Table 1 for a generated project, HLS C++ and Verilog."""

from __future__ import annotations

import argparse
from pathlib import Path


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add the ``sloc`` sub-command."""
    parser = subparsers.add_parser(
        "sloc",
        help="count source lines of the generated HLS C++ and of the Verilog beside the "
        "paper's Table 1",
        description="Count the non-comment, non-blank lines of the subscriber and publisher in a "
        "directory written by 'rosfpga-lab generate': the HLS C++ and the Verilog of the same "
        "circuit (DIR/rtl/, else the lab's own Verilog), and print them beside the paper's "
        "Table 1 (57 + 70 = 127 lines of HLS C/C++ against 415 + 445 = 860 lines of Verilog).",
    )
    parser.add_argument("directory", type=Path, metavar="DIR", help="a generated project directory")
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Print the table."""
    from rosfpga_lab.hls import count_sloc, format_table
    from rosfpga_lab.rtl.sloc import DEFAULT_SOURCE, count_verilog

    hls = count_sloc(args.directory)
    rtl_dir = args.directory / "rtl"
    if rtl_dir.is_dir():
        verilog, source = count_verilog(rtl_dir), str(rtl_dir)
    else:
        verilog, source = count_verilog(), DEFAULT_SOURCE
    print(format_table(hls, title=f"Source lines of {args.directory} (Verilog: {source})",
                       verilog=verilog))
    return 0
