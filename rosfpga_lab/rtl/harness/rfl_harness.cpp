// rfl_harness.cpp -- the fast simulation of the whole circuit: one evaluation per clock of the
// Verilated rfl_harness (rfl_node plus read-only stream taps), no --timing, frames in and out
// through memory. It does clock for clock what rfl_tb.v does (same reset, same xorshift
// draws in the same order, same sampling before each rising edge), so the bytes, statuses
// and cycle counts are those of the Verilog testbench.
//
// Batch mode (the testbench's plus-arguments):
//   rfl_harness +input=FILE [+output=FILE +status=FILE +stats=FILE +seed=N +gap=P +bp=P
//               +idle_limit=N +beats_in=FILE +beats_out=FILE]
// Serve mode (a long-lived process; the circuit keeps its state between requests):
//   rfl_harness --serve [+seed=N +gap=P +bp=P +idle_limit=N]
//   request on stdin:  "RFLQ" u32 length, then length bytes (one or more TCPROS frames)
//   reply on stdout:   "RFLR" u32 flags (1 input ended inside a frame, 2 stalled)
//                      u64 clocks (this request)  u64 span (first byte into the subscriber
//                      to last byte out, 0 without output)  u32 statuses  u32 output bytes,
//                      then per status u32 offset (in the request) u32 code, then the bytes.
//   A request of length 0 (or end of input) ends the process.
#include "Vrfl_harness.h"
#include "Vrfl_harness___024root.h"
#include "verilated.h"

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>
#ifdef __linux__
#include <fstream>
#include <link.h>
#include <sys/mman.h>
#endif

static const int NS = 9;

// How the model is evaluated per clock. The inputs are registered in rfl_harness.v and the
// falling edge changes no register, so one evaluation at the rising edge does a clock, with
// the next clock's inputs set just before it. Verilator's eval() would add an input region,
// the trigger loops, a garbage sweep and a message-queue flush (four mutex operations): a
// third of the time here. So by default (RFL_EVAL_NBA) the harness marks the clock's edge
// and runs the model's nonblocking region, all there is to a clock of this single-clock
// design (sim.py and a generated project's Makefile build it so only when the generated model
// has no input or active region; the recipe: rosfpga_lab/hls/rtlbuild.py);
// RFL_EVAL_ROOT calls the model's inner eval and tells the edge detector the clock went low;
// RFL_EVAL_PLAIN evaluates both edges with eval(). Both fall back in that order when a
// Verilator's model lacks what a mode calls.
#if defined(RFL_EVAL_PLAIN)
#define RFL_EVAL(t) (t)->eval()
#define RFL_FALL(t) RFL_EVAL(t)
#elif defined(RFL_EVAL_ROOT)
void Vrfl_harness___024root___eval(Vrfl_harness___024root* vlSelf);
#define RFL_EVAL(t) Vrfl_harness___024root___eval((t)->rootp)
#define RFL_FALL(t) ((t)->rootp->__Vtrigprevexpr___TOP__clk__0 = 0)
#else
void Vrfl_harness___024root___eval_nba(Vrfl_harness___024root* vlSelf);
#define RFL_EVAL(t) ((t)->rootp->__VnbaTriggered[0] = 1, Vrfl_harness___024root___eval_nba((t)->rootp))
#define RFL_FALL(t) ((void)0)
#endif

// The program's machine code on one 2 MiB page. On a virtual machine, the same binary ran at
// 55 ms or at 110 ms a frame depending on the physical pages its code was read into (dropping
// the page cache turned a slow copy into a fast one); the huge page is placed by chance too, so
// it helps on some machines and days, not all (tests/benchmarks/bench_rtl.py measures it).
// Linked with 2 MiB segment alignment
// (HUGE_TEXT_LDFLAGS of rosfpga_lab/hls/rtlbuild.py), the code segment starts on a 2 MiB
// boundary: it is copied into an anonymous transparent huge page, which then replaces the
// file's pages at the same addresses. Without that alignment, without transparent huge pages, or when a step fails,
// the code stays where the loader put it. RFL_NO_HUGE_TEXT=1 in the environment skips it.
#ifdef __linux__
static const uintptr_t HUGE_PAGE = (uintptr_t)2 << 20;

static bool huge_pages_allowed() {
    std::ifstream f("/sys/kernel/mm/transparent_hugepage/enabled");
    std::string mode;
    std::getline(f, mode);
    return mode.find("[always]") != std::string::npos || mode.find("[madvise]") != std::string::npos;
}

static int huge_text_segment(struct dl_phdr_info* info, size_t, void*) {
    if (info->dlpi_name && info->dlpi_name[0]) return 0;     // a shared library: not ours
    for (int i = 0; i < info->dlpi_phnum; ++i) {
        const ElfW(Phdr)& ph = info->dlpi_phdr[i];
        if (ph.p_type != PT_LOAD || !(ph.p_flags & PF_X)) continue;
        const uintptr_t start = info->dlpi_addr + ph.p_vaddr;
        if (ph.p_align < HUGE_PAGE || (start & (HUGE_PAGE - 1)) != 0) return 1;
        const size_t len = (ph.p_memsz + HUGE_PAGE - 1) & ~(HUGE_PAGE - 1);
        // the huge page also covers the rest of its 2 MiB after the code: that must be free
        const uintptr_t code_end = (start + ph.p_memsz + 4095) & ~(uintptr_t)4095;
#ifdef MAP_FIXED_NOREPLACE
        if (code_end < start + len) {
            void* probe = mmap((void*)code_end, start + len - code_end, PROT_NONE,
                               MAP_PRIVATE | MAP_ANONYMOUS | MAP_FIXED_NOREPLACE, -1, 0);
            if (probe == MAP_FAILED) return 1;
            if (probe != (void*)code_end) { munmap(probe, start + len - code_end); return 1; }
            munmap(probe, start + len - code_end);
        }
#else
        return 1;
#endif
        char* raw = (char*)mmap(nullptr, len + HUGE_PAGE, PROT_READ | PROT_WRITE,
                                MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
        if (raw == MAP_FAILED) return 1;
        char* copy = (char*)(((uintptr_t)raw + HUGE_PAGE - 1) & ~(HUGE_PAGE - 1));
        if (copy > raw) munmap(raw, copy - raw);                  // keep the aligned part
        if (raw + HUGE_PAGE > copy) munmap(copy + len, raw + HUGE_PAGE - copy);
        if (madvise(copy, len, MADV_HUGEPAGE) != 0) { munmap(copy, len); return 1; }
        memcpy(copy, (const void*)start, ph.p_memsz);
        if (mprotect(copy, len, PROT_READ | PROT_EXEC) != 0 ||
            mremap(copy, len, len, MREMAP_MAYMOVE | MREMAP_FIXED, (void*)start) == MAP_FAILED)
            munmap(copy, len);
        return 1;
    }
    return 1;
}
#endif

static uint32_t xorshift(uint32_t x) {
    uint32_t y = x ^ (x << 13);
    y = y ^ (y >> 17);
    return y ^ (y << 5);
}

static bool plusarg(int argc, char** argv, const char* name, std::string& out) {
    size_t n = strlen(name);
    for (int i = 1; i < argc; ++i) {
        if (argv[i][0] == '+' && strncmp(argv[i] + 1, name, n) == 0 && argv[i][n + 1] == '=') {
            out = argv[i] + n + 2;
            return true;
        }
    }
    return false;
}

static long long plusint(int argc, char** argv, const char* name, long long dflt) {
    std::string v;
    return plusarg(argc, argv, name, v) ? atoll(v.c_str()) : dflt;
}

struct Sim {
    Vrfl_harness* top;
    uint32_t rnd;
    uint32_t gap, bp;
    uint64_t idle_limit;
    uint64_t cycle = 0, idle = 0, done_for = 0, sub_bytes = 0, frame_off = 0;
    // Per stream: the first and last clock of a handshake and their count. They are kept per
    // value of the handshake word hs (NS bits), not per stream: while a frame streams, hs
    // changes on most clocks (a pixel's beat every fourth), so following each stream's runs
    // cost some 35 instructions a clock (callgrind) and this a few. clocks_of[v] counts the
    // clocks with hs == v and last_of[v] is the last of them; first[i] is kept as stream i's
    // first handshake comes (`seen`: the streams that had one); span() sums over the values.
    static const uint32_t NV = 1u << NS;
    uint64_t first[NS] = {0}, clocks_of[NV] = {0}, last_of[NV] = {0};
    uint32_t seen = 0;
    long frames = 0, refused = 0;
    // the input of the current run
    const uint8_t* in = nullptr;
    size_t in_len = 0, in_pos = 0;
    bool eof = false;
    std::vector<uint8_t> out;   // reserved to the input's size: a frame out is as long as in
    std::vector<std::pair<uint64_t, int>> statuses;
    uint64_t req_first = 0, req_last = 0;   // this run's first rx and last tx handshake
    FILE* fbin = nullptr;
    FILE* fbout = nullptr;
    bool stats = false;         // keep the per-stream spans (first, last, count)

    Sim(uint32_t seed, uint32_t gap_, uint32_t bp_, uint64_t limit)
        : top(new Vrfl_harness), rnd(seed == 0 ? 0x12345678u : seed), gap(gap_), bp(bp_),
          idle_limit(limit) {
        top->clk = 0; top->rst_n = 0; top->s_tvalid = 0; top->s_tdata = 0; top->m_tready = 0;
        top->eval();
        for (int i = 0; i < 4; ++i) {
            top->clk = 1; top->eval();
            top->clk = 0; top->eval();
        }
        top->rst_n = 1;
        top->eval();
    }
    ~Sim() { top->final(); delete top; }

    static void beat(FILE* f, uint64_t w) {
        // {tlast, tuser, tkeep[3:0], tdata[31:0]}: "%08x %x %x %x" as rfl_tb.v writes it
        const unsigned hi = (unsigned)(w >> 32);
        fprintf(f, "%08x %x %x %x\n", (unsigned)(w & 0xffffffffu), hi & 0xf, (hi >> 4) & 1,
                (hi >> 5) & 1);
    }

    // The streams whose first handshake is in this clock (hs: those with one now).
    void first_seen(uint32_t hs) {
        for (uint32_t m = hs & ~seen; m; m &= m - 1) first[__builtin_ctz(m)] = cycle;
        seen |= hs;
    }

    // Bytes of the input the circuit took (a byte offered is held until it is taken).
    uint64_t taken() const { return in_pos - (top->s_tvalid ? 1 : 0); }

    // Stream i's (first, last, count) up to the current clock.
    void span(int i, uint64_t& f, uint64_t& l, uint64_t& n) const {
        f = first[i];
        l = n = 0;
        for (uint32_t v = 0; v < NV; ++v) {
            if (!(v & (1u << i))) continue;
            n += clocks_of[v];
            if (clocks_of[v] && last_of[v] > l) l = last_of[v];
        }
    }

    // Run until the input is used up and the circuit idle for 8 clocks (0), the input ended
    // inside a frame (1) or nothing moved for idle_limit clocks with input left (2).
    int run() {
        eof = false;
        out.reserve(out.size() + in_len + 64);
        req_first = req_last = 0;
        done_for = 0;
        idle = 0;
        // The loop is specialised: without gaps or backpressure no random number is drawn (the
        // draws then decide nothing), and the per-stream spans and beat files only when asked.
        const bool random = gap != 0 || bp != 0, taps = stats || fbin || fbout;
        if (random) return taps ? loop<true, true>() : loop<true, false>();
        return taps ? loop<false, true>() : loop<false, false>();
    }

    template <bool Random, bool Taps>
    int loop() {
        Vrfl_harness* const t = top;
        // the input rfl_node sees in this clock: the ports hold what was set before its edge
        bool sv = t->s_tvalid;
        uint8_t sd = t->s_tdata;
        int rc;
        for (;;) {
            // the circuit's outputs in this clock, before its rising edge
            const uint32_t hs = t->hs;
            const bool s_tready = t->s_tready;
            ++cycle;
            // the inputs of the next clock, as rfl_tb.v's nonblocking drives decide them
            bool nv = sv;
            uint8_t nd = sd;
            if ((!sv || s_tready) && !eof) {
                bool take = true;
                if (Random) {
                    rnd = xorshift(rnd);
                    take = (rnd % 1000) >= gap;
                }
                if (take) {
                    if (in_pos >= in_len) { eof = true; nv = false; }
                    else { nd = in[in_pos++]; nv = true; }
                } else {
                    nv = false;
                }
            }
            if (hs & 128) out.push_back(t->m_tdata);
            bool nr = true;
            if (Random) {
                rnd = xorshift(rnd);
                nr = (rnd % 1000) >= bp;
            }
            // as the testbench: a status comes a clock after its frame's deciding byte, when the
            // next frame may already start (two records), so it is kept before frame_off moves on
            if (t->status_valid) {
                statuses.emplace_back(frame_off, t->status);
                ++frames;
                if (t->status != 0) ++refused;
            }
            if (t->frame_start) frame_off = sub_bytes;
            if (hs & 1) ++sub_bytes;
            if (hs) {
                if (Taps) {
                    ++clocks_of[hs];
                    last_of[hs] = cycle;
                    if (hs & ~seen) first_seen(hs);
                }
                if ((hs & 1) && !req_first) req_first = cycle;
                if (hs & 128) req_last = cycle;
                idle = 0;
            } else {
                ++idle;
            }
            done_for = (eof && !t->busy && !sv) ? done_for + 1 : 0;
            t->s_tvalid = nv; t->s_tdata = nd; t->m_tready = nr;
            t->clk = 1; RFL_EVAL(t);
            t->clk = 0; RFL_FALL(t);
            if (Taps) {     // the beats of the clock just ended, held by rfl_harness.v
                if (fbin && (hs & 4)) beat(fbin, t->beat_in);
                if (fbout && (hs & 16)) beat(fbout, t->beat_out);
            }
            sv = nv; sd = nd;
            if (done_for == 8) { rc = 0; break; }
            if (idle >= idle_limit) { rc = eof ? 1 : 2; break; }
        }
        return rc;
    }
};

static bool read_all(FILE* f, void* buf, size_t n) {
    return n == 0 || fread(buf, 1, n, f) == n;
}

static int serve(Sim& sim) {
    std::vector<uint8_t> buf;
    for (;;) {
        uint8_t head[8];
        if (!read_all(stdin, head, 8)) return 0;
        if (memcmp(head, "RFLQ", 4) != 0) { fprintf(stderr, "rtlsim: ERROR: bad request\n"); return 1; }
        uint32_t len;
        memcpy(&len, head + 4, 4);
        if (len == 0) return 0;
        buf.resize(len);
        if (!read_all(stdin, buf.data(), len)) { fprintf(stderr, "rtlsim: ERROR: short request\n"); return 1; }
        sim.in = buf.data(); sim.in_len = len; sim.in_pos = 0;
        sim.out.clear(); sim.statuses.clear();
        const uint64_t c0 = sim.cycle, sub0 = sim.sub_bytes;
        const int rc = sim.run();
        uint32_t flags = rc == 1 ? 1u : rc == 2 ? 2u : 0u;
        uint64_t clocks = sim.cycle - c0;
        uint64_t span = (sim.req_first && sim.req_last) ? sim.req_last - sim.req_first + 1 : 0;
        uint32_t ns = (uint32_t)sim.statuses.size(), no = (uint32_t)sim.out.size();
        fwrite("RFLR", 1, 4, stdout);
        fwrite(&flags, 4, 1, stdout);
        fwrite(&clocks, 8, 1, stdout);
        fwrite(&span, 8, 1, stdout);
        fwrite(&ns, 4, 1, stdout);
        fwrite(&no, 4, 1, stdout);
        for (auto& s : sim.statuses) {
            uint32_t off = (uint32_t)(s.first - sub0), code = (uint32_t)s.second;
            fwrite(&off, 4, 1, stdout);
            fwrite(&code, 4, 1, stdout);
        }
        if (no) fwrite(sim.out.data(), 1, no, stdout);
        fflush(stdout);
        if (rc == 2) return 2;
    }
}

int main(int argc, char** argv) {
#ifdef __linux__
    const char* no_huge = getenv("RFL_NO_HUGE_TEXT");
    if (!(no_huge && *no_huge && strcmp(no_huge, "0") != 0) && huge_pages_allowed())
        dl_iterate_phdr(huge_text_segment, nullptr);
#endif
    Verilated::commandArgs(argc, argv);
    const long long seed = plusint(argc, argv, "seed", 1);
    const long long gap = plusint(argc, argv, "gap", 0), bp = plusint(argc, argv, "bp", 0);
    const long long limit = plusint(argc, argv, "idle_limit", 1000000);
    Sim sim((uint32_t)seed, (uint32_t)gap, (uint32_t)bp, (uint64_t)limit);
    for (int i = 1; i < argc; ++i) if (strcmp(argv[i], "--serve") == 0) return serve(sim);

    std::string path;
    if (!plusarg(argc, argv, "input", path)) { fprintf(stderr, "rtlsim: ERROR: no +input=FILE\n"); return 1; }
    FILE* fin = fopen(path.c_str(), "rb");
    if (!fin) { fprintf(stderr, "rtlsim: ERROR: cannot open the input %s\n", path.c_str()); return 1; }
    std::vector<uint8_t> input;
    uint8_t chunk[1 << 16];
    size_t got;
    while ((got = fread(chunk, 1, sizeof chunk, fin)) > 0) input.insert(input.end(), chunk, chunk + got);
    fclose(fin);
    std::string out_path = "output.bin", status_path = "status.txt", stats_path = "stats.txt";
    plusarg(argc, argv, "output", out_path);
    plusarg(argc, argv, "status", status_path);
    plusarg(argc, argv, "stats", stats_path);
    FILE* fout = fopen(out_path.c_str(), "wb");
    FILE* fstatus = fopen(status_path.c_str(), "w");
    FILE* fstats = fopen(stats_path.c_str(), "w");
    if (!fout || !fstatus || !fstats) { fprintf(stderr, "rtlsim: ERROR: cannot open an output file\n"); return 1; }
    if (plusarg(argc, argv, "beats_in", path)) sim.fbin = fopen(path.c_str(), "w");
    if (plusarg(argc, argv, "beats_out", path)) sim.fbout = fopen(path.c_str(), "w");
    sim.stats = true;
    sim.in = input.data(); sim.in_len = input.size(); sim.in_pos = 0;
    const int rc = sim.run();
    for (int i = 0; i < NS; ++i) {
        uint64_t f, l, n;
        sim.span(i, f, l, n);
        fprintf(fstats, "%d %llu %llu %llu\n", i, (unsigned long long)f, (unsigned long long)l,
                (unsigned long long)n);
    }
    fprintf(fstats, "cycles %llu\n", (unsigned long long)sim.cycle);
    fprintf(fstats, "framing %u\n", (unsigned)sim.top->framing);
    for (auto& s : sim.statuses) fprintf(fstatus, "%llu %d\n", (unsigned long long)s.first, s.second);
    if (!sim.out.empty()) fwrite(sim.out.data(), 1, sim.out.size(), fout);
    fclose(fout); fclose(fstatus); fclose(fstats);
    if (sim.fbin) fclose(sim.fbin);
    if (sim.fbout) fclose(sim.fbout);
    printf("rtlsim: %ld frame(s) in, %ld refused, %llu bytes in, %llu bytes out, %llu clocks\n",
           sim.frames, sim.refused, (unsigned long long)sim.taken(),
           (unsigned long long)sim.out.size(), (unsigned long long)sim.cycle);
    if (rc == 2) { printf("rtlsim: ERROR: stalled: no handshake for +idle_limit clocks\n"); return 1; }
    if (rc == 1) printf("rtlsim: the input ended inside a frame (the circuit waits for the rest)\n");
    return 0;
}
