// rfl_rtps_disc_rom -- the fabric participant's discovery, built at build time: a ROM of whole
// UDP payloads (RTPS messages) streamed out on an 8-bit AXI4-Stream, one datagram per packet
// (TLAST on its last byte), TDEST its destination for the UDP/IP stack:
//   0 = the SPDP discovery port(s) (multicast, or the probed unicast ports on loopback),
//   1 = the new participant's metatraffic unicast port, 2 = its user-data unicast port.
// The ROM and its message table come from rosfpga_lab.rtl.discrom (render_rom, write_rom):
// ROM_FILE holds the messages back to back, one byte a line; TABLE_FILE one entry a line per
// message, {dest[7:0], offset[15:0], length[15:0]} (a length of at least 1: write_rom writes no
// empty message). Message 0 is the SPDP announcement, sent right after reset and then every
// PERIOD clocks; a pulse on send_sedp (the receive side saw a new participant) sends messages
// 1 .. MESSAGES-1 in order (SEDP, ros_discovery_info; none when MESSAGES = 1). A tick or a
// request that comes while a datagram is on its way waits for its end (a datagram is never cut
// or interleaved); requests that come while one waits are one request.
// The bytes are the ROM's as they are: the patch points the index names (INFO_DST, HEARTBEAT
// counts, preemptive ACKNACK bases, INFO_TS) hold their build-time values (rosfpga_lab.rtl.discrom
// says why a peer accepts them as they are, and which peer needs another value).
// The ROM is read on the clock into the register TDATA shows (a block RAM's read port): a
// datagram's first byte is offered the clock after it starts, then one byte per clock taken;
// a datagram waiting starts on the clock its predecessor's TLAST is taken (no idle clock).
// Stream rules: TDATA, TLAST and TDEST change only after a beat is taken, and TVALID does not
// fall before (formal/fv_rtps_disc_rom.sv proves it, for any ROM contents).
`default_nettype none

module rfl_rtps_disc_rom #(
    parameter ROM_FILE = "",                    // rfl_rtps_disc_rom.hex ("": an empty ROM, to lint)
    parameter TABLE_FILE = "",                  // rfl_rtps_disc_rom_table.hex
    parameter ROM_BYTES = 1472,                 // bytes in ROM_FILE, 1..65536: checked
    parameter MESSAGES = 3,                     // entries in TABLE_FILE, 1..256: checked
    parameter PERIOD = 100000000,               // clocks between SPDP announcements, >= 1
    parameter DEST_BITS = 2                     // width of m_axis_tdest, 1..8
) (
    input  wire                 clk,
    input  wire                 rst_n,
    input  wire                 send_sedp,      // one clock: send messages 1 .. MESSAGES-1
    output wire                 busy,           // a datagram is on its way or waits
    output wire [7:0]           m_axis_tdata,
    output wire                 m_axis_tvalid,
    input  wire                 m_axis_tready,
    output wire                 m_axis_tlast,
    output wire [DEST_BITS-1:0] m_axis_tdest
);
    // Parameter contracts: an illegal value is refused at elaboration (Verilator, Yosys);
    // Icarus -g2005 has no elaboration tasks, so it stops at time 0, before any clock.
`ifdef __ICARUS__
    initial begin
        if (ROM_BYTES < 1 || ROM_BYTES > 65536)
            $fatal(1, "rfl_rtps_disc_rom: ROM_BYTES must be 1..65536 (16-bit offsets)");
        if (MESSAGES < 1 || MESSAGES > 256)
            $fatal(1, "rfl_rtps_disc_rom: MESSAGES must be 1..256");
        if (PERIOD < 1) $fatal(1, "rfl_rtps_disc_rom: PERIOD must be at least 1");
        if (DEST_BITS < 1 || DEST_BITS > 8) $fatal(1, "rfl_rtps_disc_rom: DEST_BITS must be 1..8");
    end
`else
    if (ROM_BYTES < 1 || ROM_BYTES > 65536) begin : g_bad_rom_bytes
        $error("rfl_rtps_disc_rom: ROM_BYTES must be 1..65536 (16-bit offsets)");
    end
    if (MESSAGES < 1 || MESSAGES > 256) begin : g_bad_messages
        $error("rfl_rtps_disc_rom: MESSAGES must be 1..256");
    end
    if (PERIOD < 1) begin : g_bad_period
        $error("rfl_rtps_disc_rom: PERIOD must be at least 1");
    end
    if (DEST_BITS < 1 || DEST_BITS > 8) begin : g_bad_dest_bits
        $error("rfl_rtps_disc_rom: DEST_BITS must be 1..8");
    end
`endif

    localparam RB = (ROM_BYTES > 1) ? ROM_BYTES : 1;           // (sizes legal when refused)
    localparam NM = (MESSAGES > 1) ? MESSAGES : 1;
    localparam AW = (RB > 1) ? $clog2(RB) : 1;                  // byte address
    localparam MW = (NM > 1) ? $clog2(NM) : 1;                  // message number
    localparam CW = (PERIOD > 1) ? $clog2(PERIOD + 1) : 1;      // period counter
    localparam [31:0] PERIOD_LAST_32 = PERIOD - 1;
    localparam [CW-1:0] PERIOD_LAST = PERIOD_LAST_32[CW-1:0];
    localparam [31:0] LAST_MSG_32 = NM - 1;
    localparam [MW-1:0] LAST_MSG = LAST_MSG_32[MW-1:0];
    localparam [MW-1:0] MSG_SPDP = {MW{1'b0}};
    localparam [MW-1:0] MSG_ONE = {{(MW-1){1'b0}}, 1'b1};

    reg [7:0]  rom [0:RB-1];
    reg [39:0] table_mem [0:NM-1];
    generate
        if (ROM_FILE != "") begin : g_rom_file
            initial $readmemh(ROM_FILE, rom);
        end
        if (TABLE_FILE != "") begin : g_table_file
            initial $readmemh(TABLE_FILE, table_mem);
        end
    endgenerate

    reg [CW-1:0] ticks;                         // clocks to the next announcement
    reg spdp_wait;                              // an SPDP announcement waits
    reg sedp_wait;                              // a send_sedp request waits
    reg [MW-1:0] next_msg;                      // next message of a SEDP burst (0: none)
    reg sending;
    reg [AW-1:0] addr;                          // the byte after the one offered
    reg [7:0] q;                                // the byte offered (the ROM's read register)
    reg [15:0] left;                            // bytes of the datagram from q on
    reg [DEST_BITS-1:0] dest;

    wire take = sending && m_axis_tready;
    wire last = (left == 16'd1);
    wire done = take && last;
    wire idle = !sending || done;               // a datagram may start next clock

    // which message starts next clock (valid when start is set)
    wire start_spdp = idle && spdp_wait;
    wire start_burst = idle && !spdp_wait && (next_msg != MSG_SPDP);
    wire start_sedp = idle && !spdp_wait && (next_msg == MSG_SPDP) && sedp_wait
                      && (MESSAGES > 1);
    wire start = start_spdp || start_burst || start_sedp;
    wire [MW-1:0] msg = start_spdp ? MSG_SPDP : (start_burst ? next_msg : MSG_ONE);
    wire [39:0] entry;                          // the table's entry of msg
    wire [7:0] rom_q;                           // the ROM's byte at raddr

    wire [AW-1:0] first = entry[16 +: AW];
    wire [AW-1:0] raddr = start ? first : addr;
`ifdef FORMAL
    // the proofs hold for any ROM and table: every read returns any value
    (* anyseq *) wire [39:0] fv_entry;
    (* anyseq *) wire [7:0] fv_byte;
    assign entry = fv_entry;
    assign rom_q = fv_byte;
`else
    assign entry = table_mem[msg];
    assign rom_q = rom[raddr];
`endif

    assign m_axis_tdata = q;
    assign m_axis_tvalid = sending;
    assign m_axis_tlast = sending && last;
    assign m_axis_tdest = dest;
    assign busy = sending || spdp_wait || sedp_wait || (next_msg != MSG_SPDP);

    // an entry's offset and destination are wider than this ROM needs: their top bits are 0
    wire unused_ok = &{1'b0, entry};

    always @(posedge clk) begin
        if (!rst_n) begin
            ticks <= {CW{1'b0}};
            spdp_wait <= 1'b0;
            sedp_wait <= 1'b0;
            next_msg <= MSG_SPDP;
            sending <= 1'b0;
            addr <= {AW{1'b0}};
            q <= 8'd0;
            left <= 16'd0;
            dest <= {DEST_BITS{1'b0}};
        end else begin
            // the period: an announcement at once after reset, then every PERIOD clocks
            if (ticks == {CW{1'b0}}) begin
                ticks <= PERIOD_LAST;
                spdp_wait <= 1'b1;
            end else begin
                ticks <= ticks - 1'b1;
                if (start_spdp) spdp_wait <= 1'b0;
            end
            if (send_sedp && MESSAGES > 1) sedp_wait <= 1'b1;
            else if (start_sedp) sedp_wait <= 1'b0;
            if (start_sedp || start_burst)
                next_msg <= (msg == LAST_MSG) ? MSG_SPDP : msg + 1'b1;
            // the ROM is read on the clock (a block RAM's read port): the first byte as a
            // datagram starts, the next one as a beat is taken
            if (start || (take && !last)) begin
                q <= rom_q;
                addr <= raddr + 1'b1;
            end
            if (start) begin
                sending <= 1'b1;
                left <= entry[15:0];
                dest <= entry[32 +: DEST_BITS];
            end else if (done) begin
                sending <= 1'b0;
            end else if (take) begin
                left <= left - 1'b1;
            end
        end
    end
endmodule

`default_nettype wire
