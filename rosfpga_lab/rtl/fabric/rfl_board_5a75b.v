// rfl_board_5a75b -- the ROS 2 node in the fabric on a Colorlight 5A-75B v8.0 (LFE5U-25F-6BG256C,
// its first RGMII PHY, a Realtek RTL8211FD): rfl_fabric_top with the ECP5 RGMII LiteEth core
// (RFL_FABRIC_RGMII; the build defines it), its clock from the 25 MHz oscillator through the
// ECP5's PLL, its addresses parameters. Pins: rfl_board_5a75b.lpf (LiteX-Boards' platform file).
// Clocks: clk (125 MHz, the PLL's) runs the node and LiteEth's 8-bit UDP port; eth_clk (52.08 MHz,
// the PLL's) LiteEth's 32-bit core (MAC, ARP, IPv4: a word a clock is the byte rate's half,
// with room for a word's bubble a frame); rgmii_rx_clk (125 MHz from the PHY) LiteEth's
// receive and send side. LiteEth's FIFOs cross between them.
// The addresses and entity ids are parameters the generated project sets (rtl.board): the node's
// MAC and IPv4 address, the reader id the ROM announces. Its one peer it learns from the peers'
// SPDP announcements (cfg_learn: rfl_spdp_peer in rfl_fabric_top), which also sends its SEDP
// to it: nothing of the peer is known at build time. Reset: held while the PLL is not locked
// and for 16 clocks after. SPDP every PERIOD clocks (rfl_fabric_node). No clock of the wall:
// INFO_TS carries TIME. LED (active low): on once a datagram reached the node.
`default_nettype none

module rfl_board_5a75b #(
    parameter [47:0] MAC = 48'h0,               // all from rtl.board.board_parameters
    parameter [31:0] IP = 32'h0,
    parameter [31:0] READER = 32'h0,            // our reader's entity id (cfg_reader)
    parameter [63:0] TIME = 64'h0,              // INFO_TS's time (RTPS Time_t)
`include "rfl_fabric_top_params.vh"          // the rest: rfl_fabric_top's
) (
    input  wire       clk25,                    // the 25 MHz oscillator
    input  wire       rgmii_rx_clk,
    input  wire       rgmii_rx_ctl,
    input  wire [3:0] rgmii_rxd,
    output wire       rgmii_tx_clk,
    output wire       rgmii_tx_ctl,
    output wire [3:0] rgmii_txd,
    output wire       led_n
);
    // 25 MHz in, 125 and 52.08 MHz out: the EHXPLLL settings yowasp-ecppll -i 25 -o 125
    // --clkout1 50 computes (Project Trellis 1.4-82-g3afe7b5: VCO 625 MHz, CLKI_DIV 1,
    // CLKFB_DIV 5, CLKOP_DIV 5, CLKOS_DIV 12; 50 asked, the nearest it makes). In the proof and outside synthesis the
    // oscillator's clock as it is for both, locked.
    wire clk, eth_clk, locked;
`ifdef FORMAL
    assign clk = clk25;
    assign eth_clk = clk25;
    assign locked = 1'b1;
`elsif SYNTHESIS
    /* verilator lint_off UNUSEDSIGNAL */
    wire [4:0] pll_unused;
    /* verilator lint_on UNUSEDSIGNAL */
    (* FREQUENCY_PIN_CLKI="25" *)
    (* FREQUENCY_PIN_CLKOP="125" *)
    (* FREQUENCY_PIN_CLKOS="52.0833" *)
    (* ICP_CURRENT="12" *) (* LPF_RESISTOR="8" *) (* MFG_ENABLE_FILTEROPAMP="1" *)
    (* MFG_GMCREF_SEL="2" *)
    EHXPLLL #(
        .PLLRST_ENA("DISABLED"), .INTFB_WAKE("DISABLED"), .STDBY_ENABLE("DISABLED"),
        .DPHASE_SOURCE("DISABLED"), .OUTDIVIDER_MUXA("DIVA"), .OUTDIVIDER_MUXB("DIVB"),
        .OUTDIVIDER_MUXC("DIVC"), .OUTDIVIDER_MUXD("DIVD"), .CLKI_DIV(1),
        .CLKOP_ENABLE("ENABLED"), .CLKOP_DIV(5), .CLKOP_CPHASE(2), .CLKOP_FPHASE(0),
        .CLKOS_ENABLE("ENABLED"), .CLKOS_DIV(12), .CLKOS_CPHASE(2), .CLKOS_FPHASE(0),
        .FEEDBK_PATH("CLKOP"), .CLKFB_DIV(5)
    ) u_pll (
        .RST(1'b0), .STDBY(1'b0), .CLKI(clk25), .CLKOP(clk), .CLKFB(clk),
        .CLKINTFB(pll_unused[0]), .CLKOS(eth_clk), .CLKOS2(pll_unused[1]),
        .CLKOS3(pll_unused[2]), .INTLOCK(pll_unused[3]), .REFCLK(pll_unused[4]),
        .PHASESEL0(1'b0), .PHASESEL1(1'b0), .PHASEDIR(1'b1), .PHASESTEP(1'b1),
        .PHASELOADREG(1'b1), .PLLWAKESYNC(1'b0), .ENCLKOP(1'b0), .ENCLKOS(1'b0),
        .ENCLKOS2(1'b0), .ENCLKOS3(1'b0), .LOCK(locked));
`else
    assign clk = clk25;
    assign eth_clk = clk25;
    assign locked = 1'b1;
`endif

    // each clock's reset: held while the PLL is not locked (locked taken through two flops of
    // that clock) and 16 of its clocks after
    reg [4:0] rst_count;                        // bit 4: out of reset
    reg [4:0] eth_rst_count;
    reg [1:0] locked_clk, locked_eth;
    initial begin                               // the configured FPGA's; before the PLL locks
        rst_count = 5'd0;
        eth_rst_count = 5'd0;
        locked_clk = 2'b00;
        locked_eth = 2'b00;
    end
    wire rst_n = rst_count[4];
    wire eth_rst_n = eth_rst_count[4];
    always @(posedge clk) begin
        locked_clk <= {locked_clk[0], locked};
        if (!locked_clk[1]) rst_count <= 5'd0;
        else if (!rst_n) rst_count <= rst_count + 5'd1;
    end
    always @(posedge eth_clk) begin
        locked_eth <= {locked_eth[0], locked};
        if (!locked_eth[1]) eth_rst_count <= 5'd0;
        else if (!eth_rst_n) eth_rst_count <= eth_rst_count + 5'd1;
    end

    wire [31:0] cnt_rx_packets;
    /* verilator lint_off UNUSEDSIGNAL */
    wire status_valid;
    wire [7:0] status;
    wire [15:0] credit;
    wire [31:0] cnt_samples, cnt_answers, cnt_no_credit, cnt_rx_error, cnt_rx_length,
                cnt_rx_overflow, cnt_tx_packets, cnt_tx_overflow, cnt_rx_port,
                cnt_peer_learned, cnt_peer_refused, cnt_peer_other;
    wire [31:0] cnt_rx_header, cnt_rx_other;
    /* verilator lint_on UNUSEDSIGNAL */
    rfl_fabric_top #(
`include "rfl_fabric_top_pass.vh"
    ) u_top (
        .clk(clk), .rst_n(rst_n), .eth_clk(eth_clk), .eth_rst_n(eth_rst_n), .cfg_mac(MAC), .cfg_ip(IP), .cfg_learn(1'b1),
        .cfg_peer_ip(32'd0), .cfg_peer_meta_port(16'd0), .cfg_peer_user_port(16'd0),
        .cfg_reader(READER), .cfg_writer(32'd0), .cfg_time(TIME), .send_sedp(1'b0),
        .rgmii_rx_clk(rgmii_rx_clk), .rgmii_rx_ctl(rgmii_rx_ctl), .rgmii_rxd(rgmii_rxd),
        .rgmii_tx_clk(rgmii_tx_clk), .rgmii_tx_ctl(rgmii_tx_ctl), .rgmii_txd(rgmii_txd),
        .status_valid(status_valid), .status(status), .credit(credit),
        .cnt_samples(cnt_samples), .cnt_answers(cnt_answers), .cnt_no_credit(cnt_no_credit),
        .cnt_rx_packets(cnt_rx_packets), .cnt_rx_error(cnt_rx_error),
        .cnt_rx_length(cnt_rx_length), .cnt_rx_overflow(cnt_rx_overflow),
        .cnt_tx_packets(cnt_tx_packets), .cnt_tx_overflow(cnt_tx_overflow),
        .cnt_rx_port(cnt_rx_port), .cnt_rx_header(cnt_rx_header), .cnt_rx_other(cnt_rx_other),
        .cnt_peer_learned(cnt_peer_learned), .cnt_peer_refused(cnt_peer_refused),
        .cnt_peer_other(cnt_peer_other));

    assign led_n = cnt_rx_packets == 32'd0;
endmodule

`default_nettype wire
