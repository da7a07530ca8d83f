"""The generic HLS C++ keeps the rules a Xilinx flow (Vitis HLS 2020.2+, Vivado HLS) needs, read
from the generated text, since no Xilinx tool runs here (issue 28 item 6).

For the shipped examples (both wires, Image on TCPROS and CDR) and random message definitions:
every core of the run script is a top function with an INTERFACE pragma per port and
``ap_ctrl_none``; every stream word is narrow (``hls::stream<T>``: T's bits from its declaration,
struct members summed); no register array longer than a small bound (so none indexed by a
running counter across a frame's bytes); the cores' stream types chain in the run script's order
(subscriber -> fifo2axi -> stream_filter -> axi2fifo -> publisher); the run script is the
configured flavour's; the subscriber reads and the publisher writes their byte FIFO in one
place, in a loop pipelined at II=1 (a byte per clock whatever the fields).
"""

from __future__ import annotations

import dataclasses
import re
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from rosfpga_lab.config import load_config
from rosfpga_lab.config.vocabulary import HLS_FLAVOURS
from rosfpga_lab.hls.generic import HLS_TOOLS
from rosfpga_lab.hls.generic import meta_fields, render_generic, spec_from_config, spec_from_layout
from rosfpga_lab.hw.errors import LayoutError
from rosfpga_lab.hw.layout import Action, StepKind, derive_layout
from tests.hw.test_walker import definitions  # the models' strategy over message definitions

DATA = Path(__file__).resolve().parents[2] / "data"
CONFIGS = ("fpga_laserscan_min", "fpga_laserscan_min_cdr", "fpga_samples_dilate",
           "fpga_samples_dilate_cdr", "fpga_dilate_rgba8_cdr", "fpga_dilate_rgba8",
           "fpga_erode_mono8", "fpga_passthrough_rgb8")
#: "A few hundred bits": the widest FIFO word a core may pass.
MAX_WORD_BITS = 256
#: The longest register array (elements) a core may hold: the window, the loop stack.
MAX_REGISTER_ARRAY = 32
CHAIN = ("subscriber", "fifo2axi", "stream_filter", "axi2fifo", "publisher")


def _strip(text: str) -> str:
    return re.sub(r"//[^\n]*", "", text)


def _defines(texts: dict[str, str]) -> dict[str, str]:
    out: dict[str, str] = {}
    for text in texts.values():
        out.update(re.findall(r"^#define (\w+) (.+?)u?\s*$", _strip(text), flags=re.M))
    return out


def _value(expr: str, defines: dict[str, str]) -> int:
    """A size expression of the generated C++ (numbers, #defines, + - * /)."""
    for _ in range(10):
        expr = re.sub(r"\b[A-Z_][A-Z0-9_]*\b", lambda m: f"({defines[m.group(0)]})", expr)
    return int(eval(re.sub(r"(\d+)u\b", r"\1", expr).replace("/", "//"), {}))  # noqa: S307


def type_bits(name: str, texts: dict[str, str]) -> int:
    """Bits of a C++ type of the generated project: ap_uint<N>, bool, byte_t, ap_axiu<...>,
    a typedef of one, or a struct (its members summed, arrays times their length)."""
    every = "\n".join(_strip(t) for t in texts.values())
    defines = _defines(texts)
    name = name.strip()
    if name == "bool":
        return 1
    if m := re.fullmatch(r"ap_uint<(.+)>", name):
        return _value(m.group(1), defines)
    if m := re.fullmatch(r"ap_axiu<(.+),\s*(\d+),\s*(\d+),\s*(\d+)>", name):
        w = _value(m.group(1), defines)  # TDATA, TKEEP, TSTRB, TUSER, TLAST, TID, TDEST
        return w + 2 * (w // 8) + int(m.group(2)) + 1 + int(m.group(3)) + int(m.group(4))
    if m := re.search(rf"typedef ([^;]+?) {name};", every):
        return type_bits(m.group(1), texts)
    if m := re.search(rf"struct {name} \{{(.*?)\}};", every, flags=re.S):
        total = 0
        for member in m.group(1).split(";"):
            if not member.strip():
                continue
            decl = re.fullmatch(r"\s*(.+?)\s+\w+(?:\[(.+)\])?\s*", member, flags=re.S)
            assert decl, member
            count = _value(decl.group(2), defines) if decl.group(2) else 1
            total += count * type_bits(decl.group(1), texts)
        return total
    raise AssertionError(f"no declaration of {name}")


def stream_words(texts: dict[str, str]) -> dict[str, int]:
    """Every hls::stream<T> of the project: T -> its bits."""
    every = "\n".join(_strip(t) for t in texts.values())
    return {t: type_bits(t, texts) for t in set(re.findall(r"hls::stream<(.+?)>\s", every))}


def register_arrays(texts: dict[str, str]) -> dict[str, int]:
    """Every array but a ROM (static const) declared in a struct or a function: name -> length."""
    defines = _defines(texts)
    out = {}
    for name, text in texts.items():
        if not name.endswith((".cpp", ".h")) or name == "csim_testbench.cpp":
            continue
        for line in _strip(text).splitlines():
            m = re.fullmatch(r"\s+(?!return)([\w:<>, ]+?)\s+(\w+)\[([^\]]+)\];\s*", line)
            if m and "static const" not in line:
                out[f"{name}: {m.group(2)}"] = _value(m.group(3), defines)
    return out


def top_params(header: str) -> dict[str, list[tuple[str, str]]]:
    """The cores' prototypes in ros_node.h: top -> [(type, name)]."""
    out = {}
    for top in CHAIN:
        m = re.search(rf"void {top}\(([^)]*)\);", _strip(header), flags=re.S)
        assert m, f"no prototype of the top function {top}"
        out[top] = [tuple(p.strip().replace("&", "").rsplit(None, 1)) for p in m.group(1).split(",")]
    return out  # type: ignore[return-value]


def function_body(text: str, name: str) -> str:
    m = re.search(rf"\n\w[\w<> ]* {name}\([^)]*\) \{{\n", text)
    assert m, f"no definition of {name}"
    depth, i = 1, m.end()
    while depth:
        depth += {"{": 1, "}": -1}.get(text[i], 0)
        i += 1
    return text[m.end():i]


def enclosing_loop_pipelined(text: str, at: int) -> bool:
    """The innermost for/while block around text[at] opens with PIPELINE II = 1."""
    depth = 0
    for i in range(at, -1, -1):
        if text[i] == "}":
            depth += 1
        elif text[i] == "{":
            if depth == 0:
                head = text[text.rfind("\n", 0, i) + 1:i]
                if re.match(r"\s*(for|while)\b", head):
                    return "HLS_PRAGMA(HLS PIPELINE II = 1)" in text[i:i + 80]
            else:
                depth -= 1
    return False


def check_rules(texts: dict[str, str], flavour: str) -> None:
    code = {n: _strip(t) for n, t in texts.items()}
    sources = "\n".join(t for n, t in code.items() if n.endswith(".cpp") and n != "csim_testbench.cpp")
    params = top_params(texts["ros_node.h"])
    # every core: a top with an INTERFACE pragma per port, free-running
    for top, ports in params.items():
        body = function_body(sources, top)
        assert "HLS_PRAGMA(HLS INTERFACE ap_ctrl_none port = return)" in body, top
        for _type, port in ports:
            assert re.search(rf"HLS_PRAGMA\(HLS INTERFACE \w+ port = {port}\)", body), (top, port)
    # the run script synthesizes the chain, in order, with the flavour's commands
    tcl = texts["run_hls.tcl"]
    assert f"foreach top {{{' '.join(CHAIN)}}}" in tcl
    assert HLS_TOOLS[flavour].command in tcl
    for word in ("open_project -reset", "set_top $top", "csynth_design", "export_design -format ip_catalog"):
        assert word in tcl, word
    if flavour == "vitis":
        assert "open_solution -reset solution1 -flow_target vivado" in tcl
        assert "config_interface -default_slave_interface none" in tcl
    else:
        assert "-flow_target" not in tcl and "config_interface" not in tcl and "vitis" not in tcl
        assert "open_solution -reset solution1\n" in tcl
    assert f"HLS_PRAGMA({HLS_TOOLS[flavour].pack} variable = meta_out)" in texts["subscriber.cpp"]
    # the cores' stream types chain: each one's data output is the next one's input
    for a, b in zip(CHAIN, CHAIN[1:]):
        out_type = next(t for t, n in params[a] if n in ("out", "stream_out"))
        in_type = next(t for t, n in params[b] if n == "in")
        assert out_type == in_type, (a, out_type, b, in_type)
    ends = ({n: t for t, n in params["subscriber"]}["in"], {n: t for t, n in params["publisher"]}["out"])
    assert ends == ("byte_stream", "byte_stream")
    # narrow words, small register arrays
    words = stream_words(texts)
    assert words and max(words.values()) <= MAX_WORD_BITS, words
    assert words["frame_meta"] == sum(f[1] for f in meta_fields_of(texts)), words
    arrays = register_arrays(texts)
    assert all(n <= MAX_REGISTER_ARRAY for n in arrays.values()), arrays
    # a byte per clock: one read of the input FIFO (subscriber), one write of the output FIFO
    # (publisher), each in a loop pipelined at II=1
    for name, call in (("subscriber", "in.read()"), ("publisher", "out.write(")):
        text = function_body(code[f"{name}.cpp"], name)
        sites = [m.start() for m in re.finditer(re.escape(call), text)]
        assert len(sites) == 1, (name, call, len(sites))
        assert enclosing_loop_pipelined(text, sites[0]), (name, call)


def meta_fields_of(texts: dict[str, str]) -> list[tuple[str, int]]:
    """The metadata word's fields as ros_node.h declares them (name, bits)."""
    m = re.search(r"struct frame_meta \{(.*?)\};", _strip(texts["ros_node.h"]), flags=re.S)
    assert m
    out = []
    for member in filter(str.strip, m.group(1).split(";")):
        kind, name = member.split()
        out.append((name, type_bits(kind, texts)))
    return out


@pytest.mark.parametrize("flavour", HLS_FLAVOURS)
@pytest.mark.parametrize("stem", CONFIGS)
def test_shipped_generic_projects_keep_the_xilinx_rules(stem: str, flavour: str) -> None:
    spec = dataclasses.replace(spec_from_config(load_config(DATA / f"{stem}.yaml")), flavour=flavour)
    texts = render_generic(spec)
    check_rules(texts, flavour)
    assert [(n, b) for n, b, _what in meta_fields(spec.program)] == meta_fields_of(texts)


@settings(max_examples=12, deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.too_slow])
@given(data=st.data())
def test_random_definitions_keep_the_xilinx_rules(data: st.DataObject) -> None:
    reg, type_name, stream = data.draw(definitions())
    n = data.draw(st.integers(1, 64))
    try:  # a variable array: a drawn length; a fixed one: its own
        layout = derive_layout(reg, type_name, stream=stream, stream_length=n)
    except LayoutError:
        n = None
        layout = derive_layout(reg, type_name, stream=stream)
    # maxima of 3 to 40 per array and string (the defaults nest past the carry memory's limit)
    most = data.draw(st.integers(3, 40))
    small = {s.path: most for s in layout.steps[1:] if s.kind is StepKind.LENGTH
             and s.action is not Action.STREAM and not s.label.endswith("[] length")}
    layout = derive_layout(reg, type_name, stream=stream, stream_length=n, limits_=small)
    flavour = data.draw(st.sampled_from(HLS_FLAVOURS))
    op = data.draw(st.sampled_from(["dilate", "erode", "passthrough"]))
    check_rules(render_generic(spec_from_layout(layout, reg, op=op, flavour=flavour)), flavour)


def test_the_parsers_see_the_old_wide_word_and_its_carry_array() -> None:
    """The word as it was (the carry array inside): 145,000-odd bits for LaserScan, and a
    register array of 18,128 bytes."""
    old = {"ros_node.h": "#define CARRY_BYTES 18120\ntypedef ap_uint<8> byte_t;\n"
                         "struct frame_meta {\n    ap_uint<32> out_len;\n    bool drop;\n"
                         "    byte_t carry[CARRY_BYTES + 8];  // (+8: g++)\n};\n"
                         "typedef hls::stream<frame_meta> meta_stream;\n"}
    assert stream_words(old) == {"frame_meta": 32 + 1 + 8 * 18128}
    assert register_arrays(old) == {"ros_node.h: carry": 18128}


#: Which shipped walks release early, and a whole stream's bytes otherwise (from each
#: configuration's stream: 360 float32 ranges, 64 int32 samples).
EARLY = {"fpga_dilate_rgba8": True, "fpga_dilate_rgba8_cdr": True, "fpga_erode_mono8": True,
         "fpga_passthrough_rgb8": True, "fpga_laserscan_min": 360 * 4,
         "fpga_laserscan_min_cdr": 360 * 4, "fpga_samples_dilate": 64 * 4,
         "fpga_samples_dilate_cdr": 64 * 4}


@pytest.mark.parametrize("stem", CONFIGS)
def test_an_early_walk_hands_its_meta_over_at_the_count_so_no_fifo_holds_a_stream(stem: str) -> None:
    """Streaming early release in the HLS C++ too: the subscriber of a walk that releases early
    writes the metadata word once, when the stream's count is checked (``count_read``), so the
    FIFO before the publisher holds a few bytes in a concurrent block design; otherwise once, at
    the frame's end, and the README asks for a FIFO of a whole stream there."""
    texts = render_generic(spec_from_config(load_config(DATA / f"{stem}.yaml")))
    code = _strip(texts["subscriber.cpp"])
    at_count = function_body(code, "count_read").count("meta_out.write(")
    at_end = function_body(code, "subscriber").count("meta_out.write(")
    readme = " ".join(texts["README.md"].split())
    if EARLY[stem] is True:
        assert (at_count, at_end) == (1, 1) and "&& !w.released" in function_body(code, "subscriber")
        assert "The FIFO before the publisher (after `axi2fifo`) holds a few bytes" in readme
        assert "#define EARLY_ADD" in texts["layout.h"]
    else:
        assert (at_count, at_end) == (0, 1) and "released" not in function_body(code, "count_read")
        assert (f"must hold a whole stream, STREAM_DATA_BYTES = {EARLY[stem]:,} bytes") in readme
        assert "EARLY_ADD" not in texts["layout.h"]
