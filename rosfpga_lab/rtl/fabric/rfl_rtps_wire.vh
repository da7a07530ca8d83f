// rfl_rtps_wire.vh -- the RTPS wire vocabulary the fabric's stages share, included inside a
// module's body. The software participant owns every value (rosfpga_lab.rtps.build: the
// submessage ids, PROTOCOL_VERSION, VENDOR_ID, FLAG_LE; rosfpga_lab.rtps.message: MAGIC);
// tests/rtl/test_rtps_wire.py holds each one equal to its owner, by name, and no fabric
// module writes these as literals of its own. A stage uses some of them only.
/* verilator lint_off UNUSEDPARAM */
    localparam [31:0] RTPS_MAGIC = 32'h52545053;        // "RTPS", the header's first 4 bytes
    localparam [15:0] RTPS_VERSION = 16'h0203;          // {major, minor} the lab speaks
    localparam [15:0] RTPS_VENDOR = 16'h0000;           // the lab's vendor id (none assigned)
    localparam [7:0] FLAG_E = 8'h01;                    // a submessage's flags: little endian
    // submessage ids (RTPS 2.3 9.4.5.1.1)
    localparam [7:0] ID_PAD = 8'h01, ID_ACKNACK = 8'h06, ID_HEARTBEAT = 8'h07,
                     ID_INFO_TS = 8'h09, ID_INFO_SRC = 8'h0C, ID_INFO_DST = 8'h0E,
                     ID_DATA = 8'h15, ID_DATA_FRAG = 8'h16;
/* verilator lint_on UNUSEDPARAM */
