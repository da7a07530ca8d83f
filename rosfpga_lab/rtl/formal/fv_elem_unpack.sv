// fv_elem_unpack -- rfl_elem_unpack on its ports (2 bytes per element): the byte stream keeps
// the rules, and the bytes out are the elements taken, byte 0 first, none lost, duplicated or
// reordered (the bytes of an arbitrary n-th element come out as bytes 2n and 2n+1).
module fv_elem_unpack #(parameter EBYTES = 2) (
    input clk, input rst_n, input [8*EBYTES-1:0] s_tdata, input s_tvalid, input m_tready
);
    localparam EW = 8 * EBYTES;
    wire s_tready, m_tvalid;
    wire [7:0] m_tdata;
    rfl_elem_unpack #(.EBYTES(EBYTES)) dut (
        .clk(clk), .rst_n(rst_n), .s_axis_tdata(s_tdata), .s_axis_tvalid(s_tvalid),
        .s_axis_tready(s_tready), .m_tdata(m_tdata), .m_tvalid(m_tvalid), .m_tready(m_tready));
`include "fv_env.vh"
    `FV_SOURCE(s_tvalid, s_tready, s_tdata)
    `FV_SINK(m_tvalid, m_tready, m_tdata)

    // scoreboard: elements in, bytes out, and the element numbered `pick`
    (* anyconst *) reg [4:0] pick;
    (* anyconst *) reg [EW-1:0] pick_data;
    reg [4:0] n_in;                          // elements in (mod 32)
    reg [5:0] n_out;                         // bytes out (mod 64 = 2 x 32: EBYTES 2)
    wire [5:0] owed = EBYTES * n_in - n_out; // bytes taken in, not yet out
    wire wr = s_tvalid && s_tready, rd = m_tvalid && m_tready;
    always @(posedge clk) begin
        if (!rst_n) begin
            n_in <= 0;
            n_out <= 0;
        end else begin
            n_in <= n_in + wr;
            n_out <= n_out + rd;
        end
    end
    always @(*) if (rst_n && wr && n_in == pick) assume(s_tdata == pick_data);
    always @(posedge clk) if (!fv_init && rst_n) begin
        // bytes out never run ahead of elements in, and at most one element is held
`ifndef FV_PROVE   // bounded only: the bytes held are not visible on the ports (a stalled
                   // state holding the wrong count looks the same), so induction cannot close
        assert(owed <= EBYTES);                     // at most one element held, none lost
        assert(m_tvalid == (owed != 0));            // a byte is offered while one is owed
        if (rd && n_out / EBYTES == pick)           // order and data kept
            assert(m_tdata == pick_data[8 * (n_out % EBYTES) +: 8]);
`endif
    end
endmodule
