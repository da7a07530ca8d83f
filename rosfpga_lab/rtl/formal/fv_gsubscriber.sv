// fv_gsubscriber -- rfl_gsubscriber on its ports, walking the small program of
// rosfpga_lab.rtl.proofs.formal_program (a checked byte, a carried string of at most 2 bytes, a
// stream of exactly 2 bytes), fed any bytes by the stream rules: its stream keeps the rules, a
// frame's fields (meta_*) are held unchanged until the publisher releases them, every status is
// a code of the table, and each frame whose fields it hands over (accepted, or refused after
// its stream went out) streamed exactly the array's 2 bytes. The walk hands a frame over early
// (STREAM_EARLY: nothing after its stream's count can refuse it): then at the count, before any
// stream byte, never to be dropped; FV_WHOLE proves the same walk without an exact fit (the
// frame's end decides it, formal_program(early=False)): once it has read all of it.
module fv_gsubscriber #(parameter CW = 3) (
    input clk, input rst_n, input [7:0] s_tdata, input s_tvalid, input m_tready,
    input meta_release, input carry_restart, input carry_pop
);
    wire s_tready, m_tvalid, meta_valid, meta_drop, frame_start, status_valid, idle, carry_valid;
`ifdef FV_WHOLE
    localparam EARLY = 0;
`else
    localparam EARLY = 1;
`endif
    wire [7:0] m_tdata, carry_rdata, status;
    wire [31:0] meta_out_len;
    rfl_gsubscriber #(.CARRY_BYTES(6), .CW(CW), .MIN_BODY(11), .MAX_FRAME(13), .EARLY(EARLY)) dut (
        .clk(clk), .rst_n(rst_n), .s_tdata(s_tdata), .s_tvalid(s_tvalid), .s_tready(s_tready),
        .m_tdata(m_tdata), .m_tvalid(m_tvalid), .m_tready(m_tready),
        .meta_valid(meta_valid), .meta_release(meta_release), .meta_out_len(meta_out_len),
        .meta_drop(meta_drop), .carry_restart(carry_restart), .carry_pop(carry_pop),
        .carry_rdata(carry_rdata), .carry_valid(carry_valid),
        .frame_start(frame_start), .status_valid(status_valid), .status(status), .idle(idle));
`include "fv_env.vh"
    `FV_SOURCE(s_tvalid, s_tready, s_tdata)
    `FV_SINK(m_tvalid, m_tready, m_tdata)
    // the publisher releases the fields only while they are held
    always @(*) if (!meta_valid) assume(!meta_release);

    // stream bytes out since the frame's first byte
    reg [7:0] streamed;
    always @(posedge clk) begin
        if (!rst_n) streamed <= 0;
        else if (frame_start) streamed <= 0;
        else if (m_tvalid && m_tready) streamed <= streamed + 8'd1;
    end

    // the frame's fields were handed over since its first byte (early: before its end), seen
    // as meta_valid rising (a record handed over behind a held one is not visible on the ports:
    // the module's own assertions hold the records' order, banks and count per frame)
    reg handed;
    always @(posedge clk) begin
        if (!rst_n || frame_start) handed <= 1'b0;
        else if (meta_valid && !$past(meta_valid)) handed <= 1'b1;
    end

    always @(posedge clk) if (!fv_init && rst_n) begin
        if (status_valid) assert(status <= 8'd4);           // a code of the table
`ifndef FV_PROVE   // bounded only: whether a frame is in progress and what it streamed are not
                   // visible on the ports, so induction cannot close on these
        // the fields are held, unchanged, until released
        if ($past(rst_n) && $past(meta_valid && !meta_release)) begin
            assert(meta_valid);
            assert($stable(meta_out_len) && $stable(meta_drop));
        end
        assert(streamed <= 8'd2);                            // never more than the array
        if (meta_valid && !$past(meta_valid))                // the whole array (early: none yet)
            assert(streamed == (EARLY ? 8'd0 : 8'd2));
        if (EARLY && meta_valid) assert(!meta_drop);         // handed over early: never dropped
        if (EARLY && handed && status_valid) assert(status == 8'd0);   // ... nor refused
        if (meta_valid && !meta_drop && !$past(meta_valid))  // the answer's length: 4 + label
            assert(meta_out_len >= 1 + 4 + 4 + 2 && meta_out_len <= 1 + 4 + 2 + 4 + 2);
`endif
    end
endmodule
