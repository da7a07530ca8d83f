"""Checks of notebook 12 (one ROS 2 sample through the node in the fabric): where the RTPS
message starts in a frame on the wire, and when the UDP stage hands a datagram on."""

from __future__ import annotations

from typing import Any

from rosfpga_lab.checks._core import CheckResult, fail, require_type
from rosfpga_lab.rtl.fabricdemo import PREAMBLE, gmii_frames, stream_bytes
from rosfpga_lab.rtl.vcd import Waveform

ETHERNET_HEADER, IPV4_HEADER, UDP_HEADER = 14, 20, 8


def check_rtps_offset(answer: Any, frame: bytes) -> CheckResult:
    """Exercise 12.1: the offset of the RTPS header (``RTPS``) in a GMII frame as the PHY
    carries it (preamble and SFD first).

    Raises:
        ExerciseError: a wrong offset, with the layer probably left out or added.
    """
    ex = "12.1 (where RTPS starts on the wire)"
    require_type(ex, "rtps_offset", answer, int)
    frame = bytes(frame)
    ihl = 4 * (frame[len(PREAMBLE) + ETHERNET_HEADER] & 0x0F)
    want = len(PREAMBLE) + ETHERNET_HEADER + ihl + UDP_HEADER
    if frame[want:want + 4] != b"RTPS":
        raise ValueError("the frame holds no RTPS message after one IPv4 and one UDP header")
    if answer == want:
        return CheckResult(ex, [f"RTPS starts at byte {want}: {len(PREAMBLE)} bytes of preamble "
                                f"and SFD, {ETHERNET_HEADER} of Ethernet, {ihl} of IPv4, "
                                f"{UDP_HEADER} of UDP"])
    mistakes = [
        (-len(PREAMBLE), "left out the 7-byte preamble and the SFD (on the wire they come "
                         "first; the dump's rxd has them)"),
        (-UDP_HEADER, "left out the 8-byte UDP header (ports, length, checksum)"),
        (-ihl, f"left out the {ihl}-byte IPv4 header"),
        (-ETHERNET_HEADER, "left out the 14-byte Ethernet header (two MACs, EtherType)"),
        (+4, "counted the 4-byte FCS, which ends the frame"),
        (+20, "counted RTPS's own 20-byte header: the offset is where it starts"),
    ]
    found = [text for delta, text in mistakes if want + delta == answer]
    raise fail(ex, f"rtps_offset {answer}, expected another value: "
                   f"{' - or you '.join(found) if found else 'add up the headers before RTPS'}")


def check_handoff_clock(answer: Any, wave: Waveform) -> CheckResult:
    """Exercise 12.2: the clock at which ``rfl_udp_port`` hands the first byte of the first
    datagram on (``p_rx_tvalid`` and ``p_rx_tready`` both 1).

    Raises:
        ExerciseError: a wrong clock, named when it is another stage's.
    """
    ex = "12.2 (when the UDP stage hands a datagram on)"
    require_type(ex, "handoff_clock", answer, int)
    want = int(stream_bytes(wave, "p_rx")[0][0])
    liteeth = int(stream_bytes(wave, "le_rx")[0][0])
    start, frame = gmii_frames(wave, "rx")[0]
    end = start + len(frame) - 1
    if answer == want:
        return CheckResult(ex, [f"clock {want}: {want - end} clocks after the frame's last "
                                f"byte (clock {end}), {want - liteeth} after LiteEth's first "
                                "payload byte: rfl_udp_port keeps a datagram until its FCS "
                                "proved good"])
    hints = {liteeth: "that is LiteEth's first payload byte (le_rx_*): rfl_udp_port does not "
                      "pass it on yet",
             start: "that is the frame's first byte on the GMII side (rx_dv)",
             end: "that is the frame's last byte on the GMII side; look at p_rx_tvalid"}
    hint = hints.get(answer, "find the first clock with p_rx_tvalid and p_rx_tready both 1")
    raise fail(ex, f"handoff_clock {answer}, expected another clock: {hint}")
