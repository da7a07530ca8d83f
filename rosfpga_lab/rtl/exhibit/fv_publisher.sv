// fv_publisher -- rfl_publisher on its ports: given an accepted frame's fields (held until it
// releases them) and pixel bytes by the stream rules, its output keeps the rules and it takes
// pixels only for a frame whose fields it holds.
module fv_publisher (input clk, input rst_n, input [7:0] s_tdata, input s_tvalid,
                     input m_tready, input meta_valid, input [31:0] meta_secs,
                     input [31:0] meta_nsecs, input [7:0] meta_bigendian,
                     input [2:0] meta_fid_len);
    wire s_tready, m_tvalid, meta_release, frame_done, idle;
    wire [7:0] m_tdata;
    wire [1:0] fid_raddr;
    // the subscriber's frame_id RAM, read with a clock as in rfl_top: any contents, fixed
    (* anyconst *) reg [31:0] fid_mem;
    reg [7:0] fid_rdata;
    always @(posedge clk) fid_rdata <= fid_mem[8 * fid_raddr +: 8];
    rfl_publisher #(.WIDTH(2), .HEIGHT(1), .BYTES(1), .ENC_LEN(5), .ENCODING("mono8"),
                    .FRAME_ID_MAX(4), .MIN_BODY(37)) dut (
        .clk(clk), .rst_n(rst_n), .s_tdata(s_tdata), .s_tvalid(s_tvalid), .s_tready(s_tready),
        .m_tdata(m_tdata), .m_tvalid(m_tvalid), .m_tready(m_tready),
        .meta_valid(meta_valid), .meta_release(meta_release), .meta_secs(meta_secs),
        .meta_nsecs(meta_nsecs), .meta_bigendian(meta_bigendian), .meta_fid_len(meta_fid_len),
        .fid_raddr(fid_raddr), .fid_rdata(fid_rdata), .frame_done(frame_done), .idle(idle));
`include "fv_env.vh"
    `FV_SOURCE(s_tvalid, s_tready, s_tdata)
    `FV_SINK(m_tvalid, m_tready, m_tdata)
    // the subscriber's side: fields held, unchanged, from meta_valid until released
    always @(posedge clk) if (!fv_init && $past(rst_n)) begin
        if ($past(meta_valid && !meta_release)) assume(meta_valid && $stable(meta_secs)
            && $stable(meta_nsecs) && $stable(meta_bigendian) && $stable(meta_fid_len));
    end
    always @(*) if (!rst_n) assume(!meta_valid);
    always @(posedge clk) if (!fv_init && rst_n) begin
`ifndef FV_PROVE   // bounded only: whether it holds a frame is not visible on the ports
        if (meta_release) assert(meta_valid);               // releases only what it holds
`endif
    end
endmodule
