// A plain testbench that dumps rfl_morph's signals to a VCD (tests/rtl/test_vcd.py reads it).
// Pixels come from pixels.hex (one 32-bit word per line, written by the test); the input
// pauses every third clock and the output refuses every fourth, from fixed patterns.
`timescale 1ns / 1ps
module morph_vcd_tb;
    parameter WIDTH = 5, HEIGHT = 3, KSIZE = 3, OP = 0, BYTES = 4, CLOCKS = 80;
    reg aclk = 0, aresetn = 0;
    reg [31:0] s_tdata = 0;
    reg s_tuser = 0, s_tlast = 0, s_tvalid = 0, m_tready = 0;
    wire s_tready, m_tvalid, m_tuser, m_tlast;
    wire [31:0] m_tdata;
    wire [3:0] m_tkeep;
    reg [31:0] pixels [0:WIDTH*HEIGHT-1];
    integer sent = 0, clock = 0;

    rfl_morph #(.WIDTH(WIDTH), .HEIGHT(HEIGHT), .KSIZE(KSIZE), .OP(OP), .BYTES(BYTES)) dut (
        .aclk(aclk), .aresetn(aresetn),
        .s_axis_tdata(s_tdata), .s_axis_tkeep(4'b1111), .s_axis_tuser(s_tuser),
        .s_axis_tlast(s_tlast), .s_axis_tvalid(s_tvalid), .s_axis_tready(s_tready),
        .m_axis_tdata(m_tdata), .m_axis_tkeep(m_tkeep), .m_axis_tuser(m_tuser),
        .m_axis_tlast(m_tlast), .m_axis_tvalid(m_tvalid), .m_axis_tready(m_tready));

    always #5 aclk = !aclk;

    initial begin
        $readmemh("pixels.hex", pixels);
        $dumpfile("morph.vcd");
        $dumpvars(0, morph_vcd_tb);
    end

    always @(posedge aclk) begin
        clock <= clock + 1;
        if (clock == 2) aresetn <= 1;
        if (s_tvalid && s_tready) sent = sent + 1;
        if (!s_tvalid || s_tready) begin        // a beat once valid stays until taken
            s_tvalid <= aresetn && sent < WIDTH * HEIGHT && (clock % 3 != 0);
            s_tdata <= pixels[sent];
            s_tuser <= (sent == 0);
            s_tlast <= (sent % WIDTH == WIDTH - 1);
        end
        m_tready <= (clock % 4 != 1);
        if (clock == CLOCKS - 1) $finish;
    end
endmodule
