// fv_board_5a75b -- rfl_board_5a75b's own glue (rtl/fabric): the reset after the PLL locks, the
// peer learned (cfg_learn, no send_sedp of its own), the addresses and ids from its parameters,
// the LED. The PLL is the
// oscillator's clock here, locked from the start (the board top's FORMAL branch); rfl_fabric_top
// (the glue proven in fv_fabric_top, the rest by their own proofs and tests) is the model below,
// of the same name, parameters and ports (the RGMII ones), which checks what it is given.
// Bounded (bmc, 32 clocks): the top's resets (clk's and eth_clk's, one clock here) are low for
// the first 18 clocks (the lock through two flops, then 16) and high after;
// cfg_learn is high and send_sedp low (the top learns its peer and sends SEDP to it); the top's
// cfg_* are the parameters (cfg_writer 0: any writer); the LED is on (low) exactly when the
// top's cnt_rx_packets is not 0. The board has no stream of its own (no FV_SINK).
`define FV_MAC 48'h02524c460002
`define FV_IP 32'hc0a80a02
`define FV_READER 32'h00000104
`define FV_TIME 64'h0000_0001_8000_0000

module fv_board_5a75b (
    input clk25, input rgmii_rx_clk, input rgmii_rx_ctl, input [3:0] rgmii_rxd
);
    wire rgmii_tx_clk, rgmii_tx_ctl, led_n;
    wire [3:0] rgmii_txd;
    rfl_board_5a75b #(.MAC(`FV_MAC), .IP(`FV_IP), .READER(`FV_READER), .TIME(`FV_TIME),
                      .SPDP_PORT(7400), .META_PORT(7410), .USER_PORT(7411),
                      .SPDP_GROUP(32'hefff0001)) dut (
        .clk25(clk25), .rgmii_rx_clk(rgmii_rx_clk), .rgmii_rx_ctl(rgmii_rx_ctl),
        .rgmii_rxd(rgmii_rxd), .rgmii_tx_clk(rgmii_tx_clk), .rgmii_tx_ctl(rgmii_tx_ctl),
        .rgmii_txd(rgmii_txd), .led_n(led_n));
    // the model's cnt_rx_packets: {rgmii_rxd, 27'd0, rgmii_rx_ctl}
    always @(*) assert(led_n == ({rgmii_rxd, rgmii_rx_ctl} == 5'd0));
endmodule

// rfl_fabric_top as the board sees it: checks its inputs; cnt_rx_packets from the RGMII inputs.
module rfl_fabric_top #(
`include "rfl_fabric_top_params.vh"
) (
    input clk, input rst_n, input eth_clk, input eth_rst_n, input [47:0] cfg_mac, input [31:0] cfg_ip, input cfg_learn,
    input [31:0] cfg_peer_ip,
    input [15:0] cfg_peer_meta_port, input [15:0] cfg_peer_user_port, input [31:0] cfg_reader,
    input [31:0] cfg_writer, input [63:0] cfg_time, input send_sedp,
    input rgmii_rx_clk, input rgmii_rx_ctl, input [3:0] rgmii_rxd,
    output rgmii_tx_clk, output rgmii_tx_ctl, output [3:0] rgmii_txd,
    output status_valid, output [7:0] status, output [15:0] credit, output [31:0] cnt_samples,
    output [31:0] cnt_answers, output [31:0] cnt_no_credit, output [31:0] cnt_rx_packets,
    output [31:0] cnt_rx_error, output [31:0] cnt_rx_length, output [31:0] cnt_rx_overflow,
    output [31:0] cnt_tx_packets, output [31:0] cnt_tx_overflow, output [31:0] cnt_rx_port,
    output [31:0] cnt_rx_header, output [31:0] cnt_rx_other,
    output [31:0] cnt_peer_learned, output [31:0] cnt_peer_refused, output [31:0] cnt_peer_other
);
    assign {rgmii_tx_clk, rgmii_tx_ctl, rgmii_txd, status_valid, status, credit} = 31'd0;
    assign {cnt_samples, cnt_answers, cnt_no_credit, cnt_rx_error, cnt_rx_length} = 160'd0;
    assign {cnt_rx_overflow, cnt_tx_packets, cnt_tx_overflow, cnt_rx_port} = 128'd0;
    assign {cnt_rx_header, cnt_rx_other} = 64'd0;
    assign {cnt_peer_learned, cnt_peer_refused, cnt_peer_other} = 96'd0;
    assign cnt_rx_packets = {rgmii_rxd, 27'd0, rgmii_rx_ctl};
    reg [7:0] t = 8'd0;                         // clocks since the start
    always @(posedge clk) if (t != 8'hff) t <= t + 8'd1;
    always @(*) begin
        assert(rst_n == (t >= 8'd18) && eth_rst_n == rst_n);
        assert(cfg_learn && !send_sedp);
        assert(cfg_mac == `FV_MAC && cfg_ip == `FV_IP);
        assert(cfg_reader == `FV_READER && cfg_writer == 32'd0 && cfg_time == `FV_TIME);
    end
endmodule
