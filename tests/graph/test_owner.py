"""A node never silently joins another Unix user's master (a course server shares loopback)."""

from __future__ import annotations

import os
import socket
import sys

import pytest

import rosfpga_lab.graph.node as node_mod
from rosfpga_lab.graph import EmbeddedMaster
from rosfpga_lab.graph.owner import listener_uids, parse_tcp_table

# Two lines of a real /proc/net/tcp: uid 1000 listens on 127.0.0.1:11311 (0x2C2F), uid 0 has
# an established connection from port 11311 (st 01), which is not a listener.
TABLE = """\
  sl  local_address rem_address   st tx_queue rx_queue tr tm->when retrnsmt   uid  timeout inode
   0: 0100007F:2C2F 00000000:0000 0A 00000000:00000000 00:00000000 00000000  1000        0 27952 1
   1: 0100007F:2C2F 0100007F:D2A4 01 00000000:00000000 00:00000000 00000000     0        0 27953 1
   2: garbage
"""
TABLE6 = """\
  sl  local_address                         remote_address                        st tx_queue rx_queue tr tm->when retrnsmt   uid  timeout inode
   0: 00000000000000000000000001000000:2C2F 00000000000000000000000000000000:0000 0A 00000000:00000000 00:00000000 00000000  1001        0 1 1
"""


def test_parse_tcp_table_finds_listeners_only() -> None:
    assert parse_tcp_table(TABLE, 11311) == {1000}
    assert parse_tcp_table(TABLE6, 11311) == {1001}
    assert parse_tcp_table(TABLE, 11312) == set()
    assert parse_tcp_table("", 11311) == set()


def test_listener_uids_reads_both_tables_and_knows_when_it_cannot(tmp_path) -> None:
    (tmp_path / "tcp").write_text(TABLE)
    (tmp_path / "tcp6").write_text(TABLE6)
    assert listener_uids(11311, (tmp_path / "tcp", tmp_path / "tcp6")) == {1000, 1001}
    assert listener_uids(11311, (tmp_path / "missing",)) is None


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="/proc/net/tcp is Linux's")
def test_listener_uids_sees_this_process_listening() -> None:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        port = sock.getsockname()[1]
        assert listener_uids(port) == set()          # bound, not yet listening
        sock.listen(1)
        assert listener_uids(port) == {os.geteuid()}


def test_another_users_master_on_the_default_port_is_not_joined(monkeypatch) -> None:
    monkeypatch.delenv("ROS_MASTER_URI", raising=False)
    with EmbeddedMaster(port=0) as theirs:
        port = int(theirs.uri.rsplit(":", 1)[1].strip("/"))
        monkeypatch.setattr(node_mod, "DEFAULT_MASTER_PORT", port)
        monkeypatch.setattr(node_mod, "listener_uids", lambda p: {os.geteuid() + 1})
        try:
            with pytest.warns(RuntimeWarning, match="belongs to another user"):
                uri = node_mod.default_master_uri()
            assert uri != theirs.uri and uri == node_mod._shared.uri
        finally:
            node_mod.stop_shared_master()
        # the same master, run by this user, is joined as before
        monkeypatch.setattr(node_mod, "listener_uids", lambda p: {os.geteuid()})
        assert node_mod.default_master_uri() == theirs.uri
