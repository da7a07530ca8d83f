// A testbench of rfl_rtps_disc_rom (tests/rtl/test_fabric_disc_rom.py): reset, send_sedp pulses at
// SEDP_AT and SEDP_AT2, random backpressure (BP per mille of clocks, seed SEED) on the output;
// every beat taken goes to OUT_FILE as "dest byte last", one a line, until DATAGRAMS datagrams.
// A beat offered and not taken must stay offered, unchanged, next clock: each break is counted
// and printed as "UNSTABLE" at the end.
`timescale 1ns/1ps
`default_nettype none

module rtps_disc_rom_tb;
    parameter ROM_FILE = "rfl_rtps_disc_rom.hex";
    parameter TABLE_FILE = "rfl_rtps_disc_rom_table.hex";
    parameter ROM_BYTES = 1;
    parameter MESSAGES = 1;
    parameter PERIOD = 1000;
    parameter OUT_FILE = "out.txt";
    parameter BP = 500;
    parameter SEED = 1;
    parameter SEDP_AT = 10;
    parameter SEDP_AT2 = 5000;
    parameter DATAGRAMS = 6;
    parameter MAX_CLOCKS = 200000;

    reg clk = 1'b0, rst_n = 1'b0, send_sedp = 1'b0, ready = 1'b0;
    wire [7:0] tdata;
    wire tvalid, tlast, busy;
    wire [1:0] tdest;
    integer fd, clocks, datagrams, unstable, seed;
    reg was_stalled;
    reg [10:0] held;

    rfl_rtps_disc_rom #(.ROM_FILE(ROM_FILE), .TABLE_FILE(TABLE_FILE), .ROM_BYTES(ROM_BYTES),
                        .MESSAGES(MESSAGES), .PERIOD(PERIOD), .DEST_BITS(2)) dut (
        .clk(clk), .rst_n(rst_n), .send_sedp(send_sedp), .busy(busy), .m_axis_tdata(tdata),
        .m_axis_tvalid(tvalid), .m_axis_tready(ready), .m_axis_tlast(tlast),
        .m_axis_tdest(tdest));

    always #5 clk = !clk;

    initial begin
        fd = $fopen(OUT_FILE, "w");
        seed = SEED;
        clocks = 0; datagrams = 0; unstable = 0; was_stalled = 1'b0; held = 11'd0;
        repeat (3) @(posedge clk);
        rst_n <= 1'b1;
        while (datagrams < DATAGRAMS && clocks < MAX_CLOCKS) begin
            @(negedge clk);
            ready = ($unsigned($random(seed)) % 1000) >= BP;
            send_sedp = (clocks == SEDP_AT) || (clocks == SEDP_AT2);
            @(posedge clk);        // what the sink samples at this edge (before the DUT's update)
            clocks = clocks + 1;
            if (was_stalled && (!tvalid || {tdest, tlast, tdata} != held)) unstable = unstable + 1;
            was_stalled = tvalid && !ready;
            held = {tdest, tlast, tdata};
            if (tvalid && ready) begin
                $fwrite(fd, "%0d %02x %0d\n", tdest, tdata, tlast);
                if (tlast) datagrams = datagrams + 1;
            end
        end
        $fclose(fd);
        if (unstable != 0) $display("UNSTABLE %0d", unstable);
        $display("DONE datagrams %0d clocks %0d", datagrams, clocks);
        $finish;
    end
endmodule

`default_nettype wire
