// fv_gpublisher -- rfl_gpublisher on its ports, walking the small program of
// rosfpga_lab.rtl.proofs.formal_program (a constant byte, a carried string, a stream of 2
// bytes). Given a frame's fields held until it releases them (as rfl_gsubscriber's proof shows),
// a carry memory not written while it writes a frame, and the application's bytes by the stream
// rules: its output keeps the rules, it releases only fields it holds, a frame starts with the
// frame length it was given (little-endian) and then the constant, it takes exactly the
// array's 2 bytes of the application per frame (a dropped frame too), and writes nothing for a
// dropped frame. The carried byte at hand may wait (carry_valid: streaming early release, the
// subscriber still writing it) and is then held until taken.
module fv_gpublisher (
    input clk, input rst_n, input [7:0] s_tdata, input s_tvalid, input m_tready,
    input meta_valid, input [31:0] meta_out_len, input meta_drop, input [7:0] carry_rdata,
    input carry_valid
);
    wire s_tready, m_tvalid, meta_release, idle;
    wire [7:0] m_tdata;
    wire carry_restart, carry_pop;
    rfl_gpublisher #(.STREAM_DATA_BYTES(2), .SEQ_START(1)) dut (
        .clk(clk), .rst_n(rst_n), .s_tdata(s_tdata), .s_tvalid(s_tvalid), .s_tready(s_tready),
        .m_tdata(m_tdata), .m_tvalid(m_tvalid), .m_tready(m_tready),
        .meta_valid(meta_valid), .meta_release(meta_release), .meta_out_len(meta_out_len),
        .meta_drop(meta_drop), .carry_restart(carry_restart), .carry_pop(carry_pop),
        .carry_rdata(carry_rdata), .carry_valid(carry_valid),
        .idle(idle));
`include "fv_env.vh"
    `FV_SOURCE(s_tvalid, s_tready, s_tdata)
    `FV_SINK(m_tvalid, m_tready, m_tdata)
    // the subscriber's side: the fields are held, unchanged, from meta_valid until released,
    // dropped the clock after, and set only as meta_valid rises; the carried byte at hand
    // changes only when taken (carry_pop) or in the frame's first clocks, as the subscriber
    // reads its carry memory ahead (not written while a frame is being written)
    always @(*) if (!rst_n) assume(!meta_valid);
    always @(posedge clk) if (!fv_init && $past(rst_n)) begin
        if ($past(meta_valid && !meta_release) || $past(!idle && !meta_release))
            assume(meta_valid && $stable(meta_out_len) && $stable(meta_drop));
        if ($past(meta_release)) assume(!meta_valid);
        if (!(meta_valid && !$past(meta_valid))) assume($stable(meta_out_len));
        if ($past(!idle) && $past(!idle, 2) && $past(!idle, 3) && !$past(carry_pop)
            && $past(carry_valid))
            assume($stable(carry_rdata) && carry_valid);
    end

    // per frame (from one release to the next): bytes written, application bytes taken
    reg [7:0] n_out, n_in;
    wire put = m_tvalid && m_tready, take = s_tvalid && s_tready;
    always @(posedge clk) begin
        if (!rst_n || meta_release) begin
            n_out <= 0;
            n_in <= 0;
        end else begin
            n_out <= n_out + put;
            n_in <= n_in + take;
        end
    end

    always @(posedge clk) if (!fv_init && rst_n) begin
`ifndef FV_PROVE   // bounded only: which part of a frame it is writing is not visible on the ports
        if (meta_release) assert(meta_valid);               // releases only what it holds
        assert(n_in <= 8'd2);                               // never more than the array
        if (meta_release) assert(n_in == 8'd2);             // the whole array, dropped or not
        if (put) begin
            assert(!meta_drop && meta_valid);               // nothing for a dropped frame
            if (n_out < 4) assert(m_tdata == meta_out_len[8 * n_out[1:0] +: 8]);  // the length
            if (n_out == 4) assert(m_tdata == 8'h02);       // then the constant
        end
`endif
    end
endmodule
