// rfl_frame_arbiter -- three AXI4-Streams of datagrams onto one, a whole datagram at a time
// (rfl_fabric_node's output: 0 the transmit path, 1 the answers, 2 the discovery ROM).
// Frame-atomic round robin: when no datagram is going out, the first source after the last one
// granted (0, 1, 2, 0, ...) that offers a beat is granted, the clock after; its beats pass as
// they are (TDATA, TLAST, TDEST, TUSER; TREADY back to it alone) until its TLAST is taken, then
// one idle clock. So no datagram is interleaved with another, the sources' stream rules hold on
// the output, and a source that offers a datagram waits behind at most two others.
// Sources are packed, source i in the bits [i*W +: W].
`default_nettype none

module rfl_frame_arbiter #(
    parameter DATA_BITS = 8,
    parameter DEST_BITS = 2,
    parameter USER_BITS = 96
) (
    input  wire                   clk,
    input  wire                   rst_n,
    input  wire [3*DATA_BITS-1:0] s_axis_tdata,
    input  wire [2:0]             s_axis_tvalid,
    output wire [2:0]             s_axis_tready,
    input  wire [2:0]             s_axis_tlast,
    input  wire [3*DEST_BITS-1:0] s_axis_tdest,
    input  wire [3*USER_BITS-1:0] s_axis_tuser,
    output wire [DATA_BITS-1:0]   m_axis_tdata,
    output wire                   m_axis_tvalid,
    input  wire                   m_axis_tready,
    output wire                   m_axis_tlast,
    output wire [DEST_BITS-1:0]   m_axis_tdest,
    output wire [USER_BITS-1:0]   m_axis_tuser
);
    reg locked;
    reg [1:0] grant;
    // the next source after grant that offers a beat (round robin over 0, 1, 2)
    reg [1:0] pick;
    reg found;
    always @* begin
        pick = grant;
        found = 1'b1;
        case (grant)
            2'd0: if (s_axis_tvalid[1]) pick = 2'd1; else if (s_axis_tvalid[2]) pick = 2'd2;
                  else if (s_axis_tvalid[0]) pick = 2'd0; else found = 1'b0;
            2'd1: if (s_axis_tvalid[2]) pick = 2'd2; else if (s_axis_tvalid[0]) pick = 2'd0;
                  else if (s_axis_tvalid[1]) pick = 2'd1; else found = 1'b0;
            default: if (s_axis_tvalid[0]) pick = 2'd0; else if (s_axis_tvalid[1]) pick = 2'd1;
                     else if (s_axis_tvalid[2]) pick = 2'd2; else found = 1'b0;
        endcase
    end
    always @(posedge clk) begin
        if (!rst_n) begin
            locked <= 1'b0;
            grant <= 2'd2;                      // source 0 first after reset
        end else if (!locked) begin
            if (found) begin
                grant <= pick;
                locked <= 1'b1;
            end
        end else if (m_axis_tvalid && m_axis_tready && m_axis_tlast) begin
            locked <= 1'b0;
        end
    end
    wire [2:0] on = {3{locked}} & {grant == 2'd2, grant == 2'd1, grant == 2'd0};
    assign s_axis_tready = on & {3{m_axis_tready}};
    assign m_axis_tvalid = |(on & s_axis_tvalid);
    // (grant is 0..2: source 2's fields for the code 3 it never holds)
    wire [1:0] g = (grant == 2'd3) ? 2'd2 : grant;
    assign m_axis_tdata = s_axis_tdata[g * DATA_BITS +: DATA_BITS];
    assign m_axis_tlast = s_axis_tlast[g];
    assign m_axis_tdest = s_axis_tdest[g * DEST_BITS +: DEST_BITS];
    assign m_axis_tuser = s_axis_tuser[g * USER_BITS +: USER_BITS];

`ifdef FORMAL
    // On the ports, with the invariants that make them inductive (fv_frame_arbiter proves them).
    // Frame atomicity: f_mid, a datagram's beat taken and not yet its TLAST, f_src its source;
    // meanwhile the output is that source alone (its valid, TREADY to it only).
    // Round robin: f_wait, the datagrams of other sources ended while source i offered a beat
    // and waited: at most 2 (f_dist: steps of the rotation from the last grant to source i).
    reg f_mid;
    reg [1:0] f_src;
    wire [2:0] f_take = s_axis_tvalid & s_axis_tready;
    wire f_end = m_axis_tvalid && m_axis_tready && m_axis_tlast;
    always @(posedge clk) begin
        if (!rst_n) begin
            f_mid <= 1'b0;
            f_src <= 2'd0;
        end else if (f_take != 3'd0) begin
            f_mid <= !m_axis_tlast;
            f_src <= f_take[2] ? 2'd2 : f_take[1] ? 2'd1 : 2'd0;
        end
    end
    always @(*) if (rst_n) begin
        assert(grant != 2'd3);
        assert(f_take == 3'd0 || f_take == 3'd1 || f_take == 3'd2 || f_take == 3'd4);
        if (f_mid) begin
            assert(locked && grant == f_src);
            assert(m_axis_tvalid == s_axis_tvalid[f_src]);
        end
    end
    genvar fi;
    generate for (fi = 0; fi < 3; fi = fi + 1) begin : g_f_wait
        localparam [1:0] I = fi;
        reg [1:0] f_wait;
        wire [2:0] f_dist = (grant == I) ? 3'd3 : (I > grant) ? {1'b0, I - grant}
                                                               : {1'b0, I + 2'd3 - grant};
        always @(posedge clk) begin
            if (!rst_n || !s_axis_tvalid[fi] || f_take[fi]) f_wait <= 2'd0;
            else if (f_end && f_wait != 2'd3) f_wait <= f_wait + 2'd1;
        end
        always @(*) if (rst_n) begin
            assert(f_wait <= 2'd2);
            if (s_axis_tvalid[fi] && !(locked && grant == I))
                assert({1'b0, f_wait} + f_dist <= (locked ? 3'd2 : 3'd3));
        end
    end endgenerate
`endif
endmodule

`default_nettype wire
