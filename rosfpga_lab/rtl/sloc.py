"""The Verilog column of the paper's Table 1: lines of the RTL subscriber and publisher.

The rule is the C++ one (:func:`rosfpga_lab.hls.sloc.sloc`: no comment, no blank line), without
character literals. The files counted mirror the HLS side: the generated ``subscriber.cpp``
holds the frame reader and ``fifo2axi``, ``publisher.cpp`` the frame writer and ``axi2fifo``,
so the hand-written Verilog (the exhibit, ``exhibit/``: the conventional design of Table 1) is
counted as ``rfl_subscriber.v`` + ``rfl_fifo2axi.v`` and ``rfl_publisher.v`` + ``rfl_axi2fifo.v``
(:data:`COUNTED`). A generated project of any message type counts its walkers, the generated
walk and the element packer/unpacker (:data:`GENERIC_COUNTED`). Counting is the one thing of the
library that reads the exhibit's files.
"""

from __future__ import annotations

from pathlib import Path

from rosfpga_lab.hls.sloc import SlocTable, count_files, sloc
from rosfpga_lab.rtl.errors import RtlError

#: The exhibit's folder (the hand-written Image circuit); its shared modules are ``verilog/``'s.
EXHIBIT_DIR = Path(__file__).resolve().parent / "exhibit"
#: What a count of the default folder is, in words (``rosfpga-lab sloc`` without a project's RTL).
DEFAULT_SOURCE = "the lab's exhibit, rosfpga_lab/rtl/exhibit"

#: The exhibit's Verilog files counted as the subscriber and the publisher (Table 1).
COUNTED = {"subscriber": ("rfl_subscriber.v", "rfl_fifo2axi.v"),
           "publisher": ("rfl_publisher.v", "rfl_axi2fifo.v")}
#: Other Verilog files of the exhibit, listed beside the table (not in the paper's count).
OTHERS = ("rfl_top.v",)
#: The same for a generated project of any other message type (:mod:`rosfpga_lab.rtl.generic`):
#: the walkers, the generated walk they both step through counted with the subscriber (it is
#: the per-message part), and the element packer/unpacker as fifo2axi/axi2fifo.
GENERIC_COUNTED = {"subscriber": ("rfl_gsubscriber.v", "rfl_layout.vh", "rfl_elem_pack.v"),
                   "publisher": ("rfl_gpublisher.v", "rfl_elem_unpack.v")}
GENERIC_OTHERS = ("rfl_window1d.v", "rfl_morph.v", "rfl_fifo.v", "rfl_slice.v", "rfl_gtop.v",
                  "rfl_node.v")


def verilog_sloc(text: str) -> int:
    """Non-comment, non-blank lines of Verilog source text."""
    return sloc(text, char_literals=False)


def count_verilog(directory: str | Path | None = None) -> SlocTable:
    """Count the Verilog subscriber and publisher in ``directory`` (default: the exhibit's).

    Args:
        directory: a generated project's ``rtl/`` folder, or None for the exhibit, the
            hand-written Image circuit (``exhibit/``).

    Raises:
        RtlError: a counted file is missing.
    """
    root = Path(directory) if directory is not None else EXHIBIT_DIR
    generic = (root / GENERIC_COUNTED["subscriber"][0]).is_file()
    return count_files(root, GENERIC_COUNTED if generic else COUNTED,
                       GENERIC_OTHERS if generic else OTHERS, verilog_sloc, lambda path: RtlError(
        f"{path} not found: is {root} the rtl/ folder of a generated project?"))
