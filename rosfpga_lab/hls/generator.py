"""Write a generated project to disk: Figure 4's flow, message definition + node configuration
-> a directory of HLS C++, test frames and (from the layer above) Verilog.

How this works: :func:`generate` renders the configuration's project
(:func:`rosfpga_lab.hls.generic.render`: any message type, either wire), computes its test frames
and the Python models' output for them (:func:`rosfpga_lab.hls.vectors.sample_frames`), adds the
lab's stand-ins for Xilinx's headers (``hls_include/``) and writes everything with a manifest
listing every file. Nothing touches the disk until everything has rendered.

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

from rosfpga_lab import __version__
from rosfpga_lab.config import NodeConfig
from rosfpga_lab.hls import rtlbuild
from rosfpga_lab.hls.csim import BINARY, HLS_HEADERS, INCLUDE_DIR, TB_EXPECTED, TB_INPUT
from rosfpga_lab.hls.errors import GenerateError
from rosfpga_lab.hls.generic import render
from rosfpga_lab.hls.vectors import sample_frames

MANIFEST = ".rosfpga-lab-manifest.json"
#: What ``make csim``, ``make rtlsim`` and ``vitis_hls``/``vivado_hls -f run_hls.tcl`` leave
#: behind; --force removes these too.
BUILD_PRODUCTS = (BINARY, "csim_out", "hls_subscriber", "hls_fifo2axi", "hls_stream_filter",
                  "hls_axi2fifo", "hls_publisher", "vivado_hls.log", "vitis_hls.log",
                  "rtlsim_out", "rtl/rfl_sim.vvp", "rtl/obj_dir", f"rtl/{rtlbuild.PROJECT_OBJ_DIR}",
                  f"rtl/{rtlbuild.PROJECT_BUILD_LOG}")

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
        texts: the rendered files, when a caller rendered them already
            (:func:`rosfpga_lab.hls.generic.render_generic`); default
            :func:`~rosfpga_lab.hls.generic.render` of ``config``.
        frames: ``(tb_input, tb_expected)`` when a caller computed them already; default
            :func:`~rosfpga_lab.hls.vectors.sample_frames` of ``config``.

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
    if frames is None:
        say("computing the test frames and the Python models' output")
        frames = sample_frames(config)
    tb_input, tb_expected = frames

    blobs: dict[str, bytes] = {name: text.encode("utf-8") for name, text in texts.items()}
    for header in HLS_HEADERS:
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
