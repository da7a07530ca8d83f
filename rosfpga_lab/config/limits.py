"""Limits and defaults of a node configuration, in one place.

They bound what the circuit accepts: the hardware models (:mod:`rosfpga_lab.hw.limits`), the
generated HLS C++ and the RTL derive their limits from these. The FIFO defaults are those of the
paper's block design.
"""

from __future__ import annotations

#: Image sizes the circuit can serve (the interpreter refuses larger).
MIN_WIDTH = 1
MIN_HEIGHT = 1
MAX_WIDTH = 8192
MAX_HEIGHT = 8192
#: Odd kernel sizes from 1 to this for dilate/erode.
MAX_KSIZE = 15
#: Longest header.frame_id the circuit stores and the publisher re-sends.
MAX_FRAME_ID_MAX = 256
DEFAULT_FRAME_ID_MAX = MAX_FRAME_ID_MAX
#: Maxima of the variable-length parts of a message other than the stream, when a configuration's
#: ``limits:`` leaves them out: bytes of a string, elements of a variable-length array (a longer
#: one is refused). ``header.frame_id`` keeps ``frame_id_max``.
DEFAULT_STRING_MAX = 256
DEFAULT_ARRAY_MAX = 64
#: Largest value a ``limits:`` entry may give (bytes of a string, elements of an array).
MAX_LIMIT = 1 << 20
#: Most elements of the streamed array (``stream.length``).
MAX_STREAM_LENGTH = 1 << 24
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
#: roscore's port, and the URI of a master on it (the one literal of the default master).
DEFAULT_MASTER_PORT = 11311
DEFAULT_MASTER_URI = f"http://127.0.0.1:{DEFAULT_MASTER_PORT}/"
DEFAULT_IP_ADDRESS = "127.0.0.1"
#: The message type with a video stream (``image:`` gives its geometry), the default type.
IMAGE_TYPE = "sensor_msgs/Image"
#: Its streamed array, and the fields ``image:`` implies a check on (equal to the geometry).
IMAGE_STREAM_FIELD = "data"
IMAGE_IMPLIED_CHECKS = ("height", "width", "encoding", "step")
#: Longest ``encoding`` string an Image circuit stores.
IMAGE_MAX_ENCODING_BYTES = 32
#: Largest configuration file read (bytes).
MAX_CONFIG_BYTES = 1 << 20
#: FPGA part of the HLS project script (the Zynq-7020 of the paper's class of boards).
DEFAULT_PART = "xc7z020clg400-1"
#: Messages ``rosfpga-lab topic echo`` queues while printing falls behind (older ones are
#: dropped and counted); ``--queue-size`` changes it.
ECHO_QUEUE = 100
