"""A model of the fabric participant's answers: ``fabric/rfl_rtps_ctrl.v`` and
``fabric/rfl_rtps_disc_answer.v`` in Python, driven by the same tables.

How this works: :class:`AnswerModel` reads each received datagram with the lab's decoder
(``rtps.parse_message(keep_valid=True)`` and ``RtpsMessage.routed``: what a malformed submessage
drops, the destination INFO_DST sets), finds what the circuit's slots match (the rules are the
Verilog's header comment and ``rtl.discrom``'s docstring: an ACKNACK to a writer slot asks its
HEARTBEAT (base 0, or a base at or below the last held with no held number named) or the DATA of
each held number its bitmap names; a HEARTBEAT without F to a reader slot asks its ACKNACK with
base lastSN + 1), and writes the answers from the rendered ROM
(:attr:`~rosfpga_lab.rtl.discrom.DiscoveryRom.answers`) with their run-time fields patched
(:func:`patch_answer`), spending the same credit (``burst`` at first, ``rate`` per byte
received; the circuit's earns nothing on the clock an answer starts, so it may refuse a little
more, never send more). It has no clock: requests for a slot still pending in the circuit (sent
back to back) are not modelled; the tests give the circuit time between datagrams, or check the
bound alone. The loopback test (``tests/rtl/test_fabric_answer.py``) runs it beside Cyclone DDS
in place of the circuit.
"""

from __future__ import annotations

import struct
from dataclasses import dataclass

from rosfpga_lab.rtl.discrom import (
    ANSWER_BASE_AT, ANSWER_COUNT_START, ANSWER_DST_AT, DiscoveryRom, RomMessage, answer_flags,
)
from rosfpga_lab.rtl.limits import ANSWER_BURST, ANSWER_RATE, MAX_ANSWER_SEQ
from rosfpga_lab.rtps.errors import RtpsError
from rosfpga_lab.rtps.message import ANY_PARTICIPANT, AckNack, Heartbeat, parse_message

#: HEARTBEAT's F flag; the built-in reader entity kind a built-in writer kind 0xC2 pairs with.
_FINAL, _BUILTIN_READER_KIND = 0x02, 0xC7


@dataclass(frozen=True)
class Answer:
    """One answer datagram: where it goes (DEST_*), for whom (GUID prefix), its bytes."""

    dest: int
    prefix: bytes
    data: bytes


def patch_answer(message: RomMessage, prefix: bytes, base: int, count: int) -> bytes:
    """The answer's bytes as the circuit sends them: the asker's prefix in INFO_DST, the base (an
    ACKNACK's) and the count written."""
    out = bytearray(message.data)
    out[ANSWER_DST_AT:ANSWER_DST_AT + 12] = prefix
    if answer_flags(message):
        out[ANSWER_BASE_AT:ANSWER_BASE_AT + 8] = struct.pack("<II", (base >> 32) & 0xFFFFFFFF,
                                                                 base & 0xFFFFFFFF)
    out[-4:] = struct.pack("<I", count & 0xFFFFFFFF)
    return bytes(out)


def requests(rom: DiscoveryRom, datagram: bytes) -> list[tuple[int, bytes, int]]:
    """The requests the circuit's watcher makes of one datagram: (answer message, the asker's
    prefix, base), in the order it sends them (slot by slot, message by message)."""
    try:
        msg = parse_message(datagram, keep_valid=True)
    except RtpsError:
        return []
    if msg.header.version[0] != 2 or msg.header.guid_prefix == rom.guid_prefix:
        return []
    out: list[tuple[int, bytes, int]] = []
    for source, dst, sub in msg.routed():
        if dst not in (rom.guid_prefix, ANY_PARTICIPANT):
            continue
        for slot in rom.slots:
            if isinstance(sub, AckNack) and slot.writer and sub.writer_id == slot.entity_id:
                held = [s for s in sub.missing if 1 <= s <= min(slot.last, MAX_ANSWER_SEQ)]
                if sub.base == 0 or (not held and sub.base <= slot.last):
                    out.append((slot.message, source, 0))       # its HEARTBEAT
                else:
                    out += [(slot.message + s, source, 0) for s in held]
            elif (isinstance(sub, Heartbeat) and not slot.writer and not sub.flags & _FINAL and
                  (sub.reader_id == slot.entity_id or (sub.reader_id == 0 and (
                      sub.writer_id & ~0xFF | _BUILTIN_READER_KIND) == slot.entity_id))):
                out.append((slot.message, source, sub.last + 1))
    return out


class AnswerModel:
    """The circuit's answers to a stream of received datagrams (its credit and count kept)."""

    def __init__(self, rom: DiscoveryRom, burst: int = ANSWER_BURST, rate: int = ANSWER_RATE,
                 count_start: int = ANSWER_COUNT_START) -> None:
        self.rom, self.burst, self.rate = rom, burst, rate
        self.credit, self.count = burst, count_start
        self.no_credit = 0

    def receive(self, datagram: bytes) -> list[Answer]:
        """The answers to ``datagram`` (its bytes earn credit first)."""
        self.credit = min(self.burst, self.credit + self.rate * len(datagram))
        out = []
        for index, prefix, base in requests(self.rom, datagram):
            m = self.rom.answers[index]
            if len(m.data) > self.credit:
                self.no_credit += 1
                continue
            self.credit -= len(m.data)
            out.append(Answer(m.dest, prefix, patch_answer(m, prefix, base, self.count)))
            self.count += 1
        return out
