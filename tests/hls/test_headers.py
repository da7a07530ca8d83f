"""The lab's stand-ins for Xilinx's HLS headers behave as Xilinx's do.

One small C++ probe, compiled once with ``g++ -std=c++14 -Wall -Werror`` against
``rosfpga_lab/hls/include``, checks ``ap_uint`` arithmetic (wrapping, fields, bits) and an
``hls::stream`` read while empty. (The HLS video library's stand-in, ``hls_video.h``, is gone
with the Vivado flavour's use of it; the generated applications keep their own line buffers,
checked against OpenCV by ``test_csim.py``.)
"""

from __future__ import annotations

import subprocess
from pathlib import Path

import pytest

from tests.support.realros import require_cxx
from rosfpga_lab.hls.generator import INCLUDE_DIR

PROBE = r"""
#include <cstdio>
#include <iostream>
#include <string>
#include <ap_axi_sdata.h>
#include <ap_int.h>
#include <hls_stream.h>

int main() {
    std::string what;
    while (std::cin >> what) {
        if (what == "apuint") {
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
