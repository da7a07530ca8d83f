// A stand-in for rfl_morph in tests that run before the real one is there: passes beats on.
module rfl_morph #(parameter WIDTH = 640, HEIGHT = 480, KSIZE = 3, OP = 2, BYTES = 4) (
    input aclk, input aresetn,
    input [31:0] s_axis_tdata, input [3:0] s_axis_tkeep, input s_axis_tuser, input s_axis_tlast,
    input s_axis_tvalid, output s_axis_tready,
    output [31:0] m_axis_tdata, output [3:0] m_axis_tkeep, output m_axis_tuser,
    output m_axis_tlast, output m_axis_tvalid, input m_axis_tready);
    assign m_axis_tdata = s_axis_tdata;
    assign m_axis_tkeep = s_axis_tkeep;
    assign m_axis_tuser = s_axis_tuser;
    assign m_axis_tlast = s_axis_tlast;
    assign m_axis_tvalid = s_axis_tvalid;
    assign s_axis_tready = m_axis_tready;
endmodule
