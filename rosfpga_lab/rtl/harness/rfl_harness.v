// rfl_harness -- the top of the fast C++ simulation (rfl_harness.cpp): rfl_node, whose ports
// the C++ drives and reads, plus read-only taps of the streams between the stages (the same
// nets rfl_tb.v times), so that per-stage cycle spans and the application's beats can be
// recorded. The taps are the only place the harness names a net inside the top.
// The inputs the C++ drives (s_tvalid, s_tdata, m_tready) are the values for the next clock:
// registered here at the rising edge, they reach rfl_node as the testbench's nonblocking
// drives do. So no input reaches logic without a register between, and the Verilated model
// has nothing to evaluate when an input changes: one evaluation per clock, at the edge.
`default_nettype none

module rfl_harness (
    input  wire        clk,
    input  wire        rst_n,
    input  wire [7:0]  s_tdata,
    input  wire        s_tvalid,
    output wire        s_tready,
    output wire [7:0]  m_tdata,
    output wire        m_tvalid,
    input  wire        m_tready,
    output wire        frame_start,
    output wire        status_valid,
    output wire [7:0]  status,   // a code of the walk's table
    output wire        busy,
    output wire [7:0]  framing,  // the stages' framing flags (0 on rfl_gtop)
    output wire [8:0]  hs,       // handshake per stream (sim.STREAMS order, bit 0 first)
    output reg  [37:0] beat_in,  // {tlast, tuser, tkeep, tdata} into the application
    output reg  [37:0] beat_out  // ... and out of it (each the last beat, after its clock)
);
    reg [7:0] s_tdata_r;
    reg       s_tvalid_r, m_tready_r;
    always @(posedge clk) begin
        s_tdata_r <= s_tdata;
        s_tvalid_r <= s_tvalid;
        m_tready_r <= m_tready;
    end

    rfl_node dut (
        .clk(clk), .rst_n(rst_n),
        .s_tdata(s_tdata_r), .s_tvalid(s_tvalid_r), .s_tready(s_tready),
        .m_tdata(m_tdata), .m_tvalid(m_tvalid), .m_tready(m_tready_r),
        .frame_start(frame_start), .status_valid(status_valid), .status(status), .busy(busy),
        .framing(framing));

    assign hs = {
        dut.u_top.axis_out_tvalid && dut.u_top.axis_out_tready,
        m_tvalid && m_tready_r,
        dut.u_top.tx_tvalid && dut.u_top.tx_tready,
        dut.u_top.pix_out_tvalid && dut.u_top.pix_out_tready,
        dut.u_top.app_out_tvalid && dut.u_top.app_out_tready,
        dut.u_top.app_in_tvalid && dut.u_top.app_in_tready,
        dut.u_top.axis_in_tvalid && dut.u_top.axis_in_tready,
        dut.u_top.pix_in_tvalid && dut.u_top.pix_in_tready,
        dut.u_top.rx_tvalid && dut.u_top.rx_tready
    };
    // Each field at its place in the 38 bits: a generated top's beat is one element, its
    // TDATA and TKEEP as narrow as the element (a mono8 pixel: 8 and 1 bits), so they are
    // zero-extended to 32 and 4 bits first (as the testbench prints them), not concatenated
    // at their own widths.
    wire [31:0] in_tdata = dut.u_top.axis_in_tdata;
    wire [3:0]  in_tkeep = dut.u_top.axis_in_tkeep;
    wire [31:0] out_tdata = dut.u_top.app_out_tdata;
    wire [3:0]  out_tkeep = dut.u_top.app_out_tkeep;
    // Held from the clock of each beat's handshake: the C++ reads a beat after that clock's
    // edge, and the model assembles the 38 bits once per beat, not every clock.
    always @(posedge clk) begin
        if (hs[2]) beat_in <= {dut.u_top.axis_in_tlast, dut.u_top.axis_in_tuser, in_tkeep,
                               in_tdata};
        if (hs[4]) beat_out <= {dut.u_top.app_out_tlast, dut.u_top.app_out_tuser, out_tkeep,
                                out_tdata};
    end
endmodule

`default_nettype wire
