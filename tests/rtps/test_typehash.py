"""The ROS 2 type hash on the wire: SEDP USER_DATA ``typehash=RIHS01_...;`` as Jazzy's rmw
sends it (rmw_dds_common ``encode_type_hash_for_user_data_qos``), read back by the decoder and
the participant; a differing hash is logged once and the endpoints still match, as rmw does."""

from __future__ import annotations

import struct

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rosfpga_lab.msg.typehash import RIHS_PATTERN
from rosfpga_lab.rtps import build as b
from rosfpga_lab.rtps import parse_message
from rosfpga_lab.rtps.discovery import discovery, parse_parameters, user_data_type_hash
from rosfpga_lab.rtps.errors import RtpsError
from rosfpga_lab.rtps.participant import PUB_READER, PUB_WRITER, Participant
from tests.rtps.test_participant import TOPIC, TYPE, Net, fresh, spdp

# sensor_msgs/msg/Image and std_msgs/msg/Header of ROS 2 Jazzy (share/*/msg/*.json)
IMAGE = "RIHS01_d31d41a9a4c4bc8eae9be757b0beed306564f7526c88ea6a4588fb9582527d47"
HEADER = "RIHS01_f49fb3ae2cf070f793645ff749683ac6b06203e41c891e17701b1cb597ce6a01"
PREFIX = bytes(range(1, 13))
GUID = PREFIX + bytes([0, 0, 1, 3])
LOCATOR = b.Locator("127.0.0.1", 7411)


def test_sedp_user_data_bytes() -> None:
    payload = b.sedp_payload(GUID, TOPIC, TYPE, True, 10, LOCATOR, type_hash=IMAGE)
    text = b"typehash=" + IMAGE.encode() + b";"          # 81 bytes, no NUL
    assert len(text) == 81
    # pid 0x002c, length 88 (4 + 81 padded to 4), the octet count 81, the text, 3 pad bytes
    param = bytes.fromhex("2c 00 58 00 51 00 00 00") + text + bytes(3)
    assert payload.count(param) == 1
    assert parse_parameters(payload)[b.PID_USER_DATA] == [param[4:]]
    # without a hash (a type the lab cannot load) no USER_DATA, as rmw with an unset hash
    assert b.PID_USER_DATA not in parse_parameters(
        b.sedp_payload(GUID, TOPIC, TYPE, True, 10, LOCATOR))


def test_type_hash_decoded_from_bytes() -> None:
    text = b"typehash=" + IMAGE.encode() + b";"
    value = struct.pack("<I", len(text)) + text + bytes(3)
    assert user_data_type_hash(value) == IMAGE
    assert user_data_type_hash(struct.pack(">I", len(text)) + text, little=False) == IMAGE
    other = b"enclave=/;typehash=" + HEADER.encode() + b";x=1;"
    assert user_data_type_hash(struct.pack("<I", len(other)) + other) == HEADER
    no_end = b"typehash=" + IMAGE.encode()                   # no trailing ';' is still read
    assert user_data_type_hash(struct.pack("<I", len(no_end)) + no_end) == IMAGE
    for bad in (b"", b"\x05\x00\x00\x00", b"typehash", b"typehash=RIHS01_dead;",
                b"mytypehash=" + IMAGE.encode() + b";", b"typehash=" + IMAGE.upper().encode(),
                b"=" + IMAGE.encode() + b";"):
        assert user_data_type_hash(struct.pack("<I", len(bad)) + bad) == "", bad
    assert user_data_type_hash(b"\x01\x00") == ""                       # shorter than a count
    assert user_data_type_hash(struct.pack("<I", 10**9) + text) == IMAGE  # count past the end


def test_discovery_exposes_the_announced_hash() -> None:
    def sedp(guid: bytes, h: str) -> bytes:
        payload = b.sedp_payload(guid, TOPIC, TYPE, True, 10, LOCATOR, type_hash=h)
        return b.header(PREFIX) + b.data(PUB_READER, PUB_WRITER, 1, payload)

    second = PREFIX + bytes([0, 0, 2, 3])
    _, endpoints = discovery([parse_message(sedp(GUID, IMAGE)), parse_message(sedp(second, ""))])
    assert {e.guid: e.type_hash for e in endpoints} == {GUID: IMAGE, second: ""}


def _pair(writer_hash: str, reader_hash: str) -> tuple[Participant, Participant, int, int]:
    a = Participant(domain=7, index=0, announce=0.1)
    c = Participant(domain=7, index=1, announce=0.1)
    w = a.add_writer(TOPIC, TYPE, type_hash=writer_hash)
    r = c.add_reader(TOPIC, TYPE, type_hash=reader_hash)
    Net(a, c).run([], steps=20)
    return a, c, w, r


def test_remote_endpoint_records_the_hash_and_a_mismatch_is_logged_once_but_matched() -> None:
    a, c, w, r = _pair(IMAGE, HEADER)
    assert len(a.matched(w)) == 1 and len(c.matched(r)) == 1       # rmw matches all the same
    assert [rem.type_hash for rem in c.remote.values()] == [IMAGE]
    assert [rem.type_hash for rem in a.remote.values()] == [HEADER]
    for side, theirs, ours in ((a, HEADER, IMAGE), (c, IMAGE, HEADER)):
        said = [n for n in side.notes if "type hash differs" in n]
        assert len(said) == 1 and theirs in said[0] and ours in said[0], side.notes
    Net(a, c).run([], steps=20)          # re-announcements say nothing new
    assert sum("type hash differs" in n for n in a.notes + c.notes) == 2


@pytest.mark.parametrize("writer_hash,reader_hash", [(IMAGE, IMAGE), (IMAGE, ""), ("", IMAGE)])
def test_equal_or_missing_hashes_say_nothing(writer_hash: str, reader_hash: str) -> None:
    a, c, w, r = _pair(writer_hash, reader_hash)
    assert len(a.matched(w)) == 1 and len(c.matched(r)) == 1
    assert not any("type hash" in n for n in a.notes + c.notes)


def test_a_malformed_local_hash_is_refused() -> None:
    p = Participant(domain=7, index=0)
    with pytest.raises(RtpsError, match="RIHS01_"):
        p.add_writer(TOPIC, TYPE, type_hash="RIHS01_dead")


def test_type_hash_decoder_byte_by_byte_and_with_trailing_bytes() -> None:
    text = b"enclave=/;typehash=" + IMAGE.encode() + b";"
    value = struct.pack("<I", len(text)) + text
    for n in range(len(value)):                   # every prefix: nothing, or the whole hash
        got = user_data_type_hash(value[:n])
        assert got in ("", IMAGE), n
        assert (got == IMAGE) == (n >= len(value) - 1), n      # only the ';' may be missing
    assert user_data_type_hash(value + b"typehash=junk;" + bytes(7)) == IMAGE  # past the count


@settings(max_examples=300, deadline=None)
@given(st.one_of(st.binary(max_size=200),
                 st.lists(st.sampled_from([b"typehash=", IMAGE.encode(), b";", b"=", b"\xff",
                                           b"RIHS01_", b"0" * 64]), max_size=8).map(b"".join)
                 .map(lambda t: struct.pack("<I", len(t)) + t)))
def test_any_user_data_never_raises(value: bytes) -> None:
    got = user_data_type_hash(value)
    assert got == "" or RIHS_PATTERN.fullmatch(got)
    p = fresh()
    prefix = b"Q" * 12
    p.receive(spdp(prefix), ("127.0.0.1", 7999), 0.0)
    payload = b.param_list([(b.PID_ENDPOINT_GUID, prefix + bytes([0, 0, 1, 3])),
                            (b.PID_TOPIC_NAME, b.cdr_string(TOPIC)),
                            (b.PID_TYPE_NAME, b.cdr_string(TYPE)),
                            (b.PID_UNICAST_LOCATOR, LOCATOR.encode()), (b.PID_USER_DATA, value)])
    p.receive(b.header(prefix) + b.data(PUB_READER, PUB_WRITER, 1, payload), ("127.0.0.1", 7999), 0.0)
    assert [r.type_hash for r in p.remote.values()] == [got]
