"""Verilog of generated projects for any message layout (work in progress: the element stream).

How this works: the modules of ``generic/`` are parameterized for any streamed array of
numbers: :file:`rfl_elem_pack.v` turns the array's bytes into AXI4-Stream beats of one element,
:file:`rfl_window1d.v` is the 1-D application (sliding max/min, pass-through) and
:file:`rfl_elem_unpack.v` turns beats back into bytes.
"""

from __future__ import annotations

from pathlib import Path

GENERIC_VERILOG_DIR = Path(__file__).resolve().parent / "generic"
#: ``rfl_window1d``'s OP parameter per operation.
OP_CODES_1D = {"dilate": 0, "erode": 1, "passthrough": 2}
#: ``rfl_window1d``'s KIND parameter per element kind (how elements are ordered).
KIND_CODES = {"unsigned": 0, "signed": 1, "float": 2}
