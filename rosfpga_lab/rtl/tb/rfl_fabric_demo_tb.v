// rfl_fabric_demo_tb -- the peer of notebook 12's run (rosfpga_lab/rtl/fabricdemo.py): plays
// whole GMII frames (preamble, SFD and FCS included) into rfl_fabric_top's GMII receive side, one
// after the other with GAP idle clocks between, answers the node's ARP request for the peer with
// the ARP reply frame, and dumps the signals fabricdemo.DUMP_SIGNALS names. It ends HOLD clocks
// after EXPECT IPv4 frames came out of the GMII send side, or at MAX_CLOCKS.
// rfl_fabric_demo_params.vh (written by fabricdemo) defines the top's parameters (RFL_DEMO_PARAMS),
// its configuration inputs, the sizes of the frame memory and the dump's file name.
// The lab runs it on Verilator (--binary --timing --trace): Icarus loops at time 0 in LiteX's Verilog.
`timescale 1ns/1ps
`default_nettype none
`include "rfl_fabric_demo_params.vh"

module tb;
    reg clk = 1'b0;
    reg rst_n = 1'b0;
    always #4 clk = !clk;                       // 125 MHz: GMII's byte clock

    reg [7:0] rxd = 8'd0;
    reg rx_dv = 1'b0;
    wire [7:0] txd;
    wire tx_en, status_valid;
    wire [7:0] status;
    // the stages' streams, read from inside the top (the dump keeps this scope only)
    wire [7:0] le_rx_data = dut.le_rx_data;             // LiteEth's UDP payload out
    wire le_rx_valid = dut.le_rx_valid, le_rx_ready = dut.le_rx_ready;
    wire le_rx_last = dut.le_rx_last;
    wire [7:0] p_rx_tdata = dut.p_rx_tdata;             // rfl_udp_port's, whole datagrams
    wire p_rx_tvalid = dut.p_rx_tvalid, p_rx_tready = dut.p_rx_tready;
    wire p_rx_tlast = dut.p_rx_tlast;
    wire [3:0] rx_state = dut.u_node.u_rx.st;           // rfl_rtps_rx's walk
    wire [7:0] rx_tdata = dut.u_node.rx_tdata;          // the sample's bytes
    wire rx_tvalid = dut.u_node.rx_tvalid, rx_tready = dut.u_node.rx_tready;
    wire rx_tlast = dut.u_node.rx_tlast;
    wire [7:0] rec_tdata = dut.u_node.rec_tdata;        // the generated CDR subscriber's input
    wire rec_tvalid = dut.u_node.rec_tvalid, rec_tready = dut.u_node.rec_tready;
    wire [7:0] pub_tdata = dut.u_node.pub_tdata;        // the generated CDR publisher's output
    wire pub_tvalid = dut.u_node.pub_tvalid, pub_tready = dut.u_node.pub_tready;
    wire [7:0] tx_tdata = dut.u_node.tx_tdata;          // rfl_rtps_tx's datagram
    wire tx_tvalid = dut.u_node.tx_tvalid, tx_tready = dut.u_node.tx_tready;
    wire tx_tlast = dut.u_node.tx_tlast;
    wire [7:0] le_tx_data = dut.le_tx_data;             // to LiteEth
    wire le_tx_valid = dut.le_tx_valid, le_tx_ready = dut.le_tx_ready;
    wire le_tx_last = dut.le_tx_last;
    /*verilator tracing_off*/
    wire tx_er;
    /* verilator lint_off UNUSEDSIGNAL */
    wire [15:0] credit;
    wire [31:0] c0, c1, c2, c3, c4, c5, c6, c7, c8, c9, c10, c11, c12, c13, c14;
    /* verilator lint_on UNUSEDSIGNAL */

    rfl_fabric_top #(`RFL_DEMO_PARAMS) dut (
        .clk(clk), .rst_n(rst_n), .cfg_mac(`RFL_DEMO_MAC), .cfg_ip(`RFL_DEMO_IP),
        .cfg_learn(1'b0), .cfg_peer_ip(`RFL_DEMO_PEER_IP), .cfg_peer_meta_port(`RFL_DEMO_PEER_META),
        .cfg_peer_user_port(`RFL_DEMO_PEER_USER), .cfg_reader(`RFL_DEMO_READER),
        .cfg_writer(`RFL_DEMO_WRITER), .cfg_time(`RFL_DEMO_TIME), .send_sedp(1'b0),
        .gmii_rxd(rxd), .gmii_rx_dv(rx_dv), .gmii_rx_er(1'b0),
        .gmii_txd(txd), .gmii_tx_en(tx_en), .gmii_tx_er(tx_er),
        .status_valid(status_valid), .status(status), .credit(credit),
        .cnt_samples(c0), .cnt_answers(c1), .cnt_no_credit(c2), .cnt_rx_packets(c3),
        .cnt_rx_error(c4), .cnt_rx_length(c5), .cnt_rx_overflow(c6), .cnt_tx_packets(c7),
        .cnt_tx_overflow(c8), .cnt_rx_port(c9), .cnt_rx_header(c10), .cnt_rx_other(c11),
        .cnt_peer_learned(c12), .cnt_peer_refused(c13), .cnt_peer_other(c14));

    // frame 0 the ARP reply, frames 1.. the input; each a length, then its bytes
    reg [7:0] mem [0:`RFL_DEMO_BYTES-1];
    reg [15:0] len [0:`RFL_DEMO_FRAMES-1];
    initial begin
        $readmemh("rfl_fabric_demo_rx.hex", mem);
        $readmemh("rfl_fabric_demo_len.hex", len);
    end

    // the send side: each frame's first 32 bytes after the SFD, to see ARP requests and IPv4
    reg [7:0] head [0:31];
    integer tx_at = 0, ipv4 = 0, arp_asks = 0;
    reg was_en = 1'b0;
    always @(posedge clk) begin
        was_en <= tx_en;
        if (tx_en) begin
            if (tx_at >= 8 && tx_at < 40) head[tx_at - 8] <= txd;
            tx_at <= tx_at + 1;
        end else if (was_en) begin
            tx_at <= 0;
            if (head[12] == 8'h08 && head[13] == 8'h00) ipv4 <= ipv4 + 1;
            if (head[12] == 8'h08 && head[13] == 8'h06 && head[20] == 8'h00 && head[21] == 8'h01)
                arp_asks <= arp_asks + 1;
        end
    end

    integer start [0:`RFL_DEMO_FRAMES-1];
    integer k, n, clocks, answered;
    task play(input integer f);
        begin
            for (n = 0; n < len[f]; n = n + 1) begin
                @(negedge clk);
                rxd = mem[start[f] + n];
                rx_dv = 1'b1;
            end
            @(negedge clk);
            rxd = 8'd0;
            rx_dv = 1'b0;
            repeat (`RFL_DEMO_GAP) @(negedge clk);
        end
    endtask

    initial begin
        $dumpfile(`RFL_DEMO_VCD);
        $dumpvars(1, tb);
        start[0] = 0;
        for (k = 1; k < `RFL_DEMO_FRAMES; k = k + 1) start[k] = start[k - 1] + len[k - 1];
        repeat (10) @(negedge clk);
        rst_n = 1'b1;
        repeat (`RFL_DEMO_GAP) @(negedge clk);
        answered = 0;
        for (k = 1; k < `RFL_DEMO_FRAMES; k = k + 1) play(k);
        clocks = 0;
        while (ipv4 < `RFL_DEMO_EXPECT && clocks < `RFL_DEMO_MAX_CLOCKS) begin
            if (arp_asks > answered) begin
                answered = answered + 1;
                play(0);
            end else begin
                @(negedge clk);
                clocks = clocks + 1;
            end
        end
        repeat (`RFL_DEMO_HOLD) @(negedge clk);
        $display("RFL_DEMO_DONE ipv4=%0d arp=%0d", ipv4, arp_asks);
        $finish;
    end
endmodule

`default_nettype wire
