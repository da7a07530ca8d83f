"""Read a VCD waveform dump into per-clock arrays, one per signal.

How this works: a VCD (IEEE 1364 value change dump) is a header (``$timescale``, ``$scope``,
``$var`` ... ``$enddefinitions``) followed by timestamps (``#t``) each followed by the values
that changed at that time (``1!``, ``b1010 "``, ``r0.5 #``). The reader streams the file in
chunks of bytes and keeps, for every signal, only its *changes*: the clock index from which a new
value holds. Clock ``k`` is the ``k``-th rising edge (``0`` -> ``1``) of the clock signal, and a
signal's value at clock ``k`` is the value it had just *before* that edge: what the flip-flops
sample, so a handshake happened at clock ``k`` exactly when ``tvalid[k]`` and ``tready[k]`` are
both 1. A value written at the very time of an edge (a register's new value, a testbench
driving an input after the edge) belongs to the next clock. The per-clock arrays are filled from
the changes on demand, with numpy::

    from rosfpga_lab.rtl.vcd import read_vcd
    wave = read_vcd("dump.vcd", clock="aclk")
    wave.signals                  # ('tb.dut.aclk', 'tb.dut.m_axis_tdata', ...)
    wave.cycles                   # number of rising clock edges
    tdata = wave.values("m_axis_tdata")   # a unique suffix of a name is enough
    wave.unknown("m_axis_tdata")  # True where any bit was x or z (those bits read as 0)

Values are ``uint64`` for signals up to 64 bits, Python ints (``object`` arrays) for wider ones
and ``float64`` for ``real`` variables.
"""

from __future__ import annotations

import io
from array import array
from collections.abc import Iterable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import BinaryIO

import numpy as np

from rosfpga_lab.rtl.errors import VcdError
from rosfpga_lab.rtl.limits import VCD_MAX_HEADER_BYTES, VCD_MAX_SIGNAL_BITS

#: Bytes read from the file at a time.
CHUNK_BYTES = 1 << 20
#: Longest single token (a value or a keyword).
MAX_TOKEN_BYTES = VCD_MAX_SIGNAL_BITS + 16
_UNITS = {"s": 1.0, "ms": 1e-3, "us": 1e-6, "ns": 1e-9, "ps": 1e-12, "fs": 1e-15}
_SCALAR = frozenset(b"01xXzZ")
_UNKNOWN_BITS = bytes.maketrans(b"xXzZuUwW-", b"000000000")


@dataclass
class _Var:
    """One VCD variable (several names may share one identifier code)."""

    names: list[str]
    width: int
    real: bool
    at: array = field(default_factory=lambda: array("q"))       # clock index of each change
    raw: list[bytes] = field(default_factory=list)              # its value token, decoded late


class Waveform:
    """A dump read by :func:`read_vcd`: per-clock values of its signals.

    Attributes:
        signals: full hierarchical names (``scope.sub.name``), in the dump's order.
        clock: the full name of the clock signal.
        timescale: seconds per time unit of the dump.
        timescale_text: the dump's ``$timescale`` as written (``"1ps"``).
        times: time of every rising clock edge, in time units (``int64``).
    """

    def __init__(self, variables: dict[bytes, _Var], clock: str, timescale: float,
                 timescale_text: str, times: np.ndarray, where: str = "<vcd>") -> None:
        self._where = where
        self._by_name: dict[str, _Var] = {}
        for var in variables.values():
            for name in var.names:
                self._by_name[name] = var
        self.signals: tuple[str, ...] = tuple(self._by_name)
        self.clock = clock
        self.timescale = timescale
        self.timescale_text = timescale_text
        self.times = times
        self._cache: dict[str, tuple[np.ndarray, np.ndarray]] = {}

    @property
    def cycles(self) -> int:
        """Number of rising clock edges in the dump (the length of every array)."""
        return int(self.times.shape[0])

    @property
    def period(self) -> float | None:
        """The clock period in seconds (median edge spacing), None with fewer than two edges."""
        if self.cycles < 2:
            return None
        return float(np.median(np.diff(self.times))) * self.timescale

    def resolve(self, name: str) -> str:
        """The full name of ``name``: itself, or the one signal whose name ends with ``.name``.

        Raises:
            VcdError: no signal or several signals match.
        """
        if name in self._by_name:
            return name
        found = [s for s in self.signals if s.endswith("." + name)]
        if len(found) == 1:
            return found[0]
        if not found:
            raise VcdError(f"no signal {name!r} in the dump ({len(self.signals)} signals, e.g. "
                           f"{', '.join(self.signals[:5])})")
        raise VcdError(f"{name!r} is ambiguous: {', '.join(found[:8])}; give the full name")

    def width(self, name: str) -> int:
        """Bits of signal ``name`` (64 for a ``real``)."""
        return self._by_name[self.resolve(name)].width

    def values(self, name: str) -> np.ndarray:
        """The value of ``name`` at every clock (just before each rising edge).

        x and z bits read as 0; see :meth:`unknown`. Before its first value a signal reads 0
        and unknown.

        Raises:
            VcdError: no such signal, or one of its values in the dump is malformed (values
                are decoded on first use, so only the signals asked for cost time).
        """
        return self._arrays(name)[0]

    def unknown(self, name: str) -> np.ndarray:
        """``bool`` per clock: some bit of ``name`` was x or z (or it had no value yet)."""
        return self._arrays(name)[1]

    def _arrays(self, name: str) -> tuple[np.ndarray, np.ndarray]:
        full = self.resolve(name)
        if full not in self._cache:
            var = self._by_name[full]
            at = np.frombuffer(var.at, dtype=np.int64) if len(var.at) else np.zeros(0, np.int64)
            vals, unk = _decode(var, self._where)
            # the last change at or before clock k holds at clock k
            pos = np.searchsorted(at, np.arange(self.cycles), side="right") - 1
            have = pos >= 0
            if var.real:
                out = np.zeros(self.cycles, np.float64)
            elif var.width <= 64:
                out = np.zeros(self.cycles, np.uint64)
            else:
                out = np.zeros(self.cycles, dtype=object)
            out[have] = vals[pos[have]]
            unknown = np.ones(self.cycles, bool)
            unknown[have] = unk[pos[have]]
            self._cache[full] = (out, unknown)
        return self._cache[full]


def read_vcd(source: str | Path | BinaryIO | bytes, clock: str = "aclk",
             signals: Iterable[str] | None = None) -> Waveform:
    """Read a VCD dump, sampling every signal at the rising edges of ``clock``.

    Args:
        source: a file path, an open binary file, or the dump's bytes.
        clock: name (or unique name suffix) of the clock signal.
        signals: keep only these (names or unique suffixes; the clock is always kept);
            None keeps all. Keeping few signals makes large dumps faster to read.

    Raises:
        VcdError: the file cannot be read, is not a VCD, has no such clock or signal, or
            exceeds the reader's limits.
    """
    if isinstance(source, (bytes, bytearray)):
        return _read(io.BytesIO(source), clock, signals, "<bytes>")
    if isinstance(source, (str, Path)):
        try:
            with open(source, "rb") as stream:
                return _read(stream, clock, signals, str(source))
        except OSError as exc:
            raise VcdError(f"cannot read {source}: {exc.strerror or exc}") from None
    return _read(source, clock, signals, getattr(source, "name", "<stream>"))


def _token_batches(stream: BinaryIO, where: str) -> Iterator[list[bytes]]:
    """Whitespace-separated tokens, a chunk's worth per list, never split across chunks."""
    rest = b""
    while True:
        data = stream.read(CHUNK_BYTES)
        if not data:
            if rest:
                yield rest.split()
            return
        data = rest + data
        cut = max(data.rfind(b" "), data.rfind(b"\n"), data.rfind(b"\t"), data.rfind(b"\r"))
        if cut < 0:
            if len(data) > MAX_TOKEN_BYTES:
                raise VcdError(f"{where}: a token longer than {MAX_TOKEN_BYTES} bytes")
            rest = data
            continue
        rest = data[cut + 1:]
        yield data[:cut + 1].split()


def _read(stream: BinaryIO, clock: str, wanted: Iterable[str] | None, where: str) -> Waveform:
    batches = _token_batches(stream, where)
    header: list[bytes] = []
    header_bytes = 0
    tail: list[bytes] = []
    for batch in batches:
        try:
            end = batch.index(b"$enddefinitions")
        except ValueError:
            header.extend(batch)
            header_bytes += sum(len(t) + 1 for t in batch)
            if header_bytes > VCD_MAX_HEADER_BYTES:
                raise VcdError(f"{where}: no $enddefinitions in the first {VCD_MAX_HEADER_BYTES} "
                               "bytes: not a VCD dump?") from None
            continue
        header.extend(batch[:end])
        tail = batch[end + 1:]
        break
    else:
        raise VcdError(f"{where}: no $enddefinitions: not a VCD dump (or an empty file)")
    if tail and tail[0] == b"$end":
        tail = tail[1:]
    variables, timescale, ts_text = _parse_header(header, where)
    clock_id, clock_name = _pick_clock(variables, clock, where)
    if wanted is not None:
        keep = {clock_id}
        for name in wanted:
            keep.add(_find(variables, name, where)[0])
        variables = {code: var for code, var in variables.items() if code in keep}
    times = _parse_changes(_chain(tail, batches), variables, clock_id, where)
    return Waveform(variables, clock_name, timescale, ts_text, times, where)


def _chain(first: list[bytes], rest: Iterator[list[bytes]]) -> Iterator[list[bytes]]:
    yield first
    yield from rest


def _parse_header(tokens: list[bytes], where: str) -> tuple[dict[bytes, _Var], float, str]:
    variables: dict[bytes, _Var] = {}
    scopes: list[str] = []
    timescale, ts_text = 1e-9, "1ns"       # the IEEE default when a dump names none
    i, n = 0, len(tokens)

    def until_end(start: int) -> tuple[list[bytes], int]:
        try:
            stop = tokens.index(b"$end", start)
        except ValueError:
            raise VcdError(f"{where}: {tokens[start - 1].decode(errors='replace')} without "
                           "$end in the header") from None
        return tokens[start:stop], stop + 1

    while i < n:
        tok = tokens[i]
        if tok == b"$scope":
            body, i = until_end(i + 1)
            scopes.append(body[-1].decode(errors="replace") if body else "?")
        elif tok == b"$upscope":
            _, i = until_end(i + 1)
            if scopes:
                scopes.pop()
        elif tok == b"$var":
            body, i = until_end(i + 1)
            if len(body) < 4:
                raise VcdError(f"{where}: malformed $var: {b' '.join(body).decode(errors='replace')}")
            kind, size, code, ref = body[0], body[1], body[2], body[3].decode(errors="replace")
            if len(body) > 4 and not body[4].startswith(b"["):
                ref += body[4].decode(errors="replace")
            try:
                width = int(size)
            except ValueError:
                raise VcdError(f"{where}: $var {ref} has size {size!r}") from None
            if not 1 <= width <= VCD_MAX_SIGNAL_BITS:
                raise VcdError(f"{where}: $var {ref} is {width} bits wide; the reader keeps "
                               f"1..{VCD_MAX_SIGNAL_BITS}")
            real = kind in (b"real", b"realtime")
            name = ".".join(scopes + [ref])
            var = variables.get(code)
            if var is None:
                variables[code] = _Var([name], 64 if real else width, real)
            else:
                var.names.append(name)
        elif tok == b"$timescale":
            body, i = until_end(i + 1)
            ts_text = b"".join(body).decode(errors="replace")
            timescale = _timescale(ts_text, where)
        elif tok.startswith(b"$"):
            _, i = until_end(i + 1)         # $date, $version, $comment, ...
        else:
            raise VcdError(f"{where}: unexpected {tok[:40].decode(errors='replace')!r} in the "
                           "header")
    if not variables:
        raise VcdError(f"{where}: the dump declares no signals")
    return variables, timescale, ts_text


def _timescale(text: str, where: str) -> float:
    digits = text.rstrip("munpfs")
    unit = text[len(digits):]
    if digits not in ("1", "10", "100") or unit not in _UNITS:
        raise VcdError(f"{where}: timescale {text!r} is not 1, 10 or 100 s/ms/us/ns/ps/fs")
    return int(digits) * _UNITS[unit]


def _find(variables: dict[bytes, _Var], name: str, where: str) -> tuple[bytes, str]:
    exact = [(code, n) for code, var in variables.items() for n in var.names if n == name]
    if exact:
        return exact[0]
    found = [(code, n) for code, var in variables.items() for n in var.names
             if n.endswith("." + name)]
    if len(found) == 1 or (found and len({code for code, _ in found}) == 1):
        return found[0]
    if not found:
        raise VcdError(f"{where}: no signal {name!r} in the dump")
    raise VcdError(f"{where}: {name!r} is ambiguous: {', '.join(n for _, n in found[:8])}")


def _pick_clock(variables: dict[bytes, _Var], clock: str, where: str) -> tuple[bytes, str]:
    code, name = _find(variables, clock, where)
    var = variables[code]
    if var.width != 1 or var.real:
        raise VcdError(f"{where}: the clock {name} is {var.width} bits wide, not one bit")
    return code, name


def _parse_changes(batches: Iterator[list[bytes]], variables: dict[bytes, _Var],
                   clock_id: bytes, where: str) -> np.ndarray:
    edges = array("q")
    clock_now = -1              # 0, 1, or -1 for x/z/not yet
    clock_next = -1
    pending: list[tuple[bytes, bytes]] = []   # (code, value token) changes at this time
    time = 0
    vector = b""                # a 'b...' or 'r...' token waiting for its identifier code
    in_comment = False

    def close_time() -> None:
        nonlocal clock_now
        if clock_now == 0 and clock_next == 1:
            edges.append(time)
        clock_now = clock_next
        index = len(edges)
        for code, value in pending:     # several changes before one clock: the last one holds
            var = variables[code]
            var.at.append(index)
            var.raw.append(value)
        pending.clear()

    for batch in batches:
        for tok in batch:
            if vector:
                if tok in variables:
                    pending.append((tok, vector))
                vector = b""
                continue
            if in_comment:
                in_comment = tok != b"$end"
                continue
            first = tok[0]
            if first == 35:                                       # '#'
                close_time()
                try:
                    time = int(tok[1:])
                except ValueError:
                    raise VcdError(f"{where}: bad timestamp {tok[:40]!r}") from None
            elif first in _SCALAR:
                code = tok[1:]
                if code == clock_id:
                    clock_next = 1 if first == 49 else 0 if first == 48 else -1
                if code in variables:
                    pending.append((code, tok[:1]))
            elif first in (98, 66, 114, 82):                      # b B r R
                vector = tok
            elif first == 36:                                     # '$'
                in_comment = tok == b"$comment"
            else:
                raise VcdError(f"{where}: unexpected {tok[:40].decode(errors='replace')!r} "
                               f"after time {time}")
    close_time()
    return np.frombuffer(edges, dtype=np.int64).copy() if len(edges) else np.zeros(0, np.int64)


def _decode(var: _Var, where: str) -> tuple[np.ndarray, np.ndarray]:
    """The values of ``var``'s changes and whether each had x or z bits."""
    n = len(var.raw)
    unknown = np.zeros(n, bool)
    if var.real:
        values = np.empty(n, np.float64)
        for i, token in enumerate(var.raw):
            try:
                values[i] = float(token[1:]) if token[:1] in (b"r", b"R") else float("nan")
            except ValueError:
                raise VcdError(f"{where}: bad real value {token[:40]!r} for "
                               f"{var.names[0]}") from None
        return values, unknown
    numbers: list[int] = []
    flags: list[bool] = []
    mask = (1 << var.width) - 1
    seen: dict[bytes, tuple[int, bool]] = {}      # most tokens repeat (0, 1, a few states)
    for token in var.raw:
        known = seen.get(token)
        if known is None:
            if token[:1] in (b"r", b"R"):
                raise VcdError(f"{where}: a real value for the {var.width}-bit {var.names[0]}")
            bits = token[1:] if token[:1] in (b"b", b"B") else token
            clean = bits.translate(_UNKNOWN_BITS)
            try:
                known = ((int(clean, 2) if clean else 0) & mask, clean != bits)
            except ValueError:
                raise VcdError(f"{where}: bad value {token[:40]!r} for {var.names[0]}") from None
            if len(seen) < 4096:
                seen[token] = known
        numbers.append(known[0])
        flags.append(known[1])
    unknown = np.array(flags, dtype=bool)
    if var.width <= 64:
        return np.array(numbers, dtype=np.uint64), unknown
    values = np.empty(n, dtype=object)
    values[:] = numbers
    return values, unknown
