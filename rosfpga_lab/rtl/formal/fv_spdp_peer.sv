// fv_spdp_peer -- rfl_spdp_peer (the lab's constants, a second of 3 clocks, the resend 4 clocks
// after) on its ports, for ANY input bytes, datagram ends, source addresses and configuration
// prefix: the watcher is always ready; the peer's registers are zero until a peer is taken,
// then it stays taken, and they change only in a clock that pulses send_sedp; the counters
// never fall; and (its FORMAL block) at most two send_sedp pulses per peer taken or changed,
// at most one change a second.
module fv_spdp_peer (
    input clk, input rst_n, input [95:0] cfg_prefix, input [7:0] s_axis_tdata,
    input s_axis_tvalid, input s_axis_tlast, input [31:0] s_src_ip
);
    wire s_axis_tready, peer_known, send_sedp;
    wire [31:0] peer_meta_ip, peer_user_ip;
    wire [15:0] peer_meta_port, peer_user_port;
    wire [3:0] cnt_learned, cnt_refused, cnt_other;
    rfl_spdp_peer #(.SPDP_WRITER_ID(32'h000100c2), .SPDP_PIDS(80'h0071_0001_0002_0031_0032),
                    .SPDP_ENCAPS(32'h0002_0003), .SPDP_LOCATOR_KIND(32'd1),
                    .SPDP_LEASE_DEFAULT(100), .SPDP_LEASE_MAX(300), .TICK(3), .RESEND(4),
                    .COUNT_BITS(4)) dut (
        .clk(clk), .rst_n(rst_n), .cfg_prefix(cfg_prefix), .s_axis_tdata(s_axis_tdata),
        .s_axis_tvalid(s_axis_tvalid), .s_axis_tready(s_axis_tready),
        .s_axis_tlast(s_axis_tlast), .s_src_ip(s_src_ip), .peer_known(peer_known),
        .peer_meta_ip(peer_meta_ip), .peer_meta_port(peer_meta_port),
        .peer_user_ip(peer_user_ip), .peer_user_port(peer_user_port), .send_sedp(send_sedp),
        .cnt_learned(cnt_learned), .cnt_refused(cnt_refused), .cnt_other(cnt_other));
`include "fv_env.vh"
    wire [96:0] peer = {peer_known, peer_meta_ip, peer_meta_port, peer_user_ip, peer_user_port};
    always @(posedge clk) if (!fv_init && rst_n) begin
        assert(s_axis_tready);
        if (!peer_known) assert(peer[95:0] == 96'd0);
        if ($past(rst_n)) begin
            if ($past(peer_known)) assert(peer_known);
            if (peer != $past(peer)) assert(send_sedp);
            assert(cnt_learned >= $past(cnt_learned) && cnt_refused >= $past(cnt_refused) &&
                   cnt_other >= $past(cnt_other));
        end
    end
endmodule
