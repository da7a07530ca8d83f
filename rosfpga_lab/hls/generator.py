"""The generator of Figure 4: message definition + node configuration -> HLS C++.

How this works: :func:`render` builds one template context from the configuration, the message
registry (md5 sum, full text) and the hardware models' tables (the interpreter's states and the
message generator's fields, so the C++ walks the fields in exactly the order the Python models
do), then renders every Jinja2 template of ``templates/`` into a ``{file name: text}`` map.
Nothing touches the disk until everything has rendered. :func:`generate` then writes the files,
the lab's HLS headers (``hls_include/``), a test frame and the frame the Python models expect
for it (``tb_input.bin``, ``tb_expected.bin``), and a manifest listing every file it wrote.

Regenerating into a directory that holds files is refused unless ``force=True``, which first
deletes exactly the files the previous manifest lists (and the testbench's build products);
files the generator did not write are left alone and reported. The output depends only on the
configuration (its file's *name*, not its path), so it is byte-for-byte deterministic.
"""

from __future__ import annotations

import hashlib
import json
import shutil
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path

import jinja2
import numpy as np

from rosfpga_lab import __version__
from rosfpga_lab.config import CUSTOM, PASSTHROUGH, NodeConfig
from rosfpga_lab.hls.csim import BINARY, CXXFLAGS, SOURCES
from rosfpga_lab.hls import rtlbuild
from rosfpga_lab.hls.errors import GenerateError
from rosfpga_lab.hw import GENERATOR_TABLE, INTERPRETER_TABLE, PIXEL_FORMATS, Pipeline, image_frame
from rosfpga_lab.hw import limits as hw_limits
from rosfpga_lab.hw.interpreter import MIN_BODY_BYTES, SUBSCRIBER_STATUSES, fixed_after
from rosfpga_lab.msg import default_registry
from rosfpga_lab.tcpros import TopicSpec, encode_header, publisher_reply_fields, subscriber_request_fields

TEMPLATES_DIR = Path(__file__).resolve().parent / "templates"
INCLUDE_DIR = Path(__file__).resolve().parent / "include"
#: The lab's stand-ins for Xilinx's headers, copied to ``hls_include/`` (the Vivado HLS
#: flavour's image_filter also includes ``hls_video.h``, which Vitis HLS no longer ships).
HLS_HEADERS = ("ap_int.h", "ap_axi_sdata.h", "hls_stream.h", "hls_video.h")


@dataclass(frozen=True)
class HlsTool:
    """What one flavour of the generated C++ (``hls.flavour``) is written for.

    Attributes:
        name: the tool's name.
        versions: the releases the flavour is for (said in the generated README and scripts).
        command: how to run ``run_hls.tcl`` with it.
        pack: the directive that makes the metadata struct one FIFO word.
        free_running: the AXI4-Stream cores get ``ap_ctrl_none`` (no start/done handshake).
        headers: the lab's stand-in headers the project needs for ``make csim``.
        what: one line on how the flavour's C++ differs.
    """

    name: str
    versions: str
    command: str
    pack: str
    free_running: bool
    headers: tuple[str, ...]
    what: str


#: Flavour (:data:`rosfpga_lab.config.vocabulary.HLS_FLAVOURS`) -> its tool.
HLS_TOOLS: dict[str, HlsTool] = {
    "vitis": HlsTool(
        "Vitis HLS", "Vitis HLS 2020.2 and later",
        "vitis_hls -f run_hls.tcl", "HLS aggregate", True,
        ("ap_int.h", "ap_axi_sdata.h", "hls_stream.h"),
        "The application's own line buffer and window (no hls_video.h), `#pragma HLS aggregate` "
        "on the metadata FIFO, `ap_ctrl_none` on the free-running AXI4-Stream cores."),
    "vivado": HlsTool(
        "Vivado HLS", "Vivado HLS 2016.x to 2019.2",
        "vivado_hls -f run_hls.tcl", "HLS DATA_PACK", False, HLS_HEADERS,
        "The paper's tool. The HLS video library (`hls_video.h`: `AXIvideo2Mat`, "
        "`hls::Dilate`/`hls::Erode`, `Mat2AXIvideo`) and `DATA_PACK`, both removed in Vitis HLS."),
}


def meta_fields(config: NodeConfig) -> tuple[tuple[str, int], ...]:
    """The fields of one word of the metadata FIFO between subscriber and publisher, with
    their widths in bits (``struct image_meta`` of ``ros_node.h``; frame_id's bytes go on a
    FIFO of their own).

    Args:
        config: the node configuration.
    """
    return (("stamp_secs", 32), ("stamp_nsecs", 32),
            ("frame_id_length", config.frame_id_max.bit_length()), ("is_bigendian", 8))
#: Output file -> template. ``image_filter.cpp`` is the user's file for ``op: custom``.
TEMPLATE_FILES = {
    "ros_node.h": "ros_node.h.j2",
    "subscriber.cpp": "subscriber.cpp.j2",
    "publisher.cpp": "publisher.cpp.j2",
    "connection_headers.cpp": "connection_headers.cpp.j2",
    "image_filter.cpp": "image_filter.cpp.j2",
    "ros_fpga_node.cpp": "ros_fpga_node.cpp.j2",
    "csim_testbench.cpp": "csim_testbench.cpp.j2",
    "Makefile": "Makefile.j2",
    "run_hls.tcl": "run_hls.tcl.j2",
    "README.md": "README.md.j2",
}
MANIFEST = ".rosfpga-lab-manifest.json"
TB_INPUT = "tb_input.bin"
TB_EXPECTED = "tb_expected.bin"
#: What ``make csim`` and ``vitis_hls``/``vivado_hls -f run_hls.tcl`` leave behind; --force
#: removes these too.
BUILD_PRODUCTS = ("csim_testbench", "csim_out", "hls_subscriber", "hls_image_filter",
                  "hls_publisher", "vivado_hls.log", "vitis_hls.log", "rtlsim_out",
                  "rtl/rfl_sim.vvp", "rtl/obj_dir", f"rtl/{rtlbuild.PROJECT_OBJ_DIR}",
                  f"rtl/{rtlbuild.PROJECT_BUILD_LOG}")
#: Bytes per line of the hexadecimal arrays in connection_headers.cpp.
HEX_BYTES_PER_LINE = 16
_OP_CPP = {"dilate": "Dilate", "erode": "Erode"}
_HLS_TYPE = {1: "HLS_8UC1", 2: "HLS_8UC2", 3: "HLS_8UC3", 4: "HLS_8UC4"}
# Interpreter fields the subscriber template knows how to emit (checked at render time).
_TEMPLATE_FIELDS = {"frame_length", "seq", "stamp_secs", "stamp_nsecs", "frame_id_length",
                    "frame_id", "height", "width", "encoding_length", "encoding",
                    "is_bigendian", "step", "data_length", "data"}

Progress = Callable[[str], None]


@dataclass(frozen=True)
class GenerationResult:
    """What :func:`generate` wrote.

    Attributes:
        out_dir: the output directory.
        files: every file written, relative to ``out_dir``, sorted (the manifest excluded).
        removed: files of an earlier generation deleted first (``force=True``).
        kept: files in ``out_dir`` the generator did not write and left alone.
    """

    out_dir: Path
    files: tuple[str, ...]
    removed: tuple[str, ...] = ()
    kept: tuple[str, ...] = ()


def subscriber_header_fields(config: NodeConfig) -> dict[str, str]:
    """Connection-header fields the node's subscriber sends to a publisher (sorted on the wire).

    Args:
        config: the node configuration.

    Returns:
        ``{key: value}``: callerid, md5sum, message_definition, tcp_nodelay, topic, type.
    """
    reg = default_registry()
    t = config.subscriber.type
    return subscriber_request_fields(callerid=config.node.global_name,
                                     topic=config.subscriber.topic, md5sum=reg.md5(t),
                                     type_name=t, message_definition=reg.full_text(t),
                                     tcp_nodelay=True)


def publisher_header_fields(config: NodeConfig) -> dict[str, str]:
    """Connection-header fields the node's publisher answers a subscriber with.

    Args:
        config: the node configuration.

    Returns:
        ``{key: value}``: callerid, latching, md5sum, message_definition, topic, type.
    """
    reg = default_registry()
    t = config.publisher.type
    return publisher_reply_fields(config.node.global_name,
                                  TopicSpec(config.publisher.topic, t, reg.md5(t), reg.full_text(t)))


def _hex_rows(data: bytes) -> list[str]:
    return [", ".join(f"0x{b:02x}" for b in data[i:i + HEX_BYTES_PER_LINE]) + ","
            for i in range(0, len(data), HEX_BYTES_PER_LINE)]


def _header_context(title: str, array: str, function: str, fields: dict[str, str]) -> dict:
    data = encode_header(fields)
    shown = []
    for key in sorted(fields):
        value = fields[key]
        if "\n" in value or len(value) > 60:
            value = f"<{len(value.encode())} bytes: the full text of the message definition>"
        shown.append((key, value))
    return {"title": title, "array": array, "function": function, "length": len(data),
            "rows": _hex_rows(data), "fields": shown}


def _app_summary(config: NodeConfig) -> str:
    app = config.application
    if app.op == CUSTOM:
        return f"the user's image_filter() from {app.source.name if app.source else '?'}"
    if app.op == PASSTHROUGH:
        return "pass-through, no processing"
    return f"{app.ksize}x{app.ksize} {app.op}"


def sample_image(config: NodeConfig) -> np.ndarray:
    """A deterministic test picture for the testbench: gradients, a grid and bright dots.

    Returns:
        ``(height, width, channels)`` uint8.
    """
    h, w, c = config.image.height, config.image.width, config.image.bytes_per_pixel
    y, x = np.mgrid[0:h, 0:w]
    image = np.empty((h, w, c), np.uint8)
    for k in range(c):
        image[:, :, k] = ((x * (k + 1) * 3 + y * (5 - k) + (x ^ y) * k) % 251).astype(np.uint8)
    image[(y % 16 == 0) | (x % 16 == 0)] //= 2
    rng = np.random.default_rng(20240606)
    n = max(1, h * w // 64)
    image[rng.integers(0, h, n), rng.integers(0, w, n)] = 255
    return image


def sample_frames(config: NodeConfig) -> tuple[bytes, bytes]:
    """The testbench's input frame and the output frame the Python models give for it."""
    frame = image_frame(sample_image(config), config.image.encoding, seq=7,
                        stamp=(1_700_000_000, 123_456_789), frame_id="camera")
    if config.application.op == CUSTOM:
        return frame, b""
    return frame, Pipeline.from_config(config).process(frame).output_frame


def render(config: NodeConfig) -> dict[str, str]:
    """Render every generated text file for ``config`` (nothing is written).

    Returns:
        ``{file name: text}``.

    Raises:
        GenerateError: the hardware models' tables hold a field the templates do not know, or
            the custom application file cannot be read.
    """
    fields = {t.field for t in INTERPRETER_TABLE}
    if fields != _TEMPLATE_FIELDS:
        raise GenerateError(f"the interpreter table's fields {sorted(fields)} differ from those "
                            "the templates know; update templates/subscriber.cpp.j2")
    img = config.image
    fmt = PIXEL_FORMATS[img.encoding]
    checked = [{"status": name, "label": label} for name, label in SUBSCRIBER_STATUSES[1:]]
    status_of = {t.field: f"SUB_BAD_{t.field.upper()}" for t in INTERPRETER_TABLE}
    interp = [{"field": t.field, "label": t.label, "kind": t.kind, "status": status_of[t.field]}
              for t in INTERPRETER_TABLE]
    name = config.path.name if config.path else "<string>"
    tool = HLS_TOOLS[config.hls.flavour]
    meta = meta_fields(config)
    context = {
        "flavour": config.hls.flavour, "tool": tool, "hls_headers": tool.headers,
        "flavours": [{"key": key, "versions": t.versions, "what": t.what}
                     for key, t in HLS_TOOLS.items()],
        "meta_bits": sum(bits for _name, bits in meta),
        "frame_id_length_bits": dict(meta)["frame_id_length"],
        "generated_note": f"Generated by rosfpga-lab {__version__} from {name} (do not edit: "
                          "regenerate).",
        "node": config.node, "sub": config.subscriber, "pub": config.publisher,
        "image": img, "bpp": fmt.bytes_per_pixel, "tkeep": fmt.tkeep,
        "pixel_mask": (1 << (8 * fmt.bytes_per_pixel)) - 1,
        "hls_type": _HLS_TYPE[fmt.bytes_per_pixel], "app": config.application,
        "op_cpp": _OP_CPP.get(config.application.op, ""), "app_summary": _app_summary(config),
        "filter_name": "image_filter",
        "fifo": config.fifo, "clock_mhz": f"{config.clock_mhz:g}",
        "clock_period_ns": f"{1000.0 / config.clock_mhz:g}", "part": config.part,
        "frame_id_max": config.frame_id_max, "max_encoding_bytes": hw_limits.MAX_ENCODING_BYTES,
        "max_frame_bytes": hw_limits.MAX_FRAME_BYTES, "min_body_bytes": MIN_BODY_BYTES,
        "checked": checked, "interp_table": interp, "gen_table": GENERATOR_TABLE,
        "after_frame_id": fixed_after("frame_id"), "after_encoding": fixed_after("encoding"),
        "harness": rtlbuild.makefile_context(),
        "tb_input": TB_INPUT, "cxxflags": CXXFLAGS, "rtl": config.application.op != "custom", "csim_sources": SOURCES,
        "design_sources": [src for src in SOURCES if src != f"{BINARY}.cpp"],
        "tb_expected": TB_EXPECTED if config.application.op != CUSTOM else "",
        "headers": [
            _header_context(f"Subscriber: sent to each publisher of {config.subscriber.topic}",
                            "SUBSCRIBER_HEADER", "subscriber_connection_header",
                            subscriber_header_fields(config)),
            _header_context(f"Publisher: the answer to each subscriber of {config.publisher.topic}",
                            "PUBLISHER_HEADER", "publisher_connection_header",
                            publisher_header_fields(config)),
        ],
    }
    env = jinja2.Environment(
        loader=jinja2.FileSystemLoader(str(TEMPLATES_DIR)), undefined=jinja2.StrictUndefined,
        trim_blocks=True, lstrip_blocks=True, keep_trailing_newline=True, autoescape=False,
    )
    out: dict[str, str] = {}
    for target, template in TEMPLATE_FILES.items():
        if target == "image_filter.cpp" and config.application.op == CUSTOM:
            assert config.application.source is not None
            try:
                out[target] = config.application.source.read_text(encoding="utf-8")
            except (OSError, UnicodeDecodeError) as exc:
                raise GenerateError(f"cannot read the application file "
                                    f"{config.application.source}: {exc}") from None
            continue
        out[target] = env.get_template(template).render(context)
    return out


def _sha256(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()


def _read_manifest(out_dir: Path) -> dict | None:
    path = out_dir / MANIFEST
    if not path.exists():
        return None
    try:
        manifest = json.loads(path.read_text(encoding="utf-8"))
        files = manifest["files"]
        if not isinstance(files, dict):
            raise TypeError("files is not a mapping")
    except (OSError, ValueError, KeyError, TypeError) as exc:
        raise GenerateError(f"{path} is damaged ({exc}); remove the directory by hand") from None
    return manifest


def _existing(out_dir: Path) -> list[str]:
    return sorted(str(p.relative_to(out_dir)) for p in out_dir.rglob("*") if not p.is_dir())


def _safe_child(out_dir: Path, rel: str) -> Path:
    target = (out_dir / rel).resolve()
    if out_dir.resolve() not in target.parents:
        raise GenerateError(f"the manifest in {out_dir} names {rel!r}, outside the directory; "
                            "remove the directory by hand")
    return target


def _clean(out_dir: Path, manifest: dict) -> list[str]:
    removed = []
    for rel in sorted(manifest["files"]) + [MANIFEST]:
        target = _safe_child(out_dir, rel)
        if target.is_file():
            target.unlink()
            removed.append(rel)
    for rel in BUILD_PRODUCTS:
        target = _safe_child(out_dir, rel)
        if target.is_dir():
            shutil.rmtree(target)
            removed.append(rel + "/")
        elif target.exists():
            target.unlink()
            removed.append(rel)
    for d in sorted((p for p in out_dir.rglob("*") if p.is_dir()), reverse=True):
        if not any(d.iterdir()):
            d.rmdir()
    return removed


def generate(config: NodeConfig, out_dir: str | Path, *, force: bool = False,
             progress: Progress | None = None,
             extra_files: Mapping[str, bytes] | None = None,
             texts: Mapping[str, str] | None = None,
             frames: tuple[bytes, bytes] | None = None) -> GenerationResult:
    """Write the HLS C++ project of ``config`` into ``out_dir``.

    Args:
        config: a validated configuration (:func:`rosfpga_lab.config.load_config`).
        out_dir: the output directory (created when missing).
        force: replace an earlier generation: delete the files its manifest lists (and the
            testbench's build products) first. Files the generator did not write are kept.
        progress: called with a short message before each long step.
        extra_files: more files to write (``{relative path: bytes}``) under the same manifest:
            a layer above adds its own (``rosfpga_lab.rtl`` adds ``rtl/``, the Verilog).
        texts: the rendered files, when a caller rendered them (a message type other than
            Image: :func:`rosfpga_lab.hls.generic.render_generic`); default :func:`render`.
        frames: ``(tb_input, tb_expected)`` with ``texts``; default :func:`sample_frames`.

    Returns:
        What was written, removed and kept.

    Raises:
        GenerateError: ``out_dir`` holds files and ``force`` is False, is not a directory, or
            cannot be written.
    """
    say = progress or (lambda _msg: None)
    out = Path(out_dir)
    manifest: dict | None = None
    if out.exists():
        if not out.is_dir():
            raise GenerateError(f"{out} exists and is not a directory")
        manifest = _read_manifest(out)
        present = _existing(out)
        if present and not force:
            if manifest is not None:
                raise GenerateError(f"{out} holds an earlier generation ({len(manifest['files'])} "
                                    "files); pass --force to replace it")
            raise GenerateError(f"{out} is not empty and was not written by rosfpga-lab "
                                f"({len(present)} files); choose an empty or new directory")
    say("rendering templates")
    if texts is None:
        texts = render(config)
        say(f"computing the test frame and the Python models' output "
            f"({config.image.width}x{config.image.height} {config.image.encoding})")
        tb_input, tb_expected = sample_frames(config)
    else:
        assert frames is not None, "generate(texts=...) needs frames=(tb_input, tb_expected)"
        tb_input, tb_expected = frames

    blobs: dict[str, bytes] = {name: text.encode("utf-8") for name, text in texts.items()}
    for header in HLS_TOOLS[config.hls.flavour].headers:
        blobs[f"hls_include/{header}"] = (INCLUDE_DIR / header).read_bytes()
    for name, data in (extra_files or {}).items():
        blobs[name] = bytes(data)
    blobs[TB_INPUT] = tb_input
    if tb_expected:
        blobs[TB_EXPECTED] = tb_expected
    new_manifest = {"generator": f"rosfpga-lab {__version__}",
                    "config": config.path.name if config.path else "<string>",
                    "files": {name: _sha256(data) for name, data in sorted(blobs.items())}}
    try:
        removed = _clean(out, manifest) if manifest is not None else []
        if removed:
            say(f"removed {len(removed)} files of the earlier generation")
        out.mkdir(parents=True, exist_ok=True)
        # The manifest goes first, so even an interrupted run can be cleaned with --force.
        (out / MANIFEST).write_text(json.dumps(new_manifest, indent=1, sort_keys=True) + "\n",
                                    encoding="utf-8")
        say(f"writing {len(blobs)} files into {out}")
        for name, data in sorted(blobs.items()):
            path = out / name
            path.parent.mkdir(parents=True, exist_ok=True)
            path.write_bytes(data)
    except OSError as exc:
        where = exc.filename or out
        raise GenerateError(f"cannot write into {out}: {exc.strerror or exc} ({where})") from None
    kept = [p for p in _existing(out) if p not in blobs and p != MANIFEST]
    return GenerationResult(out, tuple(sorted(blobs)), tuple(removed), tuple(kept))
