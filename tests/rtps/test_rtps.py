"""The RTPS decoder on a real Cyclone DDS capture, against Wireshark's RTPS dissector."""

from __future__ import annotations

import struct
from collections import Counter
from pathlib import Path

import numpy as np
import pytest

from rosfpga_lab.graph.capture_read import udp_datagrams
from rosfpga_lab.msg import deserialize_cdr
from rosfpga_lab.rtps import build as b
from rosfpga_lab.rtps import (
    ANY_PARTICIPANT, AckNack, DataFrag, FragmentAssembler, Gap, InfoSrc, RtpsError,
    RtpsTruncatedError, discovery, parse_message, parse_parameters,
)
from tests.support.wiretools import assert_rtps_agrees_with_tshark, tshark_fields

CAPTURE = Path(__file__).resolve().parents[2] / "data" / "rtps_image.pcapng"
DATAGRAMS = [d[3] for d in udp_datagrams(CAPTURE)]
MESSAGES = [parse_message(d) for d in DATAGRAMS]
HEADER = b"RTPS\x02\x01\x01\x10" + bytes(range(12))


def test_capture_has_every_kind_the_issue_names() -> None:
    kinds = Counter(s.name for m in MESSAGES for s in m.submessages)
    assert {"INFO_TS", "INFO_DST", "DATA", "DATA_FRAG", "HEARTBEAT", "ACKNACK"} <= set(kinds)


def test_discovery_names_topic_type_and_participants() -> None:
    participants, endpoints = discovery(MESSAGES)
    assert len(participants) == 2
    assert {(e.kind, e.topic, e.type_name) for e in endpoints} == {
        ("writer", "rt/image_raw", "sensor_msgs::msg::dds_::Image_"),
        ("reader", "rt/image_raw", "sensor_msgs::msg::dds_::Image_")}


def test_fragments_reassemble_into_the_published_image() -> None:
    asm = FragmentAssembler()
    images = []
    for msg in MESSAGES:
        for sub in msg.submessages:
            if isinstance(sub, DataFrag):
                sample = asm.add(msg.header.guid_prefix, sub)
                if sample is not None:
                    images.append(deserialize_cdr(None, "sensor_msgs/Image", sample))
    assert len(images) == 2
    for i, img in enumerate(images):
        assert (img["width"], img["height"], img["encoding"], img["step"]) == (640, 480, "rgb8", 1920)
        assert img["header"] == {"stamp": {"sec": 1_700_000_000 + i, "nanosec": 500},
                                 "frame_id": "camera"}
        # the script's pixels: (x * 7 + i) % 256 for byte x
        expected = (np.arange(640 * 480 * 3) * 7 + i) % 256
        assert np.array_equal(img["data"], expected.astype(np.uint8))


def test_decoder_agrees_with_tshark() -> None:
    assert assert_rtps_agrees_with_tshark(CAPTURE) == len(MESSAGES)


@pytest.mark.parametrize("index", [0, 1, 2, 5, 40])
def test_every_prefix_is_a_shorter_message_or_a_typed_error(index: int) -> None:
    data = DATAGRAMS[index]
    whole = parse_message(data).submessages
    ends = {s.offset + s.size for s in whole}
    for n in range(len(data)):
        try:
            part = parse_message(data[:n]).submessages
        except RtpsTruncatedError as exc:
            assert 0 <= exc.offset <= n
            continue
        # a prefix that parses ends between two submessages, or cuts the last one whose length
        # says "to the end of the message"
        assert n in ends or n == 20 or part[-1].size == n - part[-1].offset
        assert [s.kind for s in part] == [s.kind for s in whole[:len(part)]]


def test_trailing_bytes_are_refused_or_read_as_submessages() -> None:
    data = DATAGRAMS[3]
    with pytest.raises(RtpsTruncatedError, match="too few for a submessage header"):
        parse_message(data + b"\x00\x01")
    more = parse_message(data + b"\x01\x01\x00\x00")  # a PAD submessage after the rest
    assert more.submessages[-1].name == "PAD"
    assert more.submessages[:-1] == parse_message(data).submessages
    with pytest.raises(RtpsError, match="not an RTPS message"):
        parse_message(b"RTPX" + data[4:])


def test_gap_and_acknack_bitmaps_from_bytes() -> None:
    gap = struct.pack("<BBH4s4siIiIII", 0x08, 0x01, 32, b"\x00\x00\x02\x04", b"\x00\x00\x02\x03",
                      0, 5, 0, 9, 3, 0xA0000000)
    (sub,) = parse_message(HEADER + gap).submessages
    assert isinstance(sub, Gap) and (sub.start, sub.list_base, sub.listed) == (5, 9, (9, 11))
    ack = struct.pack(">BBH4s4siIIIi", 0x06, 0x00, 28, b"\x00\x00\x02\x04", b"\x00\x00\x02\x03",
                      0, 7, 2, 0x40000000, 3)
    (sub,) = parse_message(HEADER + ack).submessages
    assert isinstance(sub, AckNack) and (sub.base, sub.missing, sub.count) == (7, (8,), 3)
    assert sub.writer_id == 0x00000203 and not sub.little_endian
    with pytest.raises(RtpsTruncatedError):
        parse_message(HEADER + ack[:-4])  # declares 28 bytes, has 24


def test_parameter_list_errors() -> None:
    with pytest.raises(RtpsError, match="not a parameter list"):
        parse_parameters(b"\x00\x01\x00\x00")
    with pytest.raises(RtpsTruncatedError, match="PID_SENTINEL"):
        parse_parameters(b"\x00\x03\x00\x00\x05\x00\x04\x00abcd")
    assert parse_parameters(b"\x00\x03\x00\x00\x05\x00\x04\x00abcd\x01\x00\x00\x00") == {5: [b"abcd"]}


def test_assembler_bounds_memory() -> None:
    frag = DataFrag(kind=0x16, flags=1, offset=0, size=0, writer_id=1, seq=1, frag_start=1,
                    frag_count=1, frag_size=4, sample_size=10**9, payload=b"abcd")
    with pytest.raises(RtpsError, match="max_sample_bytes"):
        FragmentAssembler().add(b"p" * 12, frag)


def test_assembler_ignores_fragment_numbers_past_the_sample() -> None:
    asm = FragmentAssembler()
    common = dict(kind=0x16, flags=1, offset=0, size=0, writer_id=1, seq=1, frag_size=4,
                  sample_size=6)
    assert asm.add(b"p" * 12, DataFrag(**common, frag_start=9, frag_count=1, payload=b"zzzz")) is None
    assert asm.add(b"p" * 12, DataFrag(**common, frag_start=2, frag_count=1, payload=b"ef")) is None
    assert asm.add(b"p" * 12, DataFrag(**common, frag_start=1, frag_count=1, payload=b"abcd")) == b"abcdef"


# ---- INFO_SRC: two participants of one process in one datagram ----------------------------------
#: A real datagram of Cyclone DDS (PyPI cyclonedds 0.10) with two participants in one process,
#: sent to a lab participant (010fb4ed..): the header names one participant, INFO_SRC switches
#: to the other for its SPDP, a second INFO_SRC switches back. Made by
#: data/capture_cyclone_info_src.py.
INFO_SRC_DATAGRAM = (CAPTURE.parent / "cyclone_info_src_spdp.bin").read_bytes()
FIRST, SECOND = bytes.fromhex("01109729d515b1b1edabb6b4"), bytes.fromhex("0110972927d126a60dd1d6af")
LAB = bytes.fromhex("010fb4edbcfd6003fa1936d9")


def test_info_src_sets_the_source_of_the_submessages_after_it() -> None:
    msg = parse_message(INFO_SRC_DATAGRAM)
    assert msg.header.guid_prefix == FIRST
    infos = [s for s in msg.submessages if isinstance(s, InfoSrc)]
    assert [(s.guid_prefix, s.version, s.vendor_id) for s in infos] == [
        (SECOND, (2, 5), 0x0110), (FIRST, (2, 5), 0x0110)]
    routed = [(src, dst, s.name) for src, dst, s in msg.routed()]
    assert routed == [(FIRST, LAB, "INFO_DST"), (FIRST, LAB, "ACKNACK"), (FIRST, LAB, "ACKNACK"),
                      (FIRST, LAB, "HEARTBEAT"), (FIRST, LAB, "HEARTBEAT"),
                      (SECOND, LAB, "INFO_SRC"), (SECOND, LAB, "INFO_TS"), (SECOND, LAB, "DATA"),
                      (FIRST, LAB, "INFO_SRC"), (FIRST, LAB, "INFO_TS"), (FIRST, LAB, "DATA")]
    # each SPDP announces the participant INFO_SRC named, which discovery() reports
    participants, _ = discovery([msg])
    assert {p.guid_prefix for p in participants} == {FIRST, SECOND}


def test_routed_starts_from_the_header_and_any_participant() -> None:
    msg = parse_message(HEADER + struct.pack("<BBH", 0x09, 0x03, 0))
    assert [(src, dst) for src, dst, _ in msg.routed()] == [(HEADER[8:20], ANY_PARTICIPANT)]


def test_info_src_agrees_with_tshark(tmp_path: Path) -> None:
    from scapy.all import IP, UDP, Ether, Raw, wrpcap

    capture = tmp_path / "info_src.pcap"
    wrpcap(str(capture), [Ether() / IP(src="127.0.0.1", dst="127.0.0.1")
                          / UDP(sport=7410, dport=7412) / Raw(INFO_SRC_DATAGRAM)])
    assert assert_rtps_agrees_with_tshark(capture) == 1
    [[sources]] = tshark_fields(capture, ["rtps.guidPrefix.src"], display_filter="rtps")
    msg = parse_message(INFO_SRC_DATAGRAM)
    ours = [msg.header.guid_prefix] + [s.guid_prefix for s in msg.submessages if isinstance(s, InfoSrc)]
    assert sources.split("|") == [p.hex() for p in ours]


@pytest.mark.parametrize("cut", range(1, 24))
def test_a_datagram_cut_inside_info_src_is_a_typed_error(cut: int) -> None:
    at = next(s.offset for s in parse_message(INFO_SRC_DATAGRAM).submessages if isinstance(s, InfoSrc))
    with pytest.raises(RtpsTruncatedError):
        parse_message(INFO_SRC_DATAGRAM[:at + cut])


@pytest.mark.parametrize("length", range(20))
def test_an_info_src_body_shorter_than_20_bytes_is_a_typed_error(length: int) -> None:
    with pytest.raises(RtpsTruncatedError, match="INFO_SRC at byte 20"):
        parse_message(HEADER + struct.pack("<BBH", 0x0C, 0x01, length) + bytes(length))


# ---- the receiver's rules (RTPS 2.3 8.3.4.1, 9.4.1; what Cyclone DDS's ddsi_receive.c does) ----
SPDP_DATA = b.data(0x000100C7, 0x000100C2, 1, b"\x00\x03\x00\x00\x01\x00\x00\x00")  # empty list


def test_pad_info_reply_vendor_and_unknown_submessages_are_skipped() -> None:
    skipped = (b"\x01\x01\x00\x00"                                       # PAD, empty
               + b"\x01\x01\x04\x00" + bytes(4)                         # PAD with 4 bytes
               + b"\x09\x03\x00\x00"                                    # INFO_TS, I flag: no time
               + b"\x0f\x01\x04\x00" + struct.pack("<I", 0)          # INFO_REPLY, no locators
               + b"\x0d\x01\x08\x00" + bytes(8)                         # INFO_REPLY_IP4
               + b"\x80\x01\x04\x00abcd"                                # vendor-specific id
               + b"\x7e\x00\x00\x04wxyz")                               # an id RTPS 2.3 lacks
    msg = parse_message(HEADER + skipped + SPDP_DATA)
    assert [s.name for s in msg.submessages] == ["PAD", "PAD", "INFO_TS", "INFO_REPLY",
                                                 "INFO_REPLY_IP4", "0x80", "0x7e", "DATA"]
    assert msg.submessages[2].timestamp is None
    assert msg.submessages[-1].payload == SPDP_DATA[24:]


def test_octets_to_inline_qos_past_16_skips_the_extra_fields() -> None:
    # a later RTPS minor version may add fields before the inline QoS: octetsToInlineQos says
    # where the QoS (and then the payload) starts, 8 bytes further here
    body = (struct.pack("<HH", 0, 24) + bytes.fromhex("00000104") + bytes.fromhex("00000103")
            + struct.pack("<iI", 0, 7) + b"EXTRAEXT" + b"\x00\x01\x00\x00data")
    (sub,) = parse_message(HEADER + b"\x15\x05" + struct.pack("<H", len(body)) + body).submessages
    assert (sub.seq, sub.writer_id, sub.payload) == (7, 0x103, b"\x00\x01\x00\x00data")


def test_a_data_frag_with_two_fragments_reassembles() -> None:
    sample = b"\x00\x01\x00\x00" + bytes(range(60))          # 64 bytes in 16-byte fragments
    first = b.data_frag(0x104, 0x103, 1, 1, 16, len(sample), sample[:32], 2)
    rest = b.data_frag(0x104, 0x103, 1, 3, 16, len(sample), sample[32:], 2)
    asm = FragmentAssembler()
    frags = [parse_message(HEADER + sm).submessages[0] for sm in (first, rest)]
    assert [(f.frag_start, f.frag_count) for f in frags] == [(1, 2), (3, 2)]
    assert asm.add(b"p" * 12, frags[0]) is None
    assert asm.add(b"p" * 12, frags[1]) == sample


def test_data_with_both_data_and_key_flags_is_malformed() -> None:
    dk = bytes([SPDP_DATA[0], SPDP_DATA[1] | 0x08]) + SPDP_DATA[2:]
    with pytest.raises(RtpsError, match="both the D .data. and K .key. flags"):
        parse_message(HEADER + dk)


def test_a_misaligned_submessage_is_malformed_unless_it_is_the_last() -> None:
    odd = b"\x80\x01\x03\x00abc"                              # 3 bytes: the next would start unaligned
    assert parse_message(HEADER + odd).submessages[0].size == 7     # last: up to the end
    with pytest.raises(RtpsError, match="not a multiple of 4"):
        parse_message(HEADER + odd + SPDP_DATA)


def test_keep_valid_keeps_the_submessages_before_a_malformed_one() -> None:
    bad_hb = b"\x07\x01\x08\x00" + bytes(8)                   # a HEARTBEAT needs 28 bytes
    data = HEADER + SPDP_DATA + bad_hb + SPDP_DATA
    with pytest.raises(RtpsTruncatedError):
        parse_message(data)
    msg = parse_message(data, keep_valid=True)
    assert [s.name for s in msg.submessages] == ["DATA"]
    assert isinstance(msg.error, RtpsTruncatedError) and msg.error.offset >= 20 + len(SPDP_DATA)
    assert parse_message(HEADER + SPDP_DATA, keep_valid=True).error is None
    with pytest.raises(RtpsError, match="not an RTPS message"):
        parse_message(b"RTPX" + data[4:], keep_valid=True)       # a bad header raises either way


def test_the_sedp_dispose_capture_agrees_with_tshark() -> None:
    capture = CAPTURE.parent / "cyclone_sedp_dispose.pcapng"
    assert assert_rtps_agrees_with_tshark(capture) == len(udp_datagrams(capture))
    [*_, [status]] = tshark_fields(capture, ["rtps.param.status_info"], display_filter="rtps")
    assert int(status, 0) == 3          # the last datagram: disposed and unregistered


def test_the_cyclone_configuration_probes_the_indices_the_lab_probes() -> None:
    """Cyclone sends SPDP to participant indices 0..MaxAutoParticipantIndex, the lab probes
    0..MAX_PARTICIPANT_INDEX: the two must be one number (the ROS 2 tests run real Cyclone
    under this configuration)."""
    import xml.etree.ElementTree as ET

    from rosfpga_lab.rtps.cyclone import cyclone_loopback_uri
    from rosfpga_lab.rtps.limits import MAX_PARTICIPANT_INDEX

    root = ET.fromstring(cyclone_loopback_uri())
    assert root.findtext("Domain/Discovery/MaxAutoParticipantIndex") == str(MAX_PARTICIPANT_INDEX)
    assert root.findtext("Domain/General/AllowMulticast") == "false"
    assert root.find("Domain/General/Interfaces/NetworkInterface").get("address") == "127.0.0.1"
    assert root.find("Domain/Discovery/LeaseDuration") is None
    assert ET.fromstring(cyclone_loopback_uri(1.5)).findtext("Domain/Discovery/LeaseDuration") == "1.5s"
    assert root.find("Domain/General/MaxMessageSize") is None
    sized = ET.fromstring(cyclone_loopback_uri(max_message_bytes=1472))
    assert sized.findtext("Domain/General/MaxMessageSize") == "1472B"
