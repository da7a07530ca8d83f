// rfl_fabric_sim.cpp -- the ROS 2 node in the fabric on the network (rfl_fabric_top, GMII
// variant) as a long-lived Verilated process that exchanges whole Ethernet frames with its host
// (rosfpga_lab.rtl.fabricsim builds it and speaks its protocol).
//
// The PHY side: a frame given by the host (FCS included) goes into gmii_rxd one byte a clock
// after seven 0x55 and the SFD 0xD5, with at least IFG idle clocks before the next; what the
// circuit sends (gmii_tx_en high) is collected and, when tx_en falls, given back without its
// preamble and SFD (FCS included; the host checks it). The clock keeps running when nothing
// comes in (the circuit's SPDP announcements are periodic), at most +rate=N clocks per second
// of wall time (0: as fast as the model runs), up to +max_clocks=N (0: no bound).
//
// Records, both ways: a tag byte, a u32 length (little endian), that many bytes.
//   host -> sim  'C' config: u64 mac, u32 ip, u32 peer_ip, u16 peer_meta_port,
//                    u16 peer_user_port, u32 reader, u32 writer, u64 time, u8 learn
//                    (37 bytes, LE; learn: cfg_learn, the peer from SPDP);
//                    the first record must be one (reset is released after it), later ones
//                    change the registers between frames
//                'F' a frame for gmii_rxd;  'S' a one-clock send_sedp pulse;
//                'K' counters now;  'Q' (or end of input): counters, then exit
//   sim -> host  'F' a frame from gmii_txd;  'K' u64 clocks, then the counters as u32 in
//                rosfpga_lab.rtl.fabricsim.COUNTERS' order: the top's cnt_* and credit, then
//                the generated subscriber's verdicts (status_valid pulses), the refusals among
//                them (status not 0) and the last refusal's code, then the top's cnt_peer_*
//                'N' after each 'K': the RTPS stages' counters inside rfl_fabric_node as u32
//                in rosfpga_lab.rtl.fabriccounters.NODE_COUNTERS' order (rfl_node_counters.h and
//                the .vlt that keeps those wires public are generated from that list)
#include "Vrfl_fabric_top.h"
#include "Vrfl_fabric_top___024root.h"
#include "rfl_node_counters.h"
#include "verilated.h"

#include <poll.h>
#include <time.h>
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <deque>
#include <string>
#include <vector>

static const int IFG = 12;
static const int RESET_CLOCKS = 10;
static const size_t MAX_RECORD = 1 << 16;

static long long plusint(int argc, char** argv, const char* name, long long dflt) {
    size_t n = strlen(name);
    for (int i = 1; i < argc; ++i)
        if (argv[i][0] == '+' && strncmp(argv[i] + 1, name, n) == 0 && argv[i][n + 1] == '=')
            return atoll(argv[i] + n + 2);
    return dflt;
}

static double now_s() {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec + ts.tv_nsec * 1e-9;
}

static void put_record(char tag, const uint8_t* data, uint32_t n) {
    uint8_t head[5] = {(uint8_t)tag, (uint8_t)n, (uint8_t)(n >> 8), (uint8_t)(n >> 16),
                       (uint8_t)(n >> 24)};
    fwrite(head, 1, 5, stdout);
    if (n) fwrite(data, 1, n, stdout);
    fflush(stdout);
}

static uint64_t le(const uint8_t* p, int n) {
    uint64_t v = 0;
    for (int i = n - 1; i >= 0; --i) v = (v << 8) | p[i];
    return v;
}

struct Fabric {
    Vrfl_fabric_top* top;
    uint64_t clocks = 0;
    std::deque<std::vector<uint8_t>> rx_queue;
    std::vector<uint8_t> rx_frame;      // preamble, SFD and frame being driven
    size_t rx_at = 0;
    int rx_idle = IFG;
    std::vector<uint8_t> tx_frame;
    bool tx_on = false;
    int sedp = 0;
    uint32_t statuses = 0, refused = 0, last_status = 0;   // the generated subscriber's verdicts

    explicit Fabric(Vrfl_fabric_top* t) : top(t) {}

    void config(const uint8_t* p) {
        top->cfg_mac = le(p, 8);
        top->cfg_ip = (uint32_t)le(p + 8, 4);
        top->cfg_peer_ip = (uint32_t)le(p + 12, 4);
        top->cfg_peer_meta_port = (uint16_t)le(p + 16, 2);
        top->cfg_peer_user_port = (uint16_t)le(p + 18, 2);
        top->cfg_reader = (uint32_t)le(p + 20, 4);
        top->cfg_writer = (uint32_t)le(p + 24, 4);
        top->cfg_time = le(p + 28, 8);
        top->cfg_learn = p[36] & 1;
    }

    bool idle() const { return rx_queue.empty() && rx_frame.empty() && !tx_on; }

    void drive_rx() {
        if (rx_frame.empty() && !rx_queue.empty() && rx_idle >= IFG) {
            rx_frame.assign(7, 0x55);
            rx_frame.push_back(0xD5);
            rx_frame.insert(rx_frame.end(), rx_queue.front().begin(), rx_queue.front().end());
            rx_queue.pop_front();
            rx_at = 0;
        }
        if (!rx_frame.empty()) {
            top->gmii_rx_dv = 1;
            top->gmii_rxd = rx_frame[rx_at++];
            if (rx_at == rx_frame.size()) rx_frame.clear();
            rx_idle = 0;
        } else {
            top->gmii_rx_dv = 0;
            top->gmii_rxd = 0;
            ++rx_idle;
        }
    }

    void collect_tx() {
        if (top->gmii_tx_en) {
            tx_on = true;
            tx_frame.push_back(top->gmii_txd);
        } else if (tx_on) {
            tx_on = false;
            size_t at = 0;
            while (at < tx_frame.size() && tx_frame[at] == 0x55) ++at;
            if (at < tx_frame.size() && tx_frame[at] == 0xD5) ++at;
            put_record('F', tx_frame.data() + at, (uint32_t)(tx_frame.size() - at));
            tx_frame.clear();
        }
    }

    void clock() {
        drive_rx();
        top->send_sedp = sedp > 0;
        if (sedp > 0) --sedp;
        top->clk = 1;
        top->eval();
        collect_tx();
        if (top->status_valid) {
            ++statuses;
            if (top->status != 0) { ++refused; last_status = top->status; }
        }
        top->clk = 0;
        top->eval();
        ++clocks;
    }

    void counters() {
        uint32_t c[19] = {top->cnt_samples, top->cnt_answers, top->cnt_no_credit,
                          top->cnt_rx_packets, top->cnt_rx_error, top->cnt_rx_length,
                          top->cnt_rx_overflow, top->cnt_tx_packets, top->cnt_tx_overflow,
                          top->cnt_rx_port, top->cnt_rx_header, top->cnt_rx_other,
                          (uint32_t)top->credit, statuses, refused, last_status,
                          top->cnt_peer_learned, top->cnt_peer_refused, top->cnt_peer_other};
        uint8_t out[8 + sizeof c];
        for (int i = 0; i < 8; ++i) out[i] = (uint8_t)(clocks >> (8 * i));
        for (int k = 0; k < 19; ++k)
            for (int i = 0; i < 4; ++i) out[8 + 4 * k + i] = (uint8_t)(c[k] >> (8 * i));
        put_record('K', out, sizeof out);
        node_counters();
    }

    void node_counters() {
#define RFL_READ(member) (uint32_t)top->rootp->member,
        const uint32_t c[RFL_NODE_COUNTER_COUNT] = {RFL_NODE_COUNTERS(RFL_READ)};
#undef RFL_READ
        uint8_t out[sizeof c];
        for (size_t k = 0; k < RFL_NODE_COUNTER_COUNT; ++k)
            for (int i = 0; i < 4; ++i) out[4 * k + i] = (uint8_t)(c[k] >> (8 * i));
        put_record('N', out, sizeof out);
    }
};

// Reads what stdin holds (blocking: wait for it) into buf; false at end of input.
static bool fill(std::vector<uint8_t>& buf, bool block) {
    struct pollfd p = {0, POLLIN, 0};
    if (poll(&p, 1, block ? -1 : 0) <= 0) return true;
    uint8_t chunk[65536];
    ssize_t n = read(0, chunk, sizeof chunk);
    if (n <= 0) return false;
    buf.insert(buf.end(), chunk, chunk + n);
    return true;
}

// Takes the whole records in buf; returns false on 'Q'.
static bool take(std::vector<uint8_t>& buf, Fabric& f, bool& configured) {
    size_t at = 0;
    bool go_on = true;
    while (go_on && buf.size() - at >= 5) {
        uint32_t n = (uint32_t)le(&buf[at + 1], 4);
        if (n > MAX_RECORD) {
            fprintf(stderr, "rfl_fabric_sim: a record of %u bytes (at most %zu)\n", n, MAX_RECORD);
            exit(2);
        }
        if (buf.size() - at - 5 < n) break;
        const uint8_t* body = &buf[at + 5];
        switch (buf[at]) {
        case 'C':
            if (n != 37) { fprintf(stderr, "rfl_fabric_sim: config of %u bytes\n", n); exit(2); }
            f.config(body);
            configured = true;
            break;
        case 'F': f.rx_queue.emplace_back(body, body + n); break;
        case 'S': f.sedp = 1; break;
        case 'K': f.counters(); break;
        case 'Q': go_on = false; break;
        default:
            fprintf(stderr, "rfl_fabric_sim: unknown record tag 0x%02x\n", buf[at]);
            exit(2);
        }
        at += 5 + n;
    }
    buf.erase(buf.begin(), buf.begin() + at);
    return go_on;
}

int main(int argc, char** argv) {
    Verilated::commandArgs(argc, argv);
    const long long rate = plusint(argc, argv, "rate", 0);
    const long long max_clocks = plusint(argc, argv, "max_clocks", 0);
    Vrfl_fabric_top* top = new Vrfl_fabric_top;
    Fabric f(top);
    std::vector<uint8_t> buf;
    bool configured = false, open = true;
    while (open && !configured) {
        open = fill(buf, true);
        open = take(buf, f, configured) && open;
    }
    top->rst_n = 0;
    for (int i = 0; i < RESET_CLOCKS; ++i) f.clock();
    top->rst_n = 1;
    const double start = now_s();
    const uint64_t base = f.clocks;
    while (open && (max_clocks == 0 || (long long)f.clocks < max_clocks)) {
        for (int i = 0; i < 256; ++i) f.clock();
        bool more = fill(buf, false);
        open = take(buf, f, configured) && more;
        if (rate > 0 && f.idle()) {
            double ahead = (double)(f.clocks - base) / rate - (now_s() - start);
            if (ahead > 0.001) {
                struct pollfd p = {0, POLLIN, 0};
                poll(&p, 1, (int)(ahead * 1000));
            }
        }
    }
    f.counters();
    top->final();
    delete top;
    return 0;
}
