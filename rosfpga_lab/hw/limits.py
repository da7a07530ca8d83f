"""The hardware-model layer's limits and defaults, in one place.

The image-size, kernel and ``frame_id`` limits are the node configuration's
(:mod:`rosfpga_lab.config.limits`); the rest belong to the models.
"""

from __future__ import annotations

from rosfpga_lab.config import limits as _config
from rosfpga_lab.tcpros import MAX_FRAME_BYTES as _tcpros_max_frame_bytes

#: Largest ``width`` / ``height`` of an Image circuit (an "absurd" value is larger).
MAX_WIDTH = _config.MAX_WIDTH
MAX_HEIGHT = _config.MAX_HEIGHT
#: Longest ``encoding`` string an Image circuit stores.
MAX_ENCODING_BYTES = _config.IMAGE_MAX_ENCODING_BYTES
#: Largest TCPROS frame (4-byte length excluded) a subscriber accepts: the TCPROS layer's.
MAX_FRAME_BYTES = _tcpros_max_frame_bytes
#: Width of the AXI4-Stream data bus between fifo2axi and the application, in bits.
TDATA_BITS = 32
#: Largest rectangular kernel of the dilate/erode application.
MAX_KSIZE = _config.MAX_KSIZE

#: Defaults of the circuit models (:class:`rosfpga_lab.hw.MessagePipeline`).
DEFAULT_CLOCK_HZ = _config.DEFAULT_CLOCK_MHZ * 1e6
DEFAULT_LINE_RATE_BPS = 1e9

#: What a TCP byte stream costs on (gigabit) Ethernet, for ``MessageResult.wire_time_s`` (``hw.msgpipeline.wire_bytes``):
#: IPv4 (20) + TCP (20) headers plus the 12-byte timestamp option Linux sends, inside a
#: 1,500-byte MTU, and per Ethernet frame the preamble and start delimiter (8), MAC header
#: (14), FCS (4) and the inter-frame gap (12).
ETHERNET_MTU = 1500
TCP_IP_HEADER_BYTES = 20 + 20 + 12
ETHERNET_FRAMING_BYTES = 8 + 14 + 4 + 12
