// ecp5_io_models -- behavioural models of the four ECP5 cells the vendored LiteEth core's RGMII
// variant instantiates, for tests/rtl/test_fabric_rgmii.py only (Yosys' ECP5 models of the DDR
// cells are black boxes). Written here from Lattice's descriptions (FPGA-TN-02035, ECP5 high-
// speed I/O): IDDRX1F presents at a rising SCLK edge the D of the previous rising edge (Q0) and
// of the falling edge after it (Q1); ODDRX1F drives D0 in SCLK's high half, D1 in its low half;
// DELAYG delays nothing here; FD1S3BX is a flip-flop with an asynchronous preset.
`timescale 1ns / 1ps
`default_nettype none

module DELAYG #(parameter DEL_MODE = "USER_DEFINED", parameter DEL_VALUE = 0) (
    input wire A, output wire Z);
    assign Z = A;
endmodule

module IDDRX1F (input wire D, input wire SCLK, input wire RST, output reg Q0, output reg Q1);
    reg rise, fall;
    always @(posedge SCLK) rise <= D;
    always @(negedge SCLK) fall <= D;
    always @(posedge SCLK) begin
        Q0 <= rise;
        Q1 <= fall;
    end
    wire unused_ok = &{1'b0, RST};
endmodule

module ODDRX1F (input wire D0, input wire D1, input wire SCLK, input wire RST, output wire Q);
    reg d0, d1;
    always @(posedge SCLK) begin
        d0 <= D0;
        d1 <= D1;
    end
    assign Q = SCLK ? d0 : d1;
    wire unused_ok = &{1'b0, RST};
endmodule

module FD1S3BX (input wire D, input wire CK, input wire PD, output reg Q);
    initial Q = 1'b1;
    always @(posedge CK or posedge PD) Q <= PD ? 1'b1 : D;
endmodule

`default_nettype wire
