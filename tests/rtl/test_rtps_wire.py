"""One owner for the RTPS wire vocabulary of the fabric's Verilog stages.

``rtl/fabric/rfl_rtps_wire.vh`` (written by hand: a dozen constants, read by people next to the
stages) declares the submessage ids, the header's magic, version and vendor id, and the
little-endian flag. The software participant owns each value (:mod:`rosfpga_lab.rtps.build`,
``rosfpga_lab.rtps.message.MAGIC``): every localparam equals its owner's constant by name, and no
fabric module writes one of them as a hex literal of its own (a new literal fails here).
"""

from __future__ import annotations

import re

import pytest

from rosfpga_lab.rtl.proofs import FABRIC_DIR, FABRIC_INCLUDES
from rosfpga_lab.rtps import build
from rosfpga_lab.rtps.message import MAGIC

WIRE = FABRIC_DIR / "rfl_rtps_wire.vh"
IDS = ("PAD", "ACKNACK", "HEARTBEAT", "INFO_TS", "INFO_SRC", "INFO_DST", "DATA", "DATA_FRAG")
#: the stages that include the header (they walk or write RTPS messages)
STAGES = ("rfl_rtps_walk.v", "rfl_rtps_rx.v", "rfl_rtps_ctrl.v", "rfl_rtps_tx.v",
          "rfl_spdp_peer.v")


def _owners() -> dict[str, int]:
    """Each localparam's value, from the software participant's constants."""
    major, minor = build.PROTOCOL_VERSION
    return {**{f"ID_{name}": getattr(build, name) for name in IDS},
            "RTPS_MAGIC": int.from_bytes(MAGIC, "big"), "RTPS_VERSION": major << 8 | minor,
            "RTPS_VENDOR": build.VENDOR_ID, "FLAG_E": build.FLAG_LE}


def _declared(text: str) -> dict[str, tuple[int, int]]:
    """``name -> (width, value)`` of the ``localparam [W-1:0] NAME = W'hV`` entries."""
    found: dict[str, tuple[int, int]] = {}
    for decl in re.finditer(r"localparam\s*\[(\d+):0\]([^;]*);", text):
        width = int(decl.group(1)) + 1
        for m in re.finditer(r"(\w+)\s*=\s*(\d+)'h([0-9a-fA-F_]+)", decl.group(2)):
            assert int(m.group(2)) == width, m.group(0)
            found[m.group(1)] = (width, int(m.group(3).replace("_", ""), 16))
    return found


def test_every_value_is_the_software_owners() -> None:
    declared = _declared(WIRE.read_text())
    owners = _owners()
    assert sorted(declared) == sorted(owners), "a wire constant without an owner, or one missing"
    for name, value in owners.items():
        width, got = declared[name]
        assert got == value, f"{name} = {got:#x}, the software's is {value:#x}"
        assert value < 1 << width, name


def test_the_parser_sees_a_wrong_value() -> None:
    """The check above can fail: one id changed in a copy of the header is a mismatch."""
    text = WIRE.read_text().replace("ID_DATA = 8'h15", "ID_DATA = 8'h14")
    assert _declared(text)["ID_DATA"] != (8, _owners()["ID_DATA"])


def test_the_header_is_on_every_include_path() -> None:
    """FABRIC_INCLUDES is the list the proofs, the fabric simulation and the board build copy."""
    assert WIRE.name in FABRIC_INCLUDES
    for stage in STAGES:
        assert f'`include "{WIRE.name}"' in (FABRIC_DIR / stage).read_text(), stage


def _literals(text: str) -> list[str]:
    """The hex literals in ``text`` that restate the vocabulary: an 8-bit submessage id or magic
    byte, a 32-bit submessage header (an id with the E flag next), the 32-bit magic, or an
    ``ID_*`` declared outside the header."""
    ids = {getattr(build, name) for name in IDS}
    magic = set(MAGIC)
    code = re.sub(r"//[^\n]*", "", text)
    hits = []
    for m in re.finditer(r"\b(8|32)'h([0-9a-fA-F_]+)", code):
        value = int(m.group(2).replace("_", ""), 16)
        if m.group(1) == "8" and value in ids | magic:
            hits.append(m.group(0))
        if m.group(1) == "32" and (value == int.from_bytes(MAGIC, "big") or
                                   (value >> 24 in ids and (value >> 16) & 0xFF == build.FLAG_LE)):
            hits.append(m.group(0))
    hits += re.findall(r"\bID_(?:" + "|".join(IDS) + r")\s*=", code)
    return hits


@pytest.mark.parametrize("name", sorted(p.name for p in FABRIC_DIR.glob("*.v")))
def test_no_module_writes_the_vocabulary_as_literals(name: str) -> None:
    hits = _literals((FABRIC_DIR / name).read_text())
    assert hits == [], (f"{name} restates {hits}: use rfl_rtps_wire.vh's names (or, for a value "
                        "that is not RTPS vocabulary, write it in decimal)")


def test_the_literal_check_can_fail() -> None:
    """The old spellings are caught (the ids' localparam, the magic's bytes, a header word)."""
    old = ("localparam [7:0] ID_PAD = 8'h01, ID_DATA = 8'h15;\n"
           "wire [159:0] v_hdr = {8'h52, 8'h54, 8'h50, 8'h53};\n"
           "assign h = 32'h09010800; // 8'h16 in a comment is fine\n")
    assert _literals(old) == ["8'h01", "8'h15", "8'h52", "8'h54", "8'h50", "8'h53",
                              "32'h09010800", "ID_PAD =", "ID_DATA ="]
