"""Limits and defaults of the component layer, in one place."""

from __future__ import annotations

#: Frames queued in front of the circuit (the subscriber's queue): when the circuit is busy and
#: the queue is full, the oldest waiting frame is dropped and counted ("input queue full").
#: One frame waiting while one is processed matches a double-buffered input.
DEFAULT_INPUT_QUEUE = 2
#: Frames queued per downstream subscriber before the oldest is dropped ("output queue full").
DEFAULT_OUTPUT_QUEUE = 2
#: Recent frames kept for a live view (:attr:`FpgaComponent.recent`).
DEFAULT_HISTORY = 4
#: Latency samples kept for medians and percentiles.
LATENCY_WINDOW = 1000
#: A frame's header.stamp within this many seconds before its publication counts as a camera's
#: wall-clock capture time (for "latency since stamp"); other stamps are left out of that figure.
STAMP_PLAUSIBLE = 60.0
#: Seconds between checks that the master still knows the component (re-registers after a
#: master restart).
WATCHDOG_PERIOD = 1.0
#: Refusal log lines per reason before the log is thinned to one line per LOG_EVERY refusals.
LOG_FIRST = 3
LOG_EVERY = 100
#: The reference model moves one byte per Python step: warn above this many pixels per frame.
REFERENCE_WARN_PIXELS = 160 * 120
#: Frames per second figures (status lines, the viewer): arrivals of the last FPS_WINDOW seconds
#: (at most FPS_SAMPLES of them); 0 once no frame came for FPS_STALE seconds.
FPS_WINDOW = 2.0
FPS_STALE = 1.0
FPS_SAMPLES = 256
#: Input frames a checker remembers for matching (older ones are forgotten), and latency
#: samples it keeps.
CHECKER_PENDING = 512
CHECKER_LATENCY_WINDOW = 100_000
#: Distinct frames an image source makes before it repeats.
DEFAULT_SOURCE_PERIOD = 60
#: Refusal kinds counted separately (kinds are field + rule, a few dozen at most; any beyond
#: this count under "other").
MAX_REFUSAL_KINDS = 64
#: Frame shapes (the counts of a frame's strings and arrays) whose clocks ``--timing fpga``
#: keeps: a camera sends one shape, so the generated walk is timed once, not per frame.
MAX_TIMED_SHAPES = 64
#: Camera limits: frames per second and image side.
MAX_CAMERA_RATE = 1000.0
MAX_CAMERA_SIDE = 8192
#: Bytes of decoded frames a bag source (``camera --source x.bag``) holds in memory.
MAX_BAG_SOURCE_BYTES = 512 * 1024 * 1024

#: Pictures wider than this are shrunk before encoding (pixels).
PAGE_IMAGE_MAX_WIDTH = 640
#: Seconds between the ``node`` command's looks at its stop flag (how soon SIGTERM is obeyed).
SIGNAL_POLL = 0.05
#: Seconds between the ``node`` command's tries to reach a master that does not answer yet
#: (rospy and roscpp nodes wait for it too: a launch order race is normal).
MASTER_RETRY = 0.5
#: Seconds a component that was shut down from outside while starting waits for that shutdown to
#: finish unregistering (it runs in the slave API's thread) before it reports it.
SHUTDOWN_WAIT = 5.0
