// rfl_elem_tb -- a file-based testbench of the element stream alone: bytes from +input=FILE
// (whole arrays of LENGTH elements of EBYTES bytes, little-endian) go through rfl_elem_pack,
// rfl_window1d and rfl_elem_unpack; the bytes out go to +output=FILE. Random input gaps and
// output backpressure (+gap=P +bp=P, per mille of clocks; +seed=N). A TUSER or TLAST in the
// wrong place (TLAST: the last element of every LINE, the packer's video framing) is reported
// as "rtlsim: ERROR".
`default_nettype none

module rfl_elem_tb;
    parameter EBYTES = 4;
    parameter LENGTH = 16;
    parameter KSIZE = 3;
    parameter OP = 0;
    parameter KIND = 0;
    parameter LINE = LENGTH;
    localparam EW = 8 * EBYTES;

    reg clk = 1'b0;
    reg rst_n = 1'b0;
    reg [7:0] s_tdata = 8'd0;
    reg s_tvalid = 1'b0;
    wire s_tready;
    wire [7:0] m_tdata;
    wire m_tvalid;
    reg m_tready = 1'b0;

    wire [EW-1:0] a_tdata, b_tdata;
    wire [EBYTES-1:0] a_tkeep, b_tkeep;
    wire a_tuser, a_tlast, a_tvalid, a_tready, b_tuser, b_tlast, b_tvalid, b_tready;

    rfl_elem_pack #(.EBYTES(EBYTES), .LENGTH(LENGTH), .LINE(LINE)) u_pack (
        .clk(clk), .rst_n(rst_n), .s_tdata(s_tdata), .s_tvalid(s_tvalid), .s_tready(s_tready),
        .m_axis_tdata(a_tdata), .m_axis_tkeep(a_tkeep), .m_axis_tuser(a_tuser),
        .m_axis_tlast(a_tlast), .m_axis_tvalid(a_tvalid), .m_axis_tready(a_tready));
    rfl_window1d #(.EBYTES(EBYTES), .KSIZE(KSIZE), .OP(OP), .KIND(KIND)) u_app (
        .aclk(clk), .aresetn(rst_n), .s_axis_tdata(a_tdata), .s_axis_tuser(a_tuser),
        .s_axis_tlast(a_tlast), .s_axis_tvalid(a_tvalid), .s_axis_tready(a_tready),
        .m_axis_tdata(b_tdata), .m_axis_tkeep(b_tkeep), .m_axis_tuser(b_tuser),
        .m_axis_tlast(b_tlast), .m_axis_tvalid(b_tvalid), .m_axis_tready(b_tready));
    rfl_elem_unpack #(.EBYTES(EBYTES)) u_unpack (
        .clk(clk), .rst_n(rst_n), .s_axis_tdata(b_tdata), .s_axis_tvalid(b_tvalid),
        .s_axis_tready(b_tready), .m_tdata(m_tdata), .m_tvalid(m_tvalid), .m_tready(m_tready));

    always #5 clk = ~clk;

    integer fin, fout, c, seed, gap, bp, idle;
    integer nin, nout;
    reg [31:0] rnd;
    reg [8*1024-1:0] path;
    reg eof;

    function [31:0] xorshift(input [31:0] x);
        reg [31:0] y;
        begin
            y = x ^ (x << 13);
            y = y ^ (y >> 17);
            xorshift = y ^ (y << 5);
        end
    endfunction

    initial begin
        if (!$value$plusargs("input=%s", path)) $fatal(1, "rtlsim: ERROR: no +input=FILE");
        fin = $fopen(path, "rb");
        if (!$value$plusargs("output=%s", path)) path = "output.bin";
        fout = $fopen(path, "wb");
        if (fin == 0 || fout == 0) $fatal(1, "rtlsim: ERROR: cannot open the files");
        if (!$value$plusargs("seed=%d", seed)) seed = 1;
        if (!$value$plusargs("gap=%d", gap)) gap = 0;
        if (!$value$plusargs("bp=%d", bp)) bp = 0;
        rnd = seed;
        eof = 1'b0;
        idle = 0;
        nin = 0;
        nout = 0;
        repeat (3) @(posedge clk);
        rst_n <= 1'b1;
    end

    always @(posedge clk) if (rst_n) begin
        if ((!s_tvalid || s_tready) && !eof) begin
            rnd = xorshift(rnd);
            if ((rnd % 1000) >= gap) begin
                c = $fgetc(fin);
                if (c < 0) begin
                    eof = 1'b1;
                    s_tvalid <= 1'b0;
                end else begin
                    s_tdata <= c[7:0];
                    s_tvalid <= 1'b1;
                end
            end else s_tvalid <= 1'b0;
        end
        if (m_tvalid && m_tready) $fwrite(fout, "%c", m_tdata);
        rnd = xorshift(rnd);
        m_tready <= ((rnd % 1000) >= bp);
        if (b_tvalid && b_tready) begin
            if (b_tuser != (nout == 0) || b_tlast != (nout % LINE == LINE - 1))
                $display("rtlsim: ERROR: element %0d out has TUSER %0d TLAST %0d", nout, b_tuser, b_tlast);
            nout = (nout == LENGTH - 1) ? 0 : nout + 1;
        end
        if (a_tvalid && a_tready) begin
            if (a_tuser != (nin == 0) || a_tlast != (nin % LINE == LINE - 1))
                $display("rtlsim: ERROR: element %0d in has TUSER %0d TLAST %0d", nin, a_tuser, a_tlast);
            nin = (nin == LENGTH - 1) ? 0 : nin + 1;
        end
        idle = (s_tvalid || m_tvalid || a_tvalid || b_tvalid) ? 0 : idle + 1;
        if (eof && idle > 50) begin
            $fclose(fout);
            $finish;
        end
    end
endmodule

`default_nettype wire
