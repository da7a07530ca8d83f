"""Limits and defaults of the HLS layer, in one place.

The image limits follow what the circuit (and its Python models in ``rosfpga_lab.hw``) accept;
the FIFO defaults are those of the paper's block design.
"""

from __future__ import annotations

from rosfpga_lab.hw import limits as hw_limits

#: Image sizes the templates can serve (the interpreter refuses larger).
MIN_WIDTH = 1
MIN_HEIGHT = 1
MAX_WIDTH = hw_limits.MAX_WIDTH
MAX_HEIGHT = hw_limits.MAX_HEIGHT
#: Odd kernel sizes from 1 to this for dilate/erode.
MAX_KSIZE = hw_limits.MAX_KSIZE
#: Longest header.frame_id the generated subscriber stores and the publisher re-sends.
DEFAULT_FRAME_ID_MAX = hw_limits.MAX_FRAME_ID_BYTES
MAX_FRAME_ID_MAX = hw_limits.MAX_FRAME_ID_BYTES
#: FIFO depths (items) and their bounds.
DEFAULT_INPUT_FIFO_DEPTH = 2048
DEFAULT_OUTPUT_FIFO_DEPTH = 2048
DEFAULT_AXIS_FIFO_DEPTH = 16
MAX_FIFO_DEPTH = 1 << 20
#: Clock of the circuit (MHz) and its bounds.
DEFAULT_CLOCK_MHZ = 100.0
MIN_CLOCK_MHZ = 1.0
MAX_CLOCK_MHZ = 1000.0
#: Node defaults (safe: loopback unless the configuration says otherwise).
DEFAULT_MASTER_URI = "http://127.0.0.1:11311/"
DEFAULT_IP_ADDRESS = "127.0.0.1"
#: The only message type the templates can stream through the circuit.
IMAGE_TYPE = "sensor_msgs/Image"
#: Largest configuration file read (bytes).
MAX_CONFIG_BYTES = 1 << 20
#: FPGA part of the HLS project script (the Zynq-7020 of the paper's class of boards).
DEFAULT_PART = "xc7z020clg400-1"
