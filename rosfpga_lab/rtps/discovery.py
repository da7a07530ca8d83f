"""Discovery without a master (SPDP/SEDP parameter lists), and DATA_FRAG reassembly.

How this works: DDS participants announce themselves (SPDP, on the built-in participant
writer) and their readers and writers (SEDP, on the built-in publications/subscriptions
writers) as DATA samples whose payload is a *parameter list*: a 4-byte encapsulation header
(``00 03`` PL_CDR_LE or ``00 02`` PL_CDR_BE), then (pid uint16, length uint16, value padded to
4 bytes) entries up to PID_SENTINEL. :func:`discovery` reads them from decoded messages and
names the participants, topics and types; no master is involved.
"""

from __future__ import annotations

import struct
from collections.abc import Iterable
from dataclasses import dataclass

from rosfpga_lab.msg.typehash import RIHS_PATTERN
from rosfpga_lab.rtps.build import (
    PID_ENDPOINT_GUID, PID_ENTITY_NAME, PID_PARTICIPANT_GUID, PID_SENTINEL, PID_TOPIC_NAME,
    PID_TYPE_NAME, PID_USER_DATA, TYPEHASH_KEY, USER_DATA_KEY_END, USER_DATA_PAIR_END,
)
from rosfpga_lab.rtps.entities import PUB_WRITER, SPDP_WRITER, SUB_WRITER
from rosfpga_lab.rtps.errors import RtpsError, RtpsTruncatedError
from rosfpga_lab.rtps.limits import MAX_PENDING_BYTES, MAX_PENDING_SAMPLES, MAX_SAMPLE_BYTES
from rosfpga_lab.rtps.message import Data, DataFrag, RtpsMessage

SEDP_PUBLICATIONS_WRITER, SEDP_SUBSCRIPTIONS_WRITER = PUB_WRITER, SUB_WRITER
PL_CDR_BE, PL_CDR_LE = b"\x00\x02", b"\x00\x03"


def parse_parameters(payload: bytes) -> dict[int, list[bytes]]:
    """A parameter list payload (encapsulation header first) as ``{pid: [values]}``.

    Raises:
        RtpsError: not a parameter list; RtpsTruncatedError: it ends before PID_SENTINEL.
    """
    kind = payload[:2]
    if kind not in (PL_CDR_BE, PL_CDR_LE):
        raise RtpsError(f"not a parameter list: encapsulation {payload[:4].hex(' ')}", 0)
    order = "<" if kind == PL_CDR_LE else ">"
    out: dict[int, list[bytes]] = {}
    pos = 4
    while True:
        if pos + 4 > len(payload):
            raise RtpsTruncatedError(f"parameter list ends at byte {len(payload)} without "
                                     f"PID_SENTINEL", pos)
        pid, length = struct.unpack(order + "HH", payload[pos:pos + 4])
        if pid == PID_SENTINEL:
            return out
        if pos + 4 + length > len(payload):
            raise RtpsTruncatedError(f"parameter 0x{pid:04x} at byte {pos} declares {length} "
                                     f"bytes, only {len(payload) - pos - 4} left", pos)
        out.setdefault(pid & 0x3FFF if not pid & 0x8000 else pid, []).append(
            payload[pos + 4:pos + 4 + length])
        pos += 4 + length


def _string(value: bytes, little: bool) -> str:
    (n,) = struct.unpack("<I" if little else ">I", value[:4])
    return value[4:4 + n].rstrip(b"\x00").decode("utf-8", "replace")


def user_data_pairs(value: bytes, little: bool = True) -> dict[str, str]:
    """The ``key=value;`` pairs of a USER_DATA parameter value (a ``sequence<octet>``), as
    rmw's ``parse_key_value`` reads them: an item without ``=`` or with an empty key is skipped,
    a count past the value's end is cut to the bytes there; {} when it is no such text."""
    if len(value) < 4:
        return {}
    (n,) = struct.unpack("<I" if little else ">I", value[:4])
    text = value[4:4 + n].decode("utf-8", "replace")
    out: dict[str, str] = {}
    for item in text.split(USER_DATA_PAIR_END):
        key, sep, val = item.partition(USER_DATA_KEY_END)
        if sep and key:
            out[key] = val
    return out


def user_data_type_hash(value: bytes, little: bool = True) -> str:
    """The ROS 2 type hash (``RIHS01_...``) an endpoint's USER_DATA announces; '' when it
    announces none (Humble, plain DDS) or a malformed one."""
    found = user_data_pairs(value, little).get(TYPEHASH_KEY, "")
    return found if RIHS_PATTERN.fullmatch(found) else ""


@dataclass(frozen=True)
class Participant:
    """A participant announced by SPDP: GUID prefix (12 bytes) and name when it gave one."""

    guid_prefix: bytes
    name: str = ""


@dataclass(frozen=True)
class Endpoint:
    """A reader or writer announced by SEDP."""

    guid: bytes
    kind: str            # "writer" or "reader"
    topic: str
    type_name: str
    type_hash: str = ""      # ROS 2 (Iron and later): RIHS01_... from USER_DATA, else ''


def discovery(messages: Iterable[RtpsMessage]) -> tuple[list[Participant], list[Endpoint]]:
    """Participants (SPDP) and endpoints (SEDP) announced in ``messages``, each once."""
    participants: dict[bytes, Participant] = {}
    endpoints: dict[bytes, Endpoint] = {}
    for msg in messages:
        for source, _destination, sub in msg.routed():
            if not isinstance(sub, Data) or not sub.payload or sub.key:
                continue
            if sub.writer_id not in (SPDP_WRITER, SEDP_PUBLICATIONS_WRITER, SEDP_SUBSCRIPTIONS_WRITER):
                continue
            try:
                params = parse_parameters(sub.payload)
            except RtpsError:
                continue
            little = sub.payload[:2] == PL_CDR_LE
            if sub.writer_id == SPDP_WRITER:
                guid = (params.get(PID_PARTICIPANT_GUID) or [source])[0][:12]
                name = params.get(PID_ENTITY_NAME)
                participants[guid] = Participant(guid, _string(name[0], little) if name else "")
            elif PID_TOPIC_NAME in params and PID_ENDPOINT_GUID in params:
                guid = params[PID_ENDPOINT_GUID][0][:16]
                kind = "writer" if sub.writer_id == SEDP_PUBLICATIONS_WRITER else "reader"
                endpoints[guid] = Endpoint(guid, kind, _string(params[PID_TOPIC_NAME][0], little),
                                           _string(params[PID_TYPE_NAME][0], little)
                                           if PID_TYPE_NAME in params else "",
                                           user_data_type_hash(params[PID_USER_DATA][0], little)
                                           if PID_USER_DATA in params else "")
    return list(participants.values()), list(endpoints.values())


class FragmentAssembler:
    """Puts DATA_FRAG fragments back together into whole serialized samples.

    Memory follows the fragments received: a sample's buffer grows as fragments arrive, and a
    sample may declare at most ``max_sample_bytes``; at most ``max_pending`` samples are held
    (the oldest is dropped and counted in ``dropped``).
    """

    def __init__(self, max_sample_bytes: int = MAX_SAMPLE_BYTES,
                 max_pending: int = MAX_PENDING_SAMPLES,
                 max_pending_bytes: int = MAX_PENDING_BYTES) -> None:
        self.max_sample_bytes = max_sample_bytes
        self.max_pending = max_pending
        self.max_pending_bytes = max_pending_bytes
        self.dropped = 0
        #: Bytes of fragments held now (what was received, never what a sample declares).
        self.held = 0
        self._pending: dict[tuple[bytes, int, int], dict[int, bytes]] = {}
        self._total: dict[tuple[bytes, int, int], int] = {}

    def _drop(self, key: tuple[bytes, int, int]) -> None:
        parts = self._pending.pop(key, {})
        self._total.pop(key, None)
        self.held -= sum(len(p) for p in parts.values())

    def discard(self, guid_prefix: bytes, writer_id: int, seq: int) -> None:
        """Forget a partly received sample (it was delivered whole, or will never come)."""
        self._drop((guid_prefix, writer_id, seq))

    def missing(self, guid_prefix: bytes, writer_id: int, seq: int, last: int = 0,
                limit: int = 256) -> list[int]:
        """The first ``limit`` fragment numbers of a partly received sample not yet here (up to
        ``last`` if given); [] for a sample with no fragment here. The work is bounded by the
        fragments received plus ``limit``, never by the count the sample declares."""
        key = (guid_prefix, writer_id, seq)
        if key not in self._pending:
            return []
        total = self._total[key] if not last else min(last, self._total[key])
        parts = self._pending[key]
        out: list[int] = []
        n = 1
        while n <= total and len(out) < limit:
            if n not in parts:
                out.append(n)
            n += 1
        return out

    def partial(self, guid_prefix: bytes, writer_id: int) -> list[int]:
        """Sequence numbers of ``writer_id``'s partly received samples."""
        return [k[2] for k in self._pending if k[0] == guid_prefix and k[1] == writer_id]

    def add(self, guid_prefix: bytes, frag: DataFrag) -> bytes | None:
        """Add one DATA_FRAG; return the whole sample once its last missing fragment came."""
        if frag.sample_size > self.max_sample_bytes:
            raise RtpsError(f"DATA_FRAG at byte {frag.offset} declares a {frag.sample_size}-byte "
                            f"sample, more than max_sample_bytes={self.max_sample_bytes}",
                            frag.offset)
        if frag.frag_size == 0:
            raise RtpsError(f"DATA_FRAG at byte {frag.offset} has fragment size 0", frag.offset)
        total = -(-frag.sample_size // frag.frag_size)
        key = (guid_prefix, frag.writer_id, frag.seq)
        if key in self._total and self._total[key] != total:
            self._drop(key)                # the sample changed shape: start again
        parts = self._pending.setdefault(key, {})
        self._total[key] = total
        while len(self._pending) > self.max_pending:
            self._drop(next(iter(self._pending)))
            self.dropped += 1
        for i in range(min(frag.frag_count, -(-len(frag.payload) // frag.frag_size))):
            number = frag.frag_start + i
            if 1 <= number <= total and number not in parts:   # numbers past the end ignored
                chunk = frag.payload[i * frag.frag_size:(i + 1) * frag.frag_size]
                parts[number] = chunk
                self.held += len(chunk)
        while self.held > self.max_pending_bytes and self._pending:
            oldest = next(iter(self._pending))
            self._drop(oldest)
            self.dropped += 1
            if oldest == key:
                return None
        if key not in self._pending or len(parts) < total:
            return None
        self._drop(key)
        sample = b"".join(parts[n] for n in range(1, total + 1))[:frag.sample_size]
        if len(sample) != frag.sample_size:
            raise RtpsError(f"sample {frag.seq} reassembled to {len(sample)} bytes, it declared "
                            f"{frag.sample_size}", frag.offset)
        return sample
