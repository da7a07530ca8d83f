"""Views of ROS 2 on the wire: CDR payloads in the byte viewer, RTPS traffic as a sequence diagram.

How this works: :func:`cdr_viewer` is ``message_viewer`` for CDR (fields from
``rosfpga_lab.msg.cdr_layout``; the alignment padding in a colour of its own, the encapsulation
header named). :func:`events_from_rtps` turns the datagrams of a capture into sequence-diagram
events: one arrow per RTPS message from the sending participant to the one its INFO_DST names
(or to ``peers`` when none), labelled with its submessages; SEDP announcements name their topic.
A message sent again unchanged (SPDP goes to every peer port) and the DATA_FRAGs of a sample
after its first message are folded into one "... N more" arrow at the end.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from rosfpga_lab.msg import cdr_layout
from rosfpga_lab.rtps import (
    ANY_PARTICIPANT, Data, DataFrag, InfoDst, InfoSrc, RtpsError, parse_message, parse_parameters,
)
from rosfpga_lab.rtps.discovery import (
    PID_TOPIC_NAME, SEDP_PUBLICATIONS_WRITER, SEDP_SUBSCRIPTIONS_WRITER, SPDP_WRITER,
)
from rosfpga_lab.widgets._common import WidgetError
from rosfpga_lab.widgets.byteview import ByteViewer, Span
from rosfpga_lab.widgets.sequence import SeqEvent, events_from_capture

#: The role the byte viewer colours CDR alignment padding with (see ``_common.ROLE_COLOURS``).
ALIGNMENT_ROLE = "alignment"


def cdr_spans(type_name: str, payload: bytes, *, registry: Any = None) -> list[Span]:
    """Byte viewer spans of a CDR payload: encapsulation header, fields, alignment padding."""
    out = []
    for f in cdr_layout(registry, type_name, payload, partial=True):
        if f.role == "padding":
            out.append(Span(f.offset, f.size, f"(padding before {f.path})", "padding",
                            f.value, ALIGNMENT_ROLE))
        elif f.role == "encapsulation":
            out.append(Span(f.offset, f.size, "encapsulation header", "CDR_LE", f.value, "length"))
        else:
            name = f"{f.path} length" if f.role == "length" else (f.path or f"({f.role})")
            out.append(Span(f.offset, f.size, name, f.type, f.value, f.role))
    return out


def cdr_viewer(type_name: str, payload: bytes, *, registry: Any = None, title: str = "",
               **kwargs: Any) -> ByteViewer:
    """A :class:`ByteViewer` of a CDR payload with its padding bytes highlighted."""
    return ByteViewer(payload, cdr_spans(type_name, payload, registry=registry),
                      title=title or f"{type_name} as CDR ({len(payload)} bytes)", **kwargs)


def capture_viewer(path: str | Path, index: int = 0, *, kind: str = "", **kwargs: Any) -> ByteViewer:
    """A :class:`ByteViewer` of one step of the ROS 1 conversation in a capture file.

    Args:
        path: a pcap/pcapng of real ROS 1 traffic.
        index: which step (as numbered in ``SequenceDiagram(path)``, from 0), counted among the
            steps of ``kind`` when given (``xmlrpc``, ``xmlrpc_reply``, ``tcpros_header``,
            ``tcpros_frame``).

    Raises:
        WidgetError: no such step.
    """
    events = [e for e in events_from_capture(path, frames_per_connection=1 << 30)
              if e.raw and (not kind or e.kind == kind)]
    if not 0 <= index < len(events):
        raise WidgetError(f"{path} has {len(events)} step(s) with bytes"
                          f"{' of kind ' + kind if kind else ''}; index {index} is not one of them")
    e = events[index]
    return ByteViewer(e.raw, e.byte_spans(), title=f"{e.src} \u2192 {e.dst}: {e.label}", **kwargs)


def rtps_spans(datagram: bytes) -> list[Span]:
    """Spans of one RTPS message: the header, then one per submessage."""
    msg = parse_message(datagram)
    spans = [Span(0, 20, "RTPS header", "header", msg.header.guid_prefix.hex(), "length")]
    for s in msg.submessages:
        spans.append(Span(s.offset, s.size, s.name, "submessage", "", "value"))
    return spans


def _who(prefix: bytes, names: dict[bytes, str]) -> str:
    if prefix not in names:
        names[prefix] = f"participant {len(names) + 1} ({prefix[:4].hex()}..)"
    return names[prefix]


def events_from_rtps(datagrams: Any, *, max_events: int = 60,
                     names: dict[bytes, str] | None = None) -> list[SeqEvent]:
    """Sequence-diagram events of RTPS datagrams.

    Args:
        datagrams: a capture file path, or ``(time, src, dst, payload)`` tuples as
            ``rosfpga_lab.graph.capture_read.udp_datagrams`` gives.
        max_events: arrows drawn at most (the rest summarised in one).
        names: lifeline names by GUID prefix (others are numbered ``participant N``).
    """
    if isinstance(datagrams, (str, Path)):
        from rosfpga_lab.graph.capture_read import udp_datagrams

        datagrams = udp_datagrams(datagrams)
    names = dict(names or {})
    out: list[SeqEvent] = []
    seen_frag: set[tuple[bytes, int, int]] = set()
    seen: set[bytes] = set()
    skipped = 0
    for t, _src, _dst, payload in datagrams:
        if payload in seen:   # the same announcement sent to each peer port: drawn once
            skipped += 1
            continue
        seen.add(bytes(payload))
        try:
            msg = parse_message(payload)
        except RtpsError:
            continue
        # one arrow per sender and destination: INFO_SRC lets one datagram carry the
        # submessages of several participants of one process (Cyclone DDS does this)
        groups: dict[tuple[bytes, bytes], list[str]] = {}
        sizes: dict[tuple[bytes, bytes], int] = {}
        fold = False
        for source, destination, s in msg.routed():
            # each submessage's bytes (INFO_* too) count to the sender it is routed from
            sizes[(source, destination)] = sizes.get((source, destination), 0) + s.size
            if isinstance(s, (InfoDst, InfoSrc)) or s.name == "INFO_TS":
                continue
            labels = groups.setdefault((source, destination), [])
            if isinstance(s, DataFrag):
                key = (source, s.writer_id, s.seq)
                fold = fold or key in seen_frag
                seen_frag.add(key)
                labels.append(f"DATA_FRAG seq {s.seq} frags {s.frag_start}..{s.frag_start + s.frag_count - 1}")
            elif isinstance(s, Data) and s.writer_id in (SEDP_PUBLICATIONS_WRITER, SEDP_SUBSCRIPTIONS_WRITER) and s.payload:
                try:
                    topic = parse_parameters(s.payload).get(PID_TOPIC_NAME, [b""])[0][4:].rstrip(b"\0")
                    labels.append(f"SEDP {'writer' if s.writer_id == SEDP_PUBLICATIONS_WRITER else 'reader'} "
                                  f"{topic.decode(errors='replace')}")
                except RtpsError:
                    labels.append("SEDP")
            elif isinstance(s, Data) and s.writer_id == SPDP_WRITER:
                labels.append("SPDP participant")
            else:
                labels.append(s.name)
        if fold:
            skipped += 1
            continue
        for (source, destination), labels in (groups or {(msg.header.guid_prefix, ANY_PARTICIPANT): []}).items():
            if len(out) >= max_events:
                skipped += 1
                continue
            src = _who(source, names)
            dst = _who(destination, names) if destination != ANY_PARTICIPANT else "peers"
            label = ", ".join(dict.fromkeys(labels)) or "INFO_TS"
            # a datagram packing several senders' submessages: each arrow its own share
            share = sizes.get((source, destination)) if len(groups) > 1 else None
            out.append(SeqEvent(src, dst, label[:70], bytes(payload), t, "rtps", detail=label[:300],
                                spans=rtps_spans(payload), size=share))
    if skipped and out:
        out.append(SeqEvent(out[-1].src, out[-1].dst, f"\u2026 {skipped} more RTPS messages", b"",
                            (out[-1].t or 0.0) + 1e-9, "rtps"))
    return out


def events_from_recording(recording: Any, *, max_events: int = 60) -> list[SeqEvent]:
    """Sequence-diagram events of a ROS 2 node's recording (``Ros2Node.recorded()``): its
    RTPS messages (as :func:`events_from_rtps`, lifelines named after the participants) and,
    as arrows of the node to itself at the time it logged them, its matching decisions
    ("matched", "not matched" with the reason). A message it received without INFO_DST is
    drawn to it (it was sent to its port), one it sent without INFO_DST to ``peers`` (every
    probed port)."""
    events = events_from_rtps(recording.datagrams, max_events=max_events, names=recording.names)
    more = events.pop() if events and events[-1].label.startswith("\u2026") else None
    me = recording.names.get(recording.prefix, "")
    for e in events:     # what the node received was sent to it, INFO_DST or not
        if me and e.src != me and e.dst == "peers":
            e.dst = me
    if me and events:
        last = events[-1].t or 0.0
        for t, text in recording.notes:
            if text.startswith(("matched", "not matched")) and t <= last:
                topic = next((w for w in text.split() if w.startswith("rt/")), "")
                events.append(SeqEvent(me, me, f"{text.split(':')[0]} {topic}".strip(), b"", t,
                                       "rtps_match", detail=text))
        events.sort(key=lambda e: e.t or 0.0)
    return events + ([more] if more else [])


__all__ = ["ALIGNMENT_ROLE", "capture_viewer", "cdr_spans", "cdr_viewer", "events_from_recording",
           "events_from_rtps", "rtps_spans"]
