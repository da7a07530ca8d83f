// fv_udp_port -- rfl_udp_port (rtl/fabric) with 16-byte buffers and queues of 2 payloads, under
// any LiteEth receive stream and any lab payloads by the stream rules. Bounded (bmc): both
// outputs keep the stream rules, their sideband held with each beat until taken.
module fv_udp_port (
    input clk, input rst_n,
    input [7:0] le_rx_data, input le_rx_valid, input le_rx_last, input le_rx_error,
    input [31:0] le_rx_ip, input [15:0] le_rx_src_port, input [15:0] le_rx_dst_port,
    input [15:0] le_rx_length, input le_rx_drop_header, input le_rx_drop_other,
    input le_tx_ready, input m_axis_tready,
    input [7:0] s_axis_tdata, input s_axis_tvalid, input s_axis_tlast, input [31:0] s_udp_ip,
    input [15:0] s_udp_src_port, input [15:0] s_udp_dst_port
);
    wire le_rx_ready, le_tx_valid, le_tx_last, m_axis_tvalid, m_axis_tlast, s_axis_tready;
    wire [7:0] le_tx_data, m_axis_tdata;
    wire [31:0] le_tx_ip, m_udp_ip;
    wire [15:0] le_tx_src_port, le_tx_dst_port, le_tx_length;
    wire [15:0] m_udp_src_port, m_udp_dst_port, m_udp_length;
    wire [3:0] c0, c1, c2, c3, c4, c5, c6, c7;
    rfl_udp_port #(.RX_BITS(4), .TX_BITS(4), .QUEUE_BITS(1), .COUNT_BITS(4)) dut (
        .clk(clk), .rst_n(rst_n),
        .le_rx_data(le_rx_data), .le_rx_valid(le_rx_valid), .le_rx_ready(le_rx_ready),
        .le_rx_last(le_rx_last), .le_rx_error(le_rx_error), .le_rx_ip(le_rx_ip),
        .le_rx_src_port(le_rx_src_port), .le_rx_dst_port(le_rx_dst_port),
        .le_rx_length(le_rx_length), .le_rx_drop_header(le_rx_drop_header),
        .le_rx_drop_other(le_rx_drop_other),
        .le_tx_data(le_tx_data), .le_tx_valid(le_tx_valid), .le_tx_ready(le_tx_ready),
        .le_tx_last(le_tx_last), .le_tx_ip(le_tx_ip), .le_tx_src_port(le_tx_src_port),
        .le_tx_dst_port(le_tx_dst_port), .le_tx_length(le_tx_length),
        .m_axis_tdata(m_axis_tdata), .m_axis_tvalid(m_axis_tvalid),
        .m_axis_tready(m_axis_tready), .m_axis_tlast(m_axis_tlast), .m_udp_ip(m_udp_ip),
        .m_udp_src_port(m_udp_src_port), .m_udp_dst_port(m_udp_dst_port),
        .m_udp_length(m_udp_length),
        .s_axis_tdata(s_axis_tdata), .s_axis_tvalid(s_axis_tvalid),
        .s_axis_tready(s_axis_tready), .s_axis_tlast(s_axis_tlast), .s_udp_ip(s_udp_ip),
        .s_udp_src_port(s_udp_src_port), .s_udp_dst_port(s_udp_dst_port),
        .cnt_rx_packets(c0), .cnt_rx_error(c1), .cnt_rx_length(c2), .cnt_rx_overflow(c3),
        .cnt_tx_packets(c4), .cnt_tx_overflow(c5), .cnt_rx_header(c6), .cnt_rx_other(c7));
`include "fv_env.vh"
    `FV_SOURCE(le_rx_valid, le_rx_ready, {le_rx_data, le_rx_last, le_rx_error, le_rx_ip,
                                          le_rx_src_port, le_rx_dst_port, le_rx_length})
    `FV_SOURCE(s_axis_tvalid, s_axis_tready, {s_axis_tdata, s_axis_tlast, s_udp_ip,
                                              s_udp_src_port, s_udp_dst_port})
    `FV_SINK(m_axis_tvalid, m_axis_tready, {m_axis_tdata, m_axis_tlast, m_udp_ip,
                                            m_udp_src_port, m_udp_dst_port, m_udp_length})
    `FV_SINK(le_tx_valid, le_tx_ready, {le_tx_data, le_tx_last, le_tx_ip, le_tx_src_port,
                                        le_tx_dst_port, le_tx_length})
    always @(posedge clk) if (!fv_init && rst_n) begin
        assert(le_rx_ready);                      // the receiver never holds LiteEth back
        if (m_axis_tvalid) assert(m_udp_length != 16'd0 && m_udp_length <= 16'd16);
        if (le_tx_valid) assert(le_tx_length != 16'd0 && le_tx_length <= 16'd16);
    end
endmodule
