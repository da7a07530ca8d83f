"""Capture files of the lab's own conversation, read back by scapy and by Wireshark's tshark."""

from __future__ import annotations

from pathlib import Path

import pytest

from rosfpga_lab.graph import Trace
from rosfpga_lab.graph.capture import MSS, capture_packets, connections, write_capture
from tests.support.wiretools import tshark_fields

IMAGE_MD5 = "060021388200f6f0f447d0fcd9c64743"  # DESIGN.md; genpy's sensor_msgs/Image._md5sum


def _fake_trace() -> Trace:
    """One XML-RPC call and one TCPROS link (subscriber side recorded), by hand."""
    tr = Trace(frame_bytes=8)
    c, s = "127.0.0.1:40000", "127.0.0.1:11311"
    tr.record("xmlrpc", "/a", role="client", src="/a", dst="/master", method="getUri",
              raw=b"POST / HTTP/1.1\r\n\r\n<x/>", raw_reply=b"HTTP/1.1 200 OK\r\n\r\n<y/>",
              local=c, remote=s, t0=1.0)
    sub, pub = "127.0.0.1:40001", "127.0.0.1:50000"
    tr.record("tcp_connect", "/b", role="out", local=sub, remote=pub, t0=2.0)
    tr.record("tcpros_header", "/b", role="out", raw=b"\x05\x00\x00\x00\x01\x00\x00\x00a",
              size=9, local=sub, remote=pub, t0=2.1)
    tr.record("tcpros_header", "/b", role="in", raw=b"\x04\x00\x00\x00\x00\x00\x00\x00", size=8,
              local=sub, remote=pub, t0=2.2)
    body = 200_000
    tr.record("tcpros_frame", "/b", role="in", raw=tr.frame_raw(bytes(range(250)) * 800),
              size=4 + body, local=sub, remote=pub, t0=2.3)
    tr.record("tcp_close", "/b", role="in", local=sub, remote=pub, t0=2.4)
    return tr


def test_segments_have_consistent_sequence_numbers() -> None:
    packets = capture_packets(_fake_trace())
    conns = connections([_fake_trace()])
    assert [(c.client, c.server) for c in conns] == [
        ("127.0.0.1:40000", "127.0.0.1:11311"), ("127.0.0.1:40001", "127.0.0.1:50000")]
    for conn in conns:
        mine = [p for p in packets if {p.src, p.dst} == {conn.client, conn.server}]
        assert [p.flags for p in mine[:3]] == ["S", "SA", "A"]
        assert mine[0].src == conn.client
        nxt = {conn.client: mine[0].seq + 1, conn.server: mine[1].seq + 1}
        assert mine[1].ack == nxt[conn.client]
        for p in mine[2:]:
            assert p.seq == nxt[p.src], p
            assert p.ack == nxt[p.dst], p
            assert p.length <= MSS
            nxt[p.src] += p.length + ("F" in p.flags)
        assert "F" in mine[-2].flags and mine[-1].flags == "A"
        assert [p.t for p in mine] == sorted(p.t for p in mine)
    frame = [p for p in packets if p.length and p.src == "127.0.0.1:50000"]
    # headers 8 bytes, then the 200004-byte frame in MSS segments: only 12 bytes were kept
    assert [p.length for p in frame] == [8, MSS, MSS, MSS, 200_004 - 3 * MSS]
    assert frame[1].data == (200_000).to_bytes(4, "little") + bytes(range(8))
    assert "kept 12 of the 200004 bytes" in frame[1].comment
    assert all(p.data == b"" for p in frame[2:])


def test_file_reads_back_with_true_lengths(tmp_path: Path) -> None:
    from scapy.utils import rdpcap

    for name in ("c.pcapng", "c.pcap"):
        n = write_capture(tmp_path / name, _fake_trace())
        pkts = rdpcap(str(tmp_path / name))
        assert len(pkts) == n
        big = [p for p in pkts if p.wirelen > len(bytes(p))]
        assert [p.wirelen - 54 for p in big] == [MSS, MSS, MSS, 200_004 - 3 * MSS]


@pytest.fixture(scope="module")
def demo_capture(tmp_path_factory: pytest.TempPathFactory) -> Path:
    from rosfpga_lab.component import run_demo

    path = tmp_path_factory.mktemp("demo") / "demo.pcapng"
    result = run_demo(None, frames=3, rate=30.0, source="synthetic", png=None, pcap=path)
    assert result.ok and result.pcap == path and result.pcap_packets > 0
    return path


def test_tshark_reads_the_xmlrpc_methods_of_the_demo(demo_capture: Path) -> None:
    rows = tshark_fields(demo_capture, ["xml.cdata"], display_filter="http.request")
    methods = {row[0].split("|")[0] for row in rows}
    assert {"registerPublisher", "registerSubscriber", "requestTopic"} <= methods
    replies = tshark_fields(demo_capture, ["http.response.code"], display_filter="http.response")
    assert replies and {r[0] for r in replies} == {"200"}


def test_tshark_reads_tcpros_headers_with_the_image_md5(demo_capture: Path) -> None:
    # The heuristic only recognizes frames (its header test refuses the '=' of "callerid=..."),
    # then marks the connection TCPROS: a second pass (-2) decodes the headers as well.
    rows = tshark_fields(demo_capture, ["tcpros.header_field"], display_filter="tcpros.header",
                         options=["-2", "--enable-heuristic", "tcpros_tcp"])
    fields = [f for row in rows for f in row[0].split("|")]
    # two links (camera -> component, component -> checker), each a request and a reply
    assert fields.count(f"md5sum={IMAGE_MD5}") == 4
    assert "topic=/image_raw" in fields and "type=sensor_msgs/Image" in fields
    # each frame's first segment is a ROS message to tshark; its body is cut (the trace keeps
    # an excerpt), so tshark cannot reassemble it and says so
    frames = tshark_fields(demo_capture, ["_ws.col.Info"], display_filter="tcpros && !tcpros.header",
                           options=["-2", "--enable-heuristic", "tcpros_tcp"])
    assert len(frames) == 6 and all("[ROS Msg]" in row[0] for row in frames)  # 3 in, 3 out


def test_tshark_finds_no_tcp_analysis_warnings(demo_capture: Path, tmp_path: Path) -> None:
    assert tshark_fields(demo_capture, ["frame.number"], display_filter="tcp.analysis.flags") == []
    # the same check does see a broken stream: drop one data segment
    from scapy.utils import PcapNgWriter, rdpcap

    pkts = rdpcap(str(demo_capture))
    victim = next(i for i, p in enumerate(pkts) if p.haslayer("Raw") and i > 10)
    broken = tmp_path / "broken.pcapng"
    with PcapNgWriter(str(broken)) as w:
        for i, p in enumerate(pkts):
            if i != victim:
                w.write(p)
    assert tshark_fields(broken, ["frame.number"], display_filter="tcp.analysis.flags") != []


def test_demo_command_writes_the_capture(tmp_path: Path) -> None:
    import subprocess
    import sys

    out = tmp_path / "demo.pcap"   # classic pcap by its name
    run = subprocess.run([sys.executable, "-m", "rosfpga_lab", "demo", "--frames", "2", "--source",
                          "synthetic", "--no-figure", "--pcap", str(out)],
                         capture_output=True, text=True, timeout=120)
    assert run.returncode == 0, run.stdout + run.stderr
    assert f"capture: {out} (" in run.stdout
    assert out.read_bytes()[:4] == bytes.fromhex("d4c3b2a1")   # pcap magic, little-endian


def test_whole_frames_decode_in_tshark(tmp_path: Path) -> None:
    from rosfpga_lab.component import run_demo

    path = tmp_path / "full.pcapng"
    result = run_demo(None, frames=2, source="synthetic", png=None, pcap=path,
                      pcap_frame_bytes=1_300_000)
    assert result.ok
    rows = tshark_fields(path, ["tcpros.message.length", "tcpros.message.header.frame.value"],
                         display_filter="tcpros.message",
                         options=["-2", "--enable-heuristic", "tcpros_tcp"])
    body = 640 * 480 * 4 + 4 + 8 + 4 + len("camera") + 4 + 4 + 4 + len("rgba8") + 1 + 4 + 4
    assert rows == [[str(body), "camera"]] * 4        # 2 frames in, 2 out, each whole
    assert tshark_fields(path, ["frame.number"],
                         display_filter="tcp.analysis.flags || _ws.expert.severity >= warning") == []


def test_xmlrpc_excerpts_keep_their_true_lengths(tmp_path: Path) -> None:
    tr = Trace(excerpt_bytes=120)
    body = b"<?xml version='1.0'?><methodCall><methodName>getParam</methodName>" + b" " * 500 + b"</methodCall>"
    request = b"POST / HTTP/1.1\r\nContent-Length: %d\r\n\r\n" % len(body) + body
    reply = b"HTTP/1.1 200 OK\r\nContent-Length: 300\r\n\r\n" + b"x" * 300
    tr.record("xmlrpc", "/a", role="client", method="getParam", raw=tr.excerpt(request),
              raw_reply=tr.excerpt(reply), size=len(request) + len(reply),
              local="127.0.0.1:40000", remote="127.0.0.1:11311", t0=1.0)
    data = [p for p in capture_packets(tr) if p.length]
    assert [(p.length, len(p.data)) for p in data] == [(len(request), 120), (len(reply), 120)]
    assert f"kept 120 of the {len(request)} bytes" in data[0].comment
    path = tmp_path / "x.pcapng"
    write_capture(path, tr)
    assert tshark_fields(path, ["frame.number"], display_filter="tcp.analysis.flags") == []
