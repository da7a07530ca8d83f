"""The lab's stand-ins for Xilinx's HLS headers behave as the Python models (and Xilinx) do.

One small C++ probe, compiled once with ``g++ -std=c++14 -Wall -Werror`` against
``rosfpga_lab/hls/include``, runs batches of cases read from stdin: ``hls::AXIvideo2Mat`` on
well-formed and damaged AXI4-Stream video (lost or early TLAST, a TUSER inside the frame, junk
before the start of frame) against :func:`rosfpga_lab.hw.axivideo2mat_reference`;
``hls::Dilate``/``hls::Erode`` on random small images and kernels against OpenCV (through
:func:`rosfpga_lab.hw.morph_fast`); ``Mat2AXIvideo``'s beats; and ``ap_uint`` arithmetic.
"""

from __future__ import annotations

import subprocess
from pathlib import Path

import numpy as np
import pytest

from realros import require_cxx
from rosfpga_lab.hls.generator import INCLUDE_DIR
from rosfpga_lab.hw import Beat, Fifo, Mat, StreamStarvedError, axivideo2mat_reference, morph_fast

PROBE = r"""
#include <cstdio>
#include <iostream>
#include <hls_video.h>

typedef ap_axiu<32, 1, 1, 1> beat_t;
static const int R = 8, C = 8;

template <int T>
void axivideo_case(int rows, int cols, int n) {
    hls::stream<beat_t> s;
    for (int i = 0; i < n; i++) {
        unsigned data, user, last;
        std::cin >> std::hex >> data >> user >> last;
        beat_t b;
        b.data = data; b.user = user; b.last = last; b.keep = -1;
        s.write(b);
    }
    hls::Mat<R, C, T> img(rows, cols);
    int flags = hls::AXIvideo2Mat(s, img);
    std::printf("flags %d left %d\n", flags, (int)s.size());
    for (int p = 0; p < rows * cols; p++) {
        hls::Scalar<HLS_MAT_CN(T), unsigned char> pix;
        img >> pix;
        for (int k = 0; k < HLS_MAT_CN(T); k++) std::printf("%02x", pix.val[k]);
        std::printf(p + 1 < rows * cols ? " " : "\n");
    }
    while (!s.empty()) s.read();
}

template <int T, int K>
void morph_case(bool dilate, int rows, int cols) {
    hls::Mat<R, C, T> src(rows, cols), dst(rows, cols);
    for (int p = 0; p < rows * cols; p++) {
        hls::Scalar<HLS_MAT_CN(T), unsigned char> pix;
        for (int k = 0; k < HLS_MAT_CN(T); k++) {
            unsigned v;
            std::cin >> std::hex >> v;
            pix.val[k] = (unsigned char)v;
        }
        src << pix;
    }
    if (K == 3) {
        if (dilate) hls::Dilate(src, dst); else hls::Erode(src, dst);
    } else {
        hls::Window<K, K, unsigned char> kernel;
        for (int r = 0; r < K; r++) for (int c = 0; c < K; c++) kernel.val[r][c] = 1;
        if (dilate) hls::Dilate<hls::MORPH_RECT, 1>(src, dst, kernel);
        else hls::Erode<hls::MORPH_RECT, 1>(src, dst, kernel);
    }
    hls::stream<beat_t> out;
    hls::Mat2AXIvideo(dst, out);
    for (int p = 0; p < rows * cols; p++) {
        beat_t b = out.read();
        std::printf("%08x/%x/%d/%d", b.data.to_uint(), b.keep.to_uint(), b.user.to_int(), b.last.to_int());
        std::printf(p + 1 < rows * cols ? " " : "\n");
    }
}

template <int T>
void morph_k(bool dilate, int k, int rows, int cols) {
    switch (k) {
    case 1: morph_case<T, 1>(dilate, rows, cols); break;
    case 3: morph_case<T, 3>(dilate, rows, cols); break;
    default: morph_case<T, 5>(dilate, rows, cols); break;
    }
}

int main() {
    std::string what;
    while (std::cin >> what) {
        if (what == "axivideo") {
            int rows, cols, cn, n;
            std::cin >> std::dec >> rows >> cols >> cn >> n;
            if (cn == 1) axivideo_case<HLS_8UC1>(rows, cols, n);
            else if (cn == 3) axivideo_case<HLS_8UC3>(rows, cols, n);
            else axivideo_case<HLS_8UC4>(rows, cols, n);
        } else if (what == "morph") {
            int dilate, k, rows, cols, cn;
            std::cin >> std::dec >> dilate >> k >> rows >> cols >> cn;
            if (cn == 1) morph_k<HLS_8UC1>(dilate, k, rows, cols);
            else if (cn == 3) morph_k<HLS_8UC3>(dilate, k, rows, cols);
            else morph_k<HLS_8UC4>(dilate, k, rows, cols);
        } else if (what == "apuint") {
            ap_uint<8> a = -1;                 // all ones
            ap_uint<8> b = 300;                // wraps modulo 256
            ap_uint<12> c = 0;
            c.range(11, 4) = 0xAB;             // a field write
            c[0] = 1;
            ap_uint<32> d = 0xFFFFFFFFu;
            d++;                               // wraps to 0
            ap_uint<4> e = 9;
            e += 9;                            // 18 mod 16 = 2
            ap_uint<64> f = -1;
            std::printf("%u %u %x %u %u %u %d %llx %u\n", a.to_uint(), b.to_uint(), c.to_uint(),
                        (unsigned)c(11, 8), d.to_uint(), e.to_uint(), (int)c[4],
                        (unsigned long long)f, (unsigned)a.range(3, 0));
            hls::stream<ap_uint<8> > s("probe");
            ap_uint<8> empty_read = s.read();  // warns, returns 0
            std::printf("%u %d\n", empty_read.to_uint(), (int)s.empty());
        }
    }
    return 0;
}
"""


@pytest.fixture(scope="module")
def probe(tmp_path_factory: pytest.TempPathFactory) -> Path:
    require_cxx()
    folder = tmp_path_factory.mktemp("probe")
    (folder / "probe.cpp").write_text(PROBE)
    proc = subprocess.run(["g++", "-std=c++14", "-Wall", "-Werror", "-O1", f"-I{INCLUDE_DIR}",
                           "-o", str(folder / "probe"), str(folder / "probe.cpp")],
                          capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    return folder / "probe"


def _run(probe: Path, text: str) -> subprocess.CompletedProcess:
    proc = subprocess.run([str(probe)], input=text, capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    return proc


def test_ap_uint_and_stream_semantics(probe: Path) -> None:
    proc = _run(probe, "apuint\n")
    assert proc.stdout.splitlines() == ["255 44 ab1 10 0 2 1 ffffffffffffffff 15", "0 1"]
    assert "WARNING: Hls::stream 'probe' is read while empty" in proc.stderr


def _damaged_streams(rng: np.random.Generator, count: int) -> list[tuple[int, int, int, list[Beat]]]:
    cases = []
    while len(cases) < count:
        rows, cols, cn = int(rng.integers(1, 5)), int(rng.integers(1, 6)), int(rng.choice([1, 3, 4]))
        beats = [Beat(int(rng.integers(0, 2**32)), 0xF, tuser=(i == 0), tlast=(i % cols == cols - 1))
                 for i in range(rows * cols)]
        kind = len(cases) % 6
        if kind == 1:    # a lost TLAST
            i = int(rng.integers(0, len(beats)))
            beats[i] = Beat(beats[i].tdata, 0xF, beats[i].tuser, False)
        elif kind == 2:  # an early TLAST
            i = int(rng.integers(0, len(beats)))
            beats[i] = Beat(beats[i].tdata, 0xF, beats[i].tuser, True)
        elif kind == 3:  # TUSER inside the frame
            i = int(rng.integers(0, len(beats)))
            beats[i] = Beat(beats[i].tdata, 0xF, True, beats[i].tlast)
        elif kind == 4:  # junk before the start of frame
            beats = [Beat(int(rng.integers(0, 2**32)), 0xF, False, bool(rng.integers(0, 2)))
                     for _ in range(int(rng.integers(1, 4)))] + beats
        elif kind == 5:  # extra beats at the end of the frame
            beats = beats + [Beat(7, 0xF, False, True), Beat(8, 0xF, True, False)]
        cases.append((rows, cols, cn, beats))
    return cases


def test_axivideo2mat_matches_the_reference_model_on_damaged_streams(probe: Path) -> None:
    rng = np.random.default_rng(2024)
    lines, expected = [], []
    for rows, cols, cn, beats in _damaged_streams(rng, 240):
        fifo: Fifo[Beat] = Fifo(None, "axis")
        fifo.extend(beats)
        img = Mat(rows, cols, cn)
        try:
            flags = axivideo2mat_reference(fifo, img)
        except StreamStarvedError:
            continue  # the circuit would wait for ever; C simulation reads zeros instead
        pixels = " ".join("".join(f"{v:02x}" for v in p) for p in img.to_numpy().reshape(-1, cn).tolist())
        expected.append(f"flags {flags} left {fifo.level}\n{pixels}")
        lines.append(f"axivideo {rows} {cols} {cn} {len(beats)}")
        lines += [f"{b.tdata:x} {int(b.tuser)} {int(b.tlast)}" for b in beats]
    assert len(expected) > 150
    assert any(e.startswith("flags 0") for e in expected) and any(not e.startswith("flags 0") for e in expected)
    got = _run(probe, "\n".join(lines) + "\n").stdout.splitlines()
    assert ["\n".join(got[i:i + 2]) for i in range(0, len(got), 2)] == expected


def test_dilate_erode_and_mat2axivideo_match_opencv(probe: Path) -> None:
    rng = np.random.default_rng(7)
    lines, expected = [], []
    for case in range(120):
        rows, cols, cn = int(rng.integers(1, 9)), int(rng.integers(1, 9)), int(rng.choice([1, 3, 4]))
        k, op = int(rng.choice([1, 3, 5])), ("dilate", "erode")[case % 2]
        image = rng.integers(0, 256, (rows, cols, cn), dtype=np.uint8)
        out = morph_fast(image, op, (k, k)).reshape(rows * cols, cn)
        beats = []
        for p, pix in enumerate(out.tolist()):
            word = 0xFFFFFFFF  # Xilinx's Mat2AXIvideo: bits above the last channel stay 1
            for ch, v in enumerate(pix):
                word = (word & ~(0xFF << (8 * ch))) | (v << (8 * ch))
            beats.append(f"{word:08x}/f/{int(p == 0)}/{int(p % cols == cols - 1)}")
        expected.append(" ".join(beats))
        lines.append(f"morph {int(op == 'dilate')} {k} {rows} {cols} {cn}")
        lines.append(" ".join(f"{v:x}" for v in image.reshape(-1).tolist()))
    got = _run(probe, "\n".join(lines) + "\n").stdout.splitlines()
    assert got == expected
