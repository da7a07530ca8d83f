"""Notebook widgets: byte viewer, image diff, beat viewer, waveforms, sequence diagram, live view, progress.

Every widget is constructible without a running kernel or front end (so plain pytest can test
its logic), and each has a static HTML form (``to_html()``) that needs no JavaScript, for
exported notebooks and GitHub's notebook view: the widgets put it in their output beside the
live view (as ``text/html``), ``show_static(w)`` displays it alone, and exporting an executed
notebook with ``NbConvertBase.display_data_priority = STATIC_EXPORT_PRIORITY`` picks it. Quick
reference::

    from rosfpga_lab import widgets as W
    W.ByteViewer(raw, spans)                          # any bytes + [(offset, size, path, type, value, role)]
    W.message_viewer("sensor_msgs/Image", body)       # fields from rosfpga_lab.msg.field_layout
    W.ByteViewer(hdr, W.spans_from_connection_header(hdr))   # TCPROS connection header
    W.ByteViewer(req, W.spans_from_http(req))         # HTTP / XML-RPC request or response
    W.view_bytes(raw, "tcpros_frame", "sensor_msgs/Image")   # fields chosen by kind
    W.ImageDiffViewer(output, reference, input)       # or frames=[(input, output, reference), ...]
    W.BeatViewer(beats, width=w, height=h, bytes_per_pixel=4)  # hw Beats (tdata/tkeep/tuser/tlast)
    W.SequenceDiagram(trace)                          # graph Trace or [SeqEvent(src, dst, label, raw, t, kind)]
    W.SequenceDiagram("data/ros1_image.pcapng")       # a capture of real ROS 1 traffic
    W.capture_viewer("data/ros1_image.pcapng", 0, kind="tcpros_frame")   # one step's bytes
    W.WaveformViewer(W.Waves.from_vcd("dump.vcd"), width=640)   # per-clock signals; or Waves.from_arrays({...})
    W.cdr_viewer("sensor_msgs/Image", payload)        # ROS 2 CDR, alignment padding in red
    W.SequenceDiagram(W.events_from_rtps("data/rtps_image.pcapng"))   # RTPS (DDS) traffic
    live = W.LiveView(max_fps=10); live.update(frame, stamp=t)   # from any thread
    with W.Progress(total, "dilate") as p: p.update()  # or W.track(iterable, desc=...)

What each widget shows and how it stays fast (paged bytes, windowed waveforms) is its module's
docstring. Notebooks as offline pages: ``rosfpga-lab notebooks html`` (``rosfpga_lab.cli.notebooks``).
"""

from rosfpga_lab.widgets._common import STATIC_EXPORT_PRIORITY, WidgetError, show_static
from rosfpga_lab.widgets.beats import BeatMap, BeatViewer, MarkerMismatch
from rosfpga_lab.widgets.byte_sources import (
    message_spans,
    message_viewer,
    spans_for,
    spans_from_connection_header,
    spans_from_field_layout,
    spans_from_frame,
    spans_from_http,
    spans_from_layout,
    spans_from_tcpros_stream,
    view_bytes,
)
from rosfpga_lab.widgets.byteview import ByteMap, ByteViewer, Span, as_span
from rosfpga_lab.widgets.imagediff import FrameDiff, ImageDiffViewer
from rosfpga_lab.widgets.live import LiveView, RateMeter, Throttle
from rosfpga_lab.widgets.progress import Progress, in_notebook, track
from rosfpga_lab.widgets.waveform import Marker, Signal, WaveformViewer, Waves
from rosfpga_lab.widgets.wire import (
    capture_viewer, cdr_spans, cdr_viewer, events_from_recording, events_from_rtps, rtps_spans,
)
from rosfpga_lab.widgets.sequence import (
    SeqEvent,
    SequenceDiagram,
    SvgPane,
    events_from_capture,
    events_from_trace,
    participants_of,
    sequence_html,
    sequence_svg,
)
from rosfpga_lab.widgets.code import CodeFiles, code_html
from rosfpga_lab.widgets.statemachine import StateDiagram, layout_transitions, state_diagram_svg

__all__ = [
    "STATIC_EXPORT_PRIORITY", "show_static",
    "BeatMap", "BeatViewer", "ByteMap", "CodeFiles", "code_html", "ByteViewer", "FrameDiff", "ImageDiffViewer", "LiveView",
    "MarkerMismatch", "Progress", "RateMeter", "SeqEvent", "SequenceDiagram", "Span", "StateDiagram",
    "SvgPane", "layout_transitions", "state_diagram_svg",
    "Throttle", "WidgetError", "as_span", "events_from_capture", "events_from_trace", "in_notebook", "message_spans",
    "message_viewer", "participants_of", "sequence_html", "sequence_svg", "spans_for",
    "spans_from_connection_header", "spans_from_field_layout", "spans_from_frame",
    "spans_from_http", "spans_from_layout", "spans_from_tcpros_stream", "track", "view_bytes",
    "Marker", "Signal", "WaveformViewer", "Waves",
    "capture_viewer", "cdr_spans", "cdr_viewer", "events_from_recording", "events_from_rtps",
    "rtps_spans",
]
