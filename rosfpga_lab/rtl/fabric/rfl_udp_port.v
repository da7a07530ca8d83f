// rfl_udp_port -- the lab's side of the vendored LiteEth UDP/IP core (issue #31, the MAC / ARP /
// IPv4 / UDP stage; vendor/README.md says which core and why): LiteEth's raw UDP user port
// (le_*, 8 bits) to the lab's streams, one UDP payload per 8-bit AXI4-Stream packet (TLAST on
// its last byte), the peer's IP address and the ports as sideband.
//
// Received (m_axis_*, m_udp_* hold for every beat of a packet): the payloads of the UDP datagrams
// LiteEth passes up (vendor/README.md says which: our MAC and IP, or our multicast group; the
// core's ports), each only once it ended good (rfl_udp_store): LiteEth marks a
// frame with a bad FCS only at its end (le_rx_error), and cuts a payload to its UDP
// length without saying when the frame was shorter. Dropped and counted here: le_rx_error
// (cnt_rx_error), a payload whose bytes are not its UDP length (cnt_rx_length: a truncated
// datagram, or an empty one, which LiteEth passes as one padding byte), no room in the
// 2**RX_BITS-byte buffer (cnt_rx_overflow). What LiteEth drops before, it says with a pulse,
// counted here: le_rx_drop_header (cnt_rx_header: a frame cut inside its headers, a bad IPv4
// header, a fragment, lengths that disagree; the generated core's header says which),
// le_rx_drop_other (cnt_rx_other: not for this node: another MAC, IP, protocol or port).
// Sent (s_axis_*; s_udp_* read with the TLAST beat): each payload is stored whole (its length
// goes in the UDP header before its bytes), then given to LiteEth, which resolves the peer's MAC
// by ARP (a peer that does not answer: the datagram is dropped by LiteEth) and sends
// Ethernet/IPv4/UDP (UDP checksum 0, allowed by IPv4). The input waits for room; a payload
// longer than the 2**TX_BITS-byte buffer is dropped and counted (cnt_tx_overflow).
`default_nettype none

module rfl_udp_port #(
    parameter RX_BITS    = 11,                  // receive buffer 2**RX_BITS bytes, 4..15
    parameter TX_BITS    = 11,                  // send buffer 2**TX_BITS bytes, 4..15
    parameter QUEUE_BITS = 2,                   // payloads waiting each way, 2**QUEUE_BITS: 1..6
    parameter COUNT_BITS = 32                   // width of the counters: 1..32
) (
    input  wire                  clk,
    input  wire                  rst_n,
    // LiteEth's raw UDP port (the core's udp_source_* / udp_sink_*)
    input  wire [7:0]            le_rx_data,
    input  wire                  le_rx_valid,
    output wire                  le_rx_ready,
    input  wire                  le_rx_last,
    input  wire                  le_rx_error,
    input  wire [31:0]           le_rx_ip,
    input  wire [15:0]           le_rx_src_port,
    input  wire [15:0]           le_rx_dst_port,
    input  wire [15:0]           le_rx_length,  // the UDP length - 8
    input  wire                  le_rx_drop_header, // one clock a frame LiteEth dropped
    input  wire                  le_rx_drop_other,
    output wire [7:0]            le_tx_data,
    output wire                  le_tx_valid,
    input  wire                  le_tx_ready,
    output wire                  le_tx_last,
    output wire [31:0]           le_tx_ip,
    output wire [15:0]           le_tx_src_port,
    output wire [15:0]           le_tx_dst_port,
    output wire [15:0]           le_tx_length,
    // received payloads
    output wire [7:0]            m_axis_tdata,
    output wire                  m_axis_tvalid,
    input  wire                  m_axis_tready,
    output wire                  m_axis_tlast,
    output wire [31:0]           m_udp_ip,      // the sender's IP address
    output wire [15:0]           m_udp_src_port,
    output wire [15:0]           m_udp_dst_port,
    output wire [15:0]           m_udp_length,  // the payload's bytes
    // payloads to send
    input  wire [7:0]            s_axis_tdata,
    input  wire                  s_axis_tvalid,
    output wire                  s_axis_tready,
    input  wire                  s_axis_tlast,
    input  wire [31:0]           s_udp_ip,      // the peer's IP address
    input  wire [15:0]           s_udp_src_port,
    input  wire [15:0]           s_udp_dst_port,
    output wire [COUNT_BITS-1:0] cnt_rx_packets,    // payloads passed on
    output wire [COUNT_BITS-1:0] cnt_rx_error,      // frames LiteEth marked bad (FCS)
    output wire [COUNT_BITS-1:0] cnt_rx_length,     // payload bytes != UDP length - 8
    output wire [COUNT_BITS-1:0] cnt_rx_overflow,   // no room
    output wire [COUNT_BITS-1:0] cnt_tx_packets,    // payloads taken whole, to be sent
    output wire [COUNT_BITS-1:0] cnt_tx_overflow,   // longer than the send buffer
    output wire [COUNT_BITS-1:0] cnt_rx_header,     // dropped by LiteEth: its headers
    output wire [COUNT_BITS-1:0] cnt_rx_other       // dropped by LiteEth: not for us
);
`ifdef __ICARUS__
    initial begin
        if (COUNT_BITS < 1 || COUNT_BITS > 32) $fatal(1, "rfl_udp_port: COUNT_BITS must be 1..32");
    end
`else
    if (COUNT_BITS < 1 || COUNT_BITS > 32) begin : g_bad_count_bits
        $error("rfl_udp_port: COUNT_BITS must be 1..32");
    end
`endif
    // RX_BITS, TX_BITS and QUEUE_BITS are checked by rfl_udp_store.

    // ---- receive ------------------------------------------------------------------------------
    // LiteEth's stream is registered first (r_*): it comes out of LiteEth's UDP receiver and
    // crossbar through a long combinational path, which the length check and the store's
    // commit logic lengthened past 125 MHz. The receiver never waits (the store discards a
    // payload without room), so the register needs no ready.
    // LiteEth's error flag is taken from whichever beat of the payload carries it.
    reg [7:0] r_data;
    reg r_valid, r_last, r_error;
    reg [31:0] r_ip;
    reg [15:0] r_src_port, r_dst_port, r_length;
    always @(posedge clk) begin
        r_valid <= rst_n && le_rx_valid;
        r_data <= le_rx_data;
        r_last <= le_rx_last;
        r_error <= le_rx_error;
        r_ip <= le_rx_ip;
        r_src_port <= le_rx_src_port;
        r_dst_port <= le_rx_dst_port;
        r_length <= le_rx_length;
    end
    assign le_rx_ready = 1'b1;

    reg [15:0] rx_n;                            // bytes of this payload with this beat
    reg rx_err_seen;
    wire rx_short = (rx_n != r_length);
    wire rx_err = r_error || rx_err_seen;
    wire rx_bad = rx_err || rx_short;
    wire rx_keep, rx_drop, rx_user, rx_store_ready;
    always @(posedge clk) begin
        if (!rst_n) begin
            rx_n <= 16'd1;
            rx_err_seen <= 1'b0;
        end else if (r_valid) begin
            rx_n <= r_last ? 16'd1 : rx_n + 16'd1;
            rx_err_seen <= !r_last && rx_err;
        end
    end

    rfl_udp_store #(.ADDR_BITS(RX_BITS), .QUEUE_BITS(QUEUE_BITS), .META_W(64), .WAIT(0)) u_rx (
        .clk(clk), .rst_n(rst_n),
        .s_axis_tdata(r_data), .s_axis_tvalid(r_valid), .s_axis_tready(rx_store_ready),
        .s_axis_tlast(r_last), .s_axis_tuser(rx_bad),
        .s_meta({r_ip, r_src_port, r_dst_port}),
        .m_axis_tdata(m_axis_tdata), .m_axis_tvalid(m_axis_tvalid),
        .m_axis_tready(m_axis_tready), .m_axis_tlast(m_axis_tlast),
        .m_meta({m_udp_ip, m_udp_src_port, m_udp_dst_port}), .m_len(m_udp_length),
        .done_keep(rx_keep), .done_drop(rx_drop), .done_user(rx_user));
    wire unused_rx_ok = rx_store_ready;         // 1: WAIT 0 never waits

    // ---- send -------------------------------------------------------------------------------
    wire tx_keep, tx_drop, tx_user;
    rfl_udp_store #(.ADDR_BITS(TX_BITS), .QUEUE_BITS(QUEUE_BITS), .META_W(64), .WAIT(1)) u_tx (
        .clk(clk), .rst_n(rst_n),
        .s_axis_tdata(s_axis_tdata), .s_axis_tvalid(s_axis_tvalid),
        .s_axis_tready(s_axis_tready), .s_axis_tlast(s_axis_tlast), .s_axis_tuser(1'b0),
        .s_meta({s_udp_ip, s_udp_src_port, s_udp_dst_port}),
        .m_axis_tdata(le_tx_data), .m_axis_tvalid(le_tx_valid), .m_axis_tready(le_tx_ready),
        .m_axis_tlast(le_tx_last), .m_meta({le_tx_ip, le_tx_src_port, le_tx_dst_port}),
        .m_len(le_tx_length), .done_keep(tx_keep), .done_drop(tx_drop), .done_user(tx_user));

    // ---- counters (saturating) --------------------------------------------------------------
    reg [COUNT_BITS-1:0] c_rx, c_err, c_len, c_ovf, c_tx, c_tovf, c_hdr, c_oth;
    wire [COUNT_BITS-1:0] top = {COUNT_BITS{1'b1}};
    wire rx_fin = r_valid && r_last;
    always @(posedge clk) begin
        if (!rst_n) begin
            c_rx <= {COUNT_BITS{1'b0}};
            c_err <= {COUNT_BITS{1'b0}};
            c_len <= {COUNT_BITS{1'b0}};
            c_ovf <= {COUNT_BITS{1'b0}};
            c_tx <= {COUNT_BITS{1'b0}};
            c_tovf <= {COUNT_BITS{1'b0}};
            c_hdr <= {COUNT_BITS{1'b0}};
            c_oth <= {COUNT_BITS{1'b0}};
        end else begin
            if (rx_keep && c_rx != top) c_rx <= c_rx + 1'b1;
            if (rx_fin && rx_err && c_err != top) c_err <= c_err + 1'b1;
            if (rx_fin && !rx_err && rx_short && c_len != top) c_len <= c_len + 1'b1;
            if (rx_drop && !rx_user && c_ovf != top) c_ovf <= c_ovf + 1'b1;
            if (tx_keep && c_tx != top) c_tx <= c_tx + 1'b1;
            if (tx_drop && !tx_user && c_tovf != top) c_tovf <= c_tovf + 1'b1;
            if (le_rx_drop_header && c_hdr != top) c_hdr <= c_hdr + 1'b1;
            if (le_rx_drop_other && c_oth != top) c_oth <= c_oth + 1'b1;
        end
    end
    assign cnt_rx_packets = c_rx;
    assign cnt_rx_error = c_err;
    assign cnt_rx_length = c_len;
    assign cnt_rx_overflow = c_ovf;
    assign cnt_tx_packets = c_tx;
    assign cnt_tx_overflow = c_tovf;
    assign cnt_rx_header = c_hdr;
    assign cnt_rx_other = c_oth;
endmodule

`default_nettype wire
