"""ROS 1 bag files without ROS: read and write them with the ``rosbags`` library.

The lab keeps its own codecs: a bag holds serialized bodies, and each connection of a bag holds
the type, md5 sum and full definition text (what a TCPROS header carries), so reading gives
raw bodies with that information and writing takes them. Debian's ``rosbag info``/``play``
read what :class:`BagWriter` writes (tests/msg/test_bag.py).
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from rosfpga_lab.msg.errors import MsgError


@dataclass(frozen=True)
class BagMessage:
    """One message of a bag: where, what type, when (ns since the epoch) and its body."""

    topic: str
    type_name: str      # pkg/Name
    md5sum: str
    definition: str     # the full text (message_definition)
    time_ns: int
    body: bytes


def _rosbag1() -> Any:
    try:
        from rosbags import rosbag1
    except ImportError:  # pragma: no cover - a runtime dependency
        raise MsgError("reading and writing bags needs the rosbags package "
                       "(pip install rosbags; it is in the lab's environment.txt)") from None
    return rosbag1


def _ros1_name(msgtype: str) -> str:
    parts = msgtype.split("/")
    return f"{parts[0]}/{parts[-1]}" if len(parts) == 3 and parts[1] == "msg" else msgtype


def bag_topics(path: str | Path) -> dict[str, str]:
    """topic -> type of every connection of the bag at ``path``.

    Raises:
        MsgError: not a readable ROS 1 bag.
    """
    rosbag1 = _rosbag1()
    try:
        with rosbag1.Reader(Path(path)) as reader:
            return {c.topic: _ros1_name(c.msgtype) for c in reader.connections}
    except (rosbag1.ReaderError, OSError) as exc:
        raise MsgError(f"{path}: not a readable ROS 1 bag ({exc})") from None


def read_bag(path: str | Path, topics: list[str] | None = None) -> Iterator[BagMessage]:
    """The messages of the bag at ``path`` in time order (only ``topics`` when given).

    Raises:
        MsgError: not a readable ROS 1 bag.
    """
    rosbag1 = _rosbag1()
    try:
        with rosbag1.Reader(Path(path)) as reader:
            conns = [c for c in reader.connections if topics is None or c.topic in topics]
            for conn, t_ns, raw in reader.messages(connections=conns):
                yield BagMessage(conn.topic, _ros1_name(conn.msgtype), conn.digest,
                                 conn.msgdef.data, int(t_ns), bytes(raw))
    except (rosbag1.ReaderError, OSError) as exc:
        raise MsgError(f"{path}: not a readable ROS 1 bag ({exc})") from None


class BagWriter:
    """Write messages to a new ROS 1 bag (a context manager; refuses to overwrite a file).

    Example::

        with BagWriter(tmp / "x.bag") as bag:
            bag.write("/chatter", "std_msgs/String", reg.md5("std_msgs/String"),
                      reg.full_text("std_msgs/String"), time.time_ns(), body)
    """

    def __init__(self, path: str | Path) -> None:
        rosbag1 = _rosbag1()
        self.path = Path(path)
        self.count = 0
        self._errors = (rosbag1.WriterError, OSError)
        self._conns: dict[tuple[str, str, str], Any] = {}
        try:
            self._writer = rosbag1.Writer(self.path)
            self._writer.open()
        except self._errors as exc:
            raise MsgError(f"cannot write the bag {self.path}: {exc}") from None

    def write(self, topic: str, type_name: str, md5sum: str, definition: str, time_ns: int,
              body: bytes | memoryview, callerid: str | None = None) -> None:
        """Add one message (its connection is added on first use)."""
        key = (topic, type_name, md5sum)
        conn = self._conns.get(key)
        try:
            if conn is None:
                pkg, _, name = type_name.rpartition("/")  # rosbags names types pkg/msg/Name
                conn = self._writer.add_connection(topic, f"{pkg}/msg/{name}", msgdef=definition,
                                                   md5sum=md5sum, callerid=callerid)
                self._conns[key] = conn
            self._writer.write(conn, int(time_ns), bytes(body))
        except self._errors as exc:
            raise MsgError(f"cannot write to the bag {self.path}: {exc}") from None
        self.count += 1

    def close(self) -> None:
        """Write the index and close the file."""
        try:
            self._writer.close()
        except self._errors as exc:
            raise MsgError(f"cannot finish the bag {self.path}: {exc}") from None

    def __enter__(self) -> "BagWriter":
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
