"""A real Cyclone DDS peer of the simulated fabric (PyPI ``cyclonedds``), started one way for
every fabric test: configured as the fabric's peers need (``component.fabricsim``'s
``fabric_peer_uri``: the lab's loopback configuration with datagrams of one Ethernet frame, or
``fabric_tap_peer_uri`` over the TAP interface), with ROS 2's default QoS, matched with the
fabric's node before it is used, and deleted (its goodbye sent) when done.

In this process: :func:`fabric_cyclone` and :class:`CyclonePeer`; in a child process (a
participant only, whose announcement and goodbye a test captures): :func:`fabric_participant`.
"""

from __future__ import annotations

import gc
import importlib.util
import os
import subprocess
import sys
import time
from collections.abc import Callable, Iterable
from typing import Any

import pytest

from rosfpga_lab.component.fabricsim import fabric_peer_uri
from tests.support.realros import skip_or_fail
from tests.support.ros2tools import cyclone, qos, wait

#: Seconds a peer waits for its writer and reader to match the fabric's node.
MATCH_SECONDS = 15.0

_PARTICIPANT = """
import gc, sys, time
from cyclonedds.domain import DomainParticipant
dp = DomainParticipant(int(sys.argv[1]))
time.sleep(float(sys.argv[2]))
del dp       # deleting the participant sends its goodbye
gc.collect()
time.sleep(1.0)
"""


def fabric_cyclone(monkeypatch: pytest.MonkeyPatch, uri: str | None = None) -> Any:
    """:func:`~tests.support.ros2tools.cyclone`'s modules and types (skip without cyclonedds),
    with ``CYCLONEDDS_URI`` for a peer of the fabric for this test: ``uri``, else
    ``fabric_peer_uri()``."""
    dds = cyclone()
    monkeypatch.setenv("CYCLONEDDS_URI", uri or fabric_peer_uri())
    return dds


class CyclonePeer:
    """A Cyclone DDS participant of ``domain`` writing ``topic_in`` and reading ``topic_out`` of
    ``kind`` with ROS 2's default QoS, matched with the fabric's node (``log``: what the fabric
    said, for a failure's message); :meth:`close` (or leaving the ``with`` block) deletes it,
    which says goodbye (the next test's peer is its own)."""

    def __init__(self, dds: Any, domain: int, topic_in: str, topic_out: str, kind: Any,
                 log: Callable[[], str]) -> None:
        self.log = log
        self.dp = dds.DomainParticipant(domain)
        self.writer = dds.DataWriter(self.dp, dds.Topic(self.dp, topic_in, kind), qos=qos(dds))
        self.reader = dds.DataReader(self.dp, dds.Topic(self.dp, topic_out, kind), qos=qos(dds))
        assert wait(lambda: self.writer.get_matched_subscriptions()
                    and self.reader.get_matched_publications(), MATCH_SECONDS), log()

    def __enter__(self) -> CyclonePeer:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def send(self, samples: Iterable[Any], gap: float) -> None:
        """Write each sample, ``gap`` seconds apart (a sensor's rate: back to back at line rate
        they overflow the circuit's receive buffer)."""
        for sample in samples:
            self.writer.write(sample)
            time.sleep(gap)

    def take(self, n: int, timeout: float) -> list:
        """``n`` samples from the reader, within ``timeout`` seconds."""
        got: list = []
        assert wait(lambda: got.extend(self.reader.take(10)) or len(got) >= n, timeout), \
            (len(got), self.log())
        return got

    def close(self) -> None:
        """Delete the participant (its goodbye goes out); again: nothing."""
        if hasattr(self, "dp"):
            del self.writer, self.reader, self.dp
            gc.collect()


def fabric_participant(domain: int, seconds: float, lease_seconds: float) -> subprocess.Popen:
    """A Cyclone DDS participant of ``domain`` in a child process, configured as the fabric's
    peers are (``fabric_peer_uri(lease_seconds)``): it announces itself, lives ``seconds`` and
    is deleted, which sends its goodbye (skip, or fail under ``ROSFPGA_REQUIRE_ROS2``, without
    cyclonedds)."""
    if importlib.util.find_spec("cyclonedds") is None:
        skip_or_fail("cyclonedds not installed (pip install cyclonedds)", "ROSFPGA_REQUIRE_ROS2")
    env = dict(os.environ, CYCLONEDDS_URI=fabric_peer_uri(lease_seconds=lease_seconds))
    return subprocess.Popen([sys.executable, "-c", _PARTICIPANT, str(domain), str(seconds)],
                            env=env)
