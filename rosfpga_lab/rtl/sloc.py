"""The Verilog column of the paper's Table 1: lines of the lab's RTL subscriber and publisher.

The rule is the C++ one (:func:`rosfpga_lab.hls.sloc.sloc`: no comment, no blank line), without
character literals. The files counted mirror the HLS side: the generated ``subscriber.cpp``
holds the frame reader and ``fifo2axi``, ``publisher.cpp`` the frame writer and ``axi2fifo``,
so the Verilog subscriber is ``rfl_subscriber.v`` + ``rfl_fifo2axi.v`` and the publisher
``rfl_publisher.v`` + ``rfl_axi2fifo.v``. A generated project of another message type counts
its walkers, the generated walk and the element packer/unpacker (:data:`GENERIC_COUNTED`).
"""

from __future__ import annotations

from pathlib import Path

from rosfpga_lab.hls.sloc import SlocTable, count_files, sloc
from rosfpga_lab.rtl.errors import RtlError
from rosfpga_lab.rtl.sim import VERILOG_DIR

#: Verilog files counted as the subscriber and the publisher (Table 1).
COUNTED = {"subscriber": ("rfl_subscriber.v", "rfl_fifo2axi.v"),
           "publisher": ("rfl_publisher.v", "rfl_axi2fifo.v")}
#: Other Verilog files, listed beside the table (not in the paper's count).
OTHERS = ("rfl_morph.v", "rfl_fifo.v", "rfl_top.v", "rfl_node.v")
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
    """Count the Verilog subscriber and publisher in ``directory`` (default: the lab's own).

    Args:
        directory: a generated project's ``rtl/`` folder, or None for the package's
            ``verilog/``.

    Raises:
        RtlError: a counted file is missing.
    """
    root = Path(directory) if directory is not None else VERILOG_DIR
    generic = (root / GENERIC_COUNTED["subscriber"][0]).is_file()
    return count_files(root, GENERIC_COUNTED if generic else COUNTED,
                       GENERIC_OTHERS if generic else OTHERS, verilog_sloc, lambda path: RtlError(
        f"{path} not found: is {root} the rtl/ folder of a generated project?"))
