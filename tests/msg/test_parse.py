"""Parsing ``.msg`` text: genmsg's rules on tricky definitions, the error table, the registry's
lookups and folder loading, and the comment-stripping rule.

The md5 sums and full-text hashes below were computed by Debian's genmsg
(tests/ros_programs/genpy_genmsg_md5.py) from exactly these texts; test_realros.py recomputes them
live in CI. genmsg rejects every definition in BAD as well.
"""

from __future__ import annotations

import hashlib
from pathlib import Path

import pytest

from rosfpga_lab.msg import (
    MsgDefinitionError, MsgError, MsgRegistry, UnknownTypeError, default_registry, parse_msg,
    split_full_text, strip_comments,
)

HEADER_TEXT = "uint32 seq\ntime stamp\nstring frame_id\n"
TRICKY = {
    "std_msgs/Header": HEADER_TEXT,
    "tricky/Constants": (
        "# leading comment\n"
        "string S = a # b  \n"
        "string  T=   x=y   \n"
        "string EMPTY=\n"
        "int8 X = +01 # c\n"
        "uint8 U=255\n"
        "int64 BIG=-9223372036854775808\n"
        "uint64 UBIG=18446744073709551615\n"
        "bool B1= True\n"
        "bool B2=0\n"
        "float32 F=1e3\n"
        "float64 NEG = -0.5   # negative\n"
        "char C=65\n"
        "byte Y=-3\n"
        "uint16 v\n"
    ),
    "tricky/Inner": "int32 a\nstring b\n  # indented comment\n   float32   spaced   # extra spaces\n",
    "tricky/Arrays": (
        "byte[] b\nchar[4] c\nuint8[] raw\nuint8[3] fixed\nfloat64[] f\nint16[2] s\n"
        "time[] ts\nduration[3] ds\nstring[] names\nstring[2] pair\nbool[] flags\n"
        "Inner[] inners\nInner[2] two\ntricky/Inner one\nHeader header\n"
    ),
    "tricky/Empty": "# nothing here\n\n",
    "tricky/Crlf": "int32 a\r\nstring S=hi \r\nEmpty e\r\n",
    "tricky/Top": "Header header\nArrays arrays\nInner inner\nCrlf crlf\nEmpty[] empties\n",
}
# genmsg: (compute_md5, sha256(compute_full_text)[:16])
GENMSG = {
    "std_msgs/Header": ("2176decaecbce78abc3b96ef049fabed", "39b298e4d5761a74"),
    "tricky/Constants": ("9c11ad134740e0d7771b4f3f328b748a", "18e4278bd8819536"),
    "tricky/Inner": ("11a8d1fc279b1a1f82746936b059353e", "a42c9ea1b52122f4"),
    "tricky/Arrays": ("9eb7bca70379042ef9d77c7f87b8d339", "34e22b8d30b225c6"),
    "tricky/Empty": ("d41d8cd98f00b204e9800998ecf8427e", "7bf0b06ce5b783bb"),
    "tricky/Crlf": ("a9d637fff49f96e12cf1ccb5cd599e32", "2c7deeff80fbf91d"),
    "tricky/Top": ("d52cdae693ba4cc49941d42b664f7748", "adfc8a9a0b1dc02a"),
}
BAD = {  # name: (text, words expected in our message)
    "bad/Tab": ("int32\tfoo\n", "not tabs"),
    "bad/Range": ("int8 X=128\n", "out of range for int8"),
    "bad/MultiDim": ("int32[2][3] m\n", "one-dimensional"),
    "bad/ThreeWords": ("int32 foo bar\n", "expected 'TYPE NAME', found 3"),
    "bad/TypeDigit": ("1abc x\n", "not a legal field type"),
    "bad/NameDigit": ("int32 1x\n", "not a legal field name"),
    "bad/TimeConst": ("time T=1\n", "not a legal constant type"),
    "bad/ArrayConst": ("string[] S=a\n", "not a legal constant type"),
    "bad/TwoEquals": ("int32 X=1=2\n", "exactly one '='"),
    "bad/BoolWord": ("bool B=nonsense\n", "True, False, 1 or 0"),
    "bad/Dup": ("int32 a\nint32 a\n", "duplicate name 'a'"),
    "bad/Float": ("int32 X=1.5\n", "invalid int32 constant value '1.5'"),
    "bad/Bracket": ("int32[x] a\n", "malformed array suffix"),
    "bad/TwoSlashes": ("a/b/C x\n", "not a legal field type"),
    "bad/Bounded": ("string<=5 s\n", "not a legal constant type"),  # ROS 2 only; "=" -> constant
}


@pytest.fixture(scope="module")
def tricky() -> MsgRegistry:
    reg = MsgRegistry()
    for name, text in TRICKY.items():
        reg.add(name, text)
    return reg


@pytest.mark.parametrize("name", sorted(GENMSG))
def test_tricky_md5_and_full_text_match_genmsg(tricky: MsgRegistry, name: str) -> None:
    md5, text_hash = GENMSG[name]
    assert tricky.md5(name) == md5
    assert hashlib.sha256(tricky.full_text(name).encode()).hexdigest()[:16] == text_hash


def test_constants_follow_genmsg(tricky: MsgRegistry) -> None:
    consts = {c.name: c for c in tricky.get("tricky/Constants").constants}
    assert consts["S"].value == "a # b"          # '#' belongs to a string constant
    assert consts["T"].value == "x=y"
    assert consts["EMPTY"].value == ""
    assert (consts["X"].value, consts["X"].value_text) == (1, "+01")
    assert consts["BIG"].value == -2**63 and consts["UBIG"].value == 2**64 - 1
    assert consts["B1"].value is True and consts["B2"].value is False
    assert consts["F"].value == 1000.0 and consts["NEG"].value == -0.5
    assert consts["C"].value == 65 and consts["Y"].value == -3
    assert tricky.md5_text("tricky/Constants").splitlines()[:4] == [
        "string S=a # b", "string T=x=y", "string EMPTY=", "int8 X=+01"]


def test_fields_resolve_like_genmsg(tricky: MsgRegistry) -> None:
    fields = {f.name: f for f in tricky.get("tricky/Arrays").fields}
    assert fields["inners"].type == "tricky/Inner[]" and fields["inners"].array_length is None
    assert fields["two"].type == "tricky/Inner[2]" and fields["two"].array_length == 2
    assert fields["header"].type == "std_msgs/Header"
    assert fields["b"].type == "byte[]" and fields["c"].type == "char[4]"
    assert fields["ds"].base_type == "duration" and fields["ds"].is_builtin
    spec = parse_msg("Header[] hs\n", "pkg/M")  # genmsg maps only exactly 'Header'
    assert spec.fields[0].type == "pkg/Header[]"
    assert [f.name for f in tricky.get("tricky/Inner").fields] == ["a", "b", "spaced"]
    assert tricky.get("tricky/Top").has_header and not tricky.get("tricky/Arrays").has_header


@pytest.mark.parametrize("name", sorted(BAD))
def test_bad_definitions_name_source_line_and_reason(name: str) -> None:
    text, words = BAD[name]
    with pytest.raises(MsgDefinitionError) as info:
        parse_msg(text, name, source=f"/defs/{name}.msg")
    err = info.value
    assert words in err.reason
    line = text.count("\n", 0, text.rstrip("\n").rfind("\n") + 1) + 1
    assert err.line == line and err.source == f"/defs/{name}.msg"
    assert str(err).startswith(f"/defs/{name}.msg:{line}: ")


def test_bad_type_names() -> None:
    for full_name in ("NoPackage", "a/b/C", "1pkg/X", "pkg/"):
        with pytest.raises(MsgDefinitionError, match="package/Name"):
            parse_msg("int32 a\n", full_name)


def test_load_path_reads_package_folders(tmp_path: Path) -> None:
    (tmp_path / "my_msgs" / "msg").mkdir(parents=True)
    (tmp_path / "my_msgs" / "msg" / "Blob.msg").write_text("Header header\nuint8[] data\n")
    (tmp_path / "my_msgs" / "msg" / "Pair.msg").write_text("Blob a\ngeometry_msgs/Point b\n")
    (tmp_path / "notes").mkdir()  # not a package: ignored
    reg = MsgRegistry.with_defaults()
    assert reg.load_path(tmp_path) == ["my_msgs/Blob", "my_msgs/Pair"]
    assert reg.dependencies("my_msgs/Pair") == [
        "my_msgs/Blob", "std_msgs/Header", "geometry_msgs/Point"]
    other = MsgRegistry.with_defaults()
    assert other.load_path(tmp_path / "my_msgs") == ["my_msgs/Blob", "my_msgs/Pair"]
    assert other.md5("my_msgs/Pair") == reg.md5("my_msgs/Pair")
    deep = tmp_path / "ws" / "src" / "group" / "deep_msgs" / "msg"  # catkin workspace layout
    deep.mkdir(parents=True)
    (deep / "D.msg").write_text("int8 x\n")
    (tmp_path / "ws" / ".hidden" / "h_msgs" / "msg").mkdir(parents=True)
    (tmp_path / "ws" / ".hidden" / "h_msgs" / "msg" / "H.msg").write_text("int8 x\n")
    assert MsgRegistry().load_path(tmp_path / "ws") == ["deep_msgs/D"]


def test_malformed_file_names_file_and_line(tmp_path: Path) -> None:
    bad = tmp_path / "my_msgs" / "msg" / "Bad.msg"
    bad.parent.mkdir(parents=True)
    bad.write_text("# ok\nint32 a\nfloat64 b c\n")
    with pytest.raises(MsgDefinitionError) as info:
        MsgRegistry().load_path(tmp_path)
    assert str(info.value).startswith(f"{bad}:3: expected 'TYPE NAME'")
    bad.write_bytes(b"int32 a # \xff\n")
    with pytest.raises(MsgDefinitionError, match="not UTF-8"):
        MsgRegistry().load_path(tmp_path)
    with pytest.raises(MsgError, match="not a folder"):
        MsgRegistry().load_path(tmp_path / "missing")


def test_unknown_types_say_what_and_where(tmp_path: Path) -> None:
    reg = default_registry()
    with pytest.raises(UnknownTypeError) as info:
        reg.get("nav_msgs/Odometry")
    assert "nav_msgs/Odometry" in str(info.value) and "shipped definitions" in str(info.value)
    assert "no package 'nav_msgs'" in str(info.value) and info.value.type_name == "nav_msgs/Odometry"
    with pytest.raises(UnknownTypeError, match="builtin"):
        reg.get("uint8[]")
    (tmp_path / "p" / "msg").mkdir(parents=True)
    (tmp_path / "p" / "msg" / "A.msg").write_text("int32 x\nMissing m\n")
    mine = MsgRegistry.with_defaults()
    mine.load_path(tmp_path)
    with pytest.raises(UnknownTypeError) as info:
        mine.md5("p/A")
    text = str(info.value)
    assert "'p/Missing'" in text and "field 'm' of p/A" in text and "A.msg:2" in text
    assert str(tmp_path) in text  # where it searched


def test_ambiguous_short_name() -> None:
    reg = MsgRegistry()
    reg.add("a/X", "int32 v\n")
    reg.add("b/X", "int32 v\n")
    with pytest.raises(UnknownTypeError, match="ambiguous: a/X, b/X"):
        reg.get("X")
    assert reg.get("X", package="b").full_name == "b/X"


def test_recursive_definition_refused() -> None:
    reg = MsgRegistry()
    reg.add("r/A", "B b\n")
    reg.add("r/B", "A[] a\n")
    with pytest.raises(MsgDefinitionError, match="recursive message definition: r/A -> r/B -> r/A"):
        reg.md5("r/A")


def test_strip_comments_rule() -> None:
    text = ("# title\n\nuint8 A = 1   # one\nstring S = x # y   \n  int32  v  # c\n"
            "Header header#h\n#end")
    assert strip_comments(text) == "uint8 A = 1\nstring S = x # y\n  int32  v\nHeader header\n"
    assert strip_comments("# only comments\n") == ""
    reg = MsgRegistry.with_defaults()
    reg.add("s/A", text)
    reg.add("s/B", strip_comments(text))
    assert reg.md5("s/A") == reg.md5("s/B")


def test_split_full_text_round_trip() -> None:
    reg = default_registry()
    full = reg.full_text("geometry_msgs/PoseStamped")
    sections = split_full_text(full)
    assert [name for name, _ in sections] == [
        None, "std_msgs/Header", "geometry_msgs/Pose", "geometry_msgs/Point",
        "geometry_msgs/Quaternion"]
    assert sections[1][1] == reg.get("std_msgs/Header").text
    copy = MsgRegistry()
    assert copy.add_full_text("geometry_msgs/PoseStamped", full)[0] == "geometry_msgs/PoseStamped"
    assert copy.full_text("geometry_msgs/PoseStamped") == full
    assert copy.md5("geometry_msgs/PoseStamped") == "d3812c3cbc69362b77dc0b19b345f8f5"
