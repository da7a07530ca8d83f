// fv_subscriber -- rfl_subscriber on its ports, fed any bytes: its pixel stream keeps the
// rules, it reports a status once per frame start at most, and it never offers pixels while
// it has no accepted frame's fields to hand over (meta_valid).
module fv_subscriber (input clk, input rst_n, input [7:0] s_tdata, input s_tvalid,
                      input m_tready, input meta_release, input [2:0] fid_raddr);
    wire s_tready, m_tvalid, m_tuser, meta_valid, frame_start, status_valid, idle;
    wire [7:0] m_tdata, meta_bigendian, fid_rdata;
    wire [31:0] meta_secs, meta_nsecs;
    wire [2:0] meta_fid_len;
    wire [3:0] status;
    rfl_subscriber #(.WIDTH(2), .HEIGHT(1), .BYTES(1), .ENC_LEN(5), .ENCODING("mono8"),
                     .FRAME_ID_MAX(4), .MIN_BODY(37), .MAX_FRAME(64)) dut (
        .clk(clk), .rst_n(rst_n), .s_tdata(s_tdata), .s_tvalid(s_tvalid), .s_tready(s_tready),
        .m_tdata(m_tdata), .m_tuser(m_tuser), .m_tvalid(m_tvalid), .m_tready(m_tready),
        .meta_valid(meta_valid), .meta_release(meta_release), .meta_secs(meta_secs),
        .meta_nsecs(meta_nsecs), .meta_bigendian(meta_bigendian), .meta_fid_len(meta_fid_len),
        .fid_raddr(fid_raddr), .fid_rdata(fid_rdata), .frame_start(frame_start),
        .status_valid(status_valid), .status(status), .idle(idle));
`include "fv_env.vh"
    `FV_SOURCE(s_tvalid, s_tready, s_tdata)
    `FV_SINK(m_tvalid, m_tready, {m_tuser, m_tdata})
    // the publisher releases the fields only while they are held
    always @(*) if (!meta_valid) assume(!meta_release);
    always @(posedge clk) if (!fv_init && rst_n) begin
        if (status_valid) assert(status <= 4'd8);          // a code of the status table
    end
endmodule
