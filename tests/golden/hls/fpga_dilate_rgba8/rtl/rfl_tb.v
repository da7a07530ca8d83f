// rfl_tb -- a file-based testbench of the whole circuit (rfl_node: a generated project's
// rfl_gtop, or any top with the same ports, with the node configuration's parameters: an
// 8-bit status of the subscriber's table and the framing flags, which rfl_gtop ties to 0, and
// the stream nets timed below; rfl_harness.v taps the same). It streams TCPROS frames from a file into the 8-bit input,
// with random input gaps and random output backpressure from a seeded xorshift generator,
// writes every output byte to a file, and records per frame the subscriber's status and per
// stream the first and last handshake clocks. No Python runs per clock.
//
//   +input=FILE    frames in (required)        +output=FILE   bytes out (output.bin)
//   +status=FILE   "offset code" per frame     +stats=FILE    "stream first last count"
//   +seed=N        random seed (default 1)     +gap=P +bp=P   per mille of clocks the input
//   +vcd=FILE      dump the stream and FIFO       is idle / the output is not ready
//                  signals                     +idle_limit=N  clocks without progress = stall
`timescale 1ns / 1ps
`default_nettype none

module rfl_tb;
    reg clk = 1'b0;
    reg rst_n = 1'b0;
    reg [7:0] s_tdata = 8'd0;
    reg s_tvalid = 1'b0;
    wire s_tready;
    wire [7:0] m_tdata;
    wire m_tvalid;
    reg m_tready = 1'b0;
    wire frame_start, status_valid, busy;
    wire [7:0] status;
    wire [7:0] framing;

    rfl_node dut (
        .clk(clk), .rst_n(rst_n),
        .s_tdata(s_tdata), .s_tvalid(s_tvalid), .s_tready(s_tready),
        .m_tdata(m_tdata), .m_tvalid(m_tvalid), .m_tready(m_tready),
        .frame_start(frame_start), .status_valid(status_valid), .status(status), .busy(busy),
        .framing(framing));

    always #5 clk = ~clk;

    // The streams whose handshakes are timed: name, valid, ready.
    localparam NS = 9;
    wire [NS-1:0] hs = {
        dut.u_top.axis_out_tvalid && dut.u_top.axis_out_tready,          // 8 axi2fifo in
        m_tvalid && m_tready,                                            // 7 tx (out)
        dut.u_top.tx_tvalid && dut.u_top.tx_tready,                      // 6 publisher out
        dut.u_top.pix_out_tvalid && dut.u_top.pix_out_tready,            // 5 axi2fifo out
        dut.u_top.app_out_tvalid && dut.u_top.app_out_tready,            // 4 application out
        dut.u_top.app_in_tvalid && dut.u_top.app_in_tready,              // 3 application in
        dut.u_top.axis_in_tvalid && dut.u_top.axis_in_tready,            // 2 fifo2axi out
        dut.u_top.pix_in_tvalid && dut.u_top.pix_in_tready,              // 1 subscriber out
        dut.u_top.rx_tvalid && dut.u_top.rx_tready                       // 0 subscriber in
    };

    // The testbench's own bookkeeping stays out of a Verilator waveform.
    /* verilator tracing_off */
    integer fin, fout, fstatus, fstats, fbin, fbout, ff2a, c, i;
    reg f2a_on;
    integer seed, gap, bp, idle_limit;
    reg [31:0] rnd;
    reg [8*1024-1:0] path;
    reg eof;
    reg stopping;
    reg [63:0] cycle, idle, done_for, in_bytes, out_bytes, sub_bytes, frame_off;
    reg [63:0] first [0:NS-1];
    reg [63:0] last [0:NS-1];
    reg [63:0] count [0:NS-1];
    integer frames, refused;

    /* verilator tracing_on */

    function [31:0] xorshift(input [31:0] x);
        reg [31:0] y;
        begin
            y = x ^ (x << 13);
            y = y ^ (y >> 17);
            xorshift = y ^ (y << 5);
        end
    endfunction

    // Next input byte, or eof.
    task fetch;
        begin
            c = $fgetc(fin);
            if (c < 0) begin
                eof = 1'b1;
                s_tvalid <= 1'b0;
            end else begin
                s_tdata <= c[7:0];
                s_tvalid <= 1'b1;
            end
        end
    endtask

    initial begin
        if (!$value$plusargs("input=%s", path)) begin
            $fatal(1, "rtlsim: ERROR: no +input=FILE");
        end
        fin = $fopen(path, "rb");
        if (fin == 0) begin
            $fatal(1, "rtlsim: ERROR: cannot open the input %0s", path);
        end
        if (!$value$plusargs("output=%s", path)) path = "output.bin";
        fout = $fopen(path, "wb");
        if (!$value$plusargs("status=%s", path)) path = "status.txt";
        fstatus = $fopen(path, "w");
        if (!$value$plusargs("stats=%s", path)) path = "stats.txt";
        fstats = $fopen(path, "w");
        if (fout == 0 || fstatus == 0 || fstats == 0) begin
            $fatal(1, "rtlsim: ERROR: cannot open an output file");
        end
        fbin = 0;
        fbout = 0;
        if ($value$plusargs("beats_in=%s", path)) fbin = $fopen(path, "w");
        if ($value$plusargs("beats_out=%s", path)) fbout = $fopen(path, "w");
        ff2a = 0;
        f2a_on = 1'b0;
        if ($value$plusargs("clocks_f2a=%s", path)) ff2a = $fopen(path, "w");
        if (!$value$plusargs("seed=%d", seed)) seed = 1;
        if (!$value$plusargs("gap=%d", gap)) gap = 0;
        if (!$value$plusargs("bp=%d", bp)) bp = 0;
        if (!$value$plusargs("idle_limit=%d", idle_limit)) idle_limit = 1000000;
        if ($value$plusargs("vcd=%s", path)) begin
            $dumpfile(path);
            $dumpvars(1, dut.u_top);
        end
        rnd = (seed == 0) ? 32'h1234_5678 : seed;
        eof = 1'b0;
        stopping = 1'b0;
        cycle = 0; idle = 0; done_for = 0; in_bytes = 0; out_bytes = 0; sub_bytes = 0;
        frame_off = 0; frames = 0; refused = 0;
        for (i = 0; i < NS; i = i + 1) begin
            first[i] = 0; last[i] = 0; count[i] = 0;
        end
        repeat (4) @(posedge clk);
        rst_n <= 1'b1;
    end

    always @(posedge clk) if (rst_n && !stopping) begin
        cycle = cycle + 1;
        // input: hold a byte until it is taken; between bytes, a random gap
        if (s_tvalid && s_tready) in_bytes = in_bytes + 1;
        if ((!s_tvalid || s_tready) && !eof) begin
            rnd = xorshift(rnd);
            if ((rnd % 1000) >= gap) fetch;
            else s_tvalid <= 1'b0;
        end
        // output: random backpressure
        if (m_tvalid && m_tready) begin
            $fwrite(fout, "%c", m_tdata);
            out_bytes = out_bytes + 1;
        end
        rnd = xorshift(rnd);
        m_tready <= ((rnd % 1000) >= bp);
        // the subscriber's frames (a status comes a clock after its frame's deciding byte, when
        // the next frame may already start: write it before frame_off moves on)
        if (status_valid) begin
            $fwrite(fstatus, "%0d %0d\n", frame_off, status);
            frames = frames + 1;
            if (status != 0) refused = refused + 1;
        end
        if (frame_start) frame_off = sub_bytes;
        if (dut.u_top.rx_tvalid && dut.u_top.rx_tready) sub_bytes = sub_bytes + 1;
        // fifo2axi's ports at every clock from its first byte offered (+clocks_f2a): s_tvalid
        // s_tready s_tdata m_axis_tvalid m_axis_tready m_axis_tdata m_axis_tuser m_axis_tlast
        if (ff2a != 0 && dut.u_top.pix_in_tvalid) f2a_on = 1'b1;
        if (ff2a != 0 && f2a_on)
            $fwrite(ff2a, "%0d %0d %02x %0d %0d %08x %0d %0d\n", dut.u_top.pix_in_tvalid,
                    dut.u_top.pix_in_tready, dut.u_top.pix_in_tdata, dut.u_top.axis_in_tvalid,
                    dut.u_top.axis_in_tready, dut.u_top.axis_in_tdata, dut.u_top.axis_in_tuser,
                    dut.u_top.axis_in_tlast);
        // the beats into and out of the application (fifo2axi's and rfl_morph's outputs)
        if (fbin != 0 && hs[2])
            $fwrite(fbin, "%08x %x %x %x\n", dut.u_top.axis_in_tdata, dut.u_top.axis_in_tkeep,
                    dut.u_top.axis_in_tuser, dut.u_top.axis_in_tlast);
        if (fbout != 0 && hs[4])
            $fwrite(fbout, "%08x %x %x %x\n", dut.u_top.app_out_tdata, dut.u_top.app_out_tkeep,
                    dut.u_top.app_out_tuser, dut.u_top.app_out_tlast);
        for (i = 0; i < NS; i = i + 1) if (hs[i]) begin
            if (count[i] == 0) first[i] = cycle;
            last[i] = cycle;
            count[i] = count[i] + 1;
        end
        idle = (hs != 0) ? 0 : idle + 1;
        done_for = (eof && !busy && !s_tvalid) ? done_for + 1 : 0;
        if (done_for == 8) finish_run(1'b0, "");
        else if (idle >= idle_limit) begin
            if (eof) finish_run(1'b0, "the input ended inside a frame (the circuit waits for the rest)");
            else finish_run(1'b1, "ERROR: stalled: no handshake for +idle_limit clocks");
        end
    end

    task finish_run(input failed, input [8*80-1:0] note);
        begin
            stopping = 1'b1;
            for (i = 0; i < NS; i = i + 1)
                $fwrite(fstats, "%0d %0d %0d %0d\n", i, first[i], last[i], count[i]);
            $fwrite(fstats, "cycles %0d\n", cycle);
            $fwrite(fstats, "framing %0d\n", framing);
            $fclose(fout);
            $fclose(fstatus);
            $fclose(fstats);
            if (fbin != 0) $fclose(fbin);
            if (fbout != 0) $fclose(fbout);
            if (ff2a != 0) $fclose(ff2a);
            $display("rtlsim: %0d frame(s) in, %0d refused, %0d bytes in, %0d bytes out, %0d clocks",
                     frames, refused, in_bytes, out_bytes, cycle);
            if (failed) $fatal(1, "rtlsim: %0s", note);
            if (note != 0) $display("rtlsim: %0s", note);
            $finish;
        end
    endtask
endmodule

`default_nettype wire
