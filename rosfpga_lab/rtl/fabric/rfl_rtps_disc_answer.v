// rfl_rtps_disc_answer -- the fabric participant's answers to ACKNACK and HEARTBEAT (issue #31:
// its built-in writers are reliable): takes rfl_rtps_ctrl's requests (one a beat on s_axis,
// {base[63:0], guidPrefix[95:0], message[7:0]}) and sends answer ROM message `message` as one
// UDP payload on an 8-bit AXI4-Stream (TLAST on its last byte, TDEST its destination as in
// rfl_rtps_disc_rom, m_dst_prefix the asker's GUID prefix for the UDP/IP side's locator, both
// constant over the datagram), with its run-time fields written as it goes (the layout is
// rosfpga_lab.rtl.discrom's: render_answers, answer_params):
//   bytes DST_AT .. DST_AT+11: guidPrefix (INFO_DST: the answer is for the asker);
//   bytes BASE_AT .. BASE_AT+7 when the table entry's flag bit 0 is set (an ACKNACK): base,
//     as an RTPS sequence number little endian (high half, then low half);
//   the last 4 bytes: the answer counter (HEARTBEAT's or ACKNACK's count, little endian),
//     COUNT_START at reset, one more after each answer (a count must rise to be acted on).
// ROM_FILE holds the answers back to back, a byte a line; TABLE_FILE one entry a line,
// {flags[7:0], dest[7:0], offset[15:0], length[15:0]} (lengths >= DST_AT + 16: checked by
// rosfpga_lab.rtl.discrom, which renders every answer with its header, INFO_DST and a count).
// Bounded: a credit of bytes, BURST at reset, RATE more per byte received (rx_byte), at most
// BURST; an answer starts only when the credit holds its length, which it spends at once; one
// it cannot afford is dropped and counted (cnt_no_credit: the peer asks again). So the bytes
// sent are never more than BURST + RATE x the bytes received (formal/fv_rtps_disc_answer.sv
// proves it, in every reachable state, with the stream rules, for any ROM contents).
// A request is taken when no answer is on its way (s_axis_tready); the clock after, its table
// entry is read into a register; the clock after, the answer starts (or is dropped). The ROM is
// read on the clock into its own register (a block RAM's read port), one byte per clock taken;
// TDATA is that register or, on a written field, the register that holds the field's byte.
// Timing: the credit compare, the ROM address and the field positions read registers only.
`default_nettype none

module rfl_rtps_disc_answer #(
    parameter ROM_FILE = "",                    // rfl_rtps_disc_answer.hex ("": empty, to lint)
    parameter TABLE_FILE = "",                  // rfl_rtps_disc_answer_table.hex
    parameter ROM_BYTES = 2048,                 // bytes in ROM_FILE, 1..65536: checked
    parameter MESSAGES = 9,                     // entries in TABLE_FILE, 1..256: checked
    parameter DST_AT = 24,                      // INFO_DST's prefix in every answer
    parameter BASE_AT = 48,                     // an ACKNACK's base
    parameter COUNT_START = 3,                  // the first answer's count, >= 1
    parameter BURST = 4096,                     // credit at reset and at most: 1..65535
    parameter RATE = 4,                         // credit per byte received: 0..255
    parameter DEST_BITS = 2,                    // width of m_axis_tdest, 1..8
    parameter COUNT_BITS = 32                   // width of the counters: 1..32
) (
    input  wire                  clk,
    input  wire                  rst_n,
    input  wire                  rx_byte,       // a byte received (rfl_rtps_ctrl's rx_byte)
    input  wire [167:0]          s_axis_tdata,  // {base, guidPrefix, message}
    input  wire                  s_axis_tvalid,
    output wire                  s_axis_tready,
    output wire [7:0]            m_axis_tdata,
    output wire                  m_axis_tvalid,
    input  wire                  m_axis_tready,
    output wire                  m_axis_tlast,
    output wire [DEST_BITS-1:0]  m_axis_tdest,
    output wire [95:0]           m_dst_prefix,  // the asker (constant over a datagram)
    output wire [15:0]           credit,        // bytes the credit holds
    output wire [COUNT_BITS-1:0] cnt_answers,
    output wire [COUNT_BITS-1:0] cnt_no_credit
);
    // Parameter contracts: an illegal value is refused at elaboration (Verilator, Yosys);
    // Icarus -g2005 has no elaboration tasks, so it stops at time 0, before any clock.
`ifdef __ICARUS__
    initial begin
        if (ROM_BYTES < 1 || ROM_BYTES > 65536)
            $fatal(1, "rfl_rtps_disc_answer: ROM_BYTES must be 1..65536 (16-bit offsets)");
        if (MESSAGES < 1 || MESSAGES > 256) $fatal(1, "rfl_rtps_disc_answer: MESSAGES must be 1..256");
        if (COUNT_START < 1) $fatal(1, "rfl_rtps_disc_answer: COUNT_START must be at least 1");
        if (BURST < 1 || BURST > 65535) $fatal(1, "rfl_rtps_disc_answer: BURST must be 1..65535");
        if (RATE < 0 || RATE > 255) $fatal(1, "rfl_rtps_disc_answer: RATE must be 0..255");
        if (DEST_BITS < 1 || DEST_BITS > 8) $fatal(1, "rfl_rtps_disc_answer: DEST_BITS must be 1..8");
        if (COUNT_BITS < 1 || COUNT_BITS > 32)
            $fatal(1, "rfl_rtps_disc_answer: COUNT_BITS must be 1..32");
    end
`else
    if (ROM_BYTES < 1 || ROM_BYTES > 65536) begin : g_bad_rom_bytes
        $error("rfl_rtps_disc_answer: ROM_BYTES must be 1..65536 (16-bit offsets)");
    end
    if (MESSAGES < 1 || MESSAGES > 256) begin : g_bad_messages
        $error("rfl_rtps_disc_answer: MESSAGES must be 1..256");
    end
    if (COUNT_START < 1) begin : g_bad_count_start
        $error("rfl_rtps_disc_answer: COUNT_START must be at least 1");
    end
    if (BURST < 1 || BURST > 65535) begin : g_bad_burst
        $error("rfl_rtps_disc_answer: BURST must be 1..65535");
    end
    if (RATE < 0 || RATE > 255) begin : g_bad_rate
        $error("rfl_rtps_disc_answer: RATE must be 0..255");
    end
    if (DEST_BITS < 1 || DEST_BITS > 8) begin : g_bad_dest_bits
        $error("rfl_rtps_disc_answer: DEST_BITS must be 1..8");
    end
    if (COUNT_BITS < 1 || COUNT_BITS > 32) begin : g_bad_count_bits
        $error("rfl_rtps_disc_answer: COUNT_BITS must be 1..32");
    end
`endif

    localparam RB = (ROM_BYTES > 1) ? ROM_BYTES : 1;           // (sizes legal when refused)
    localparam NM = (MESSAGES > 1) ? MESSAGES : 1;
    localparam AW = (RB > 1) ? $clog2(RB) : 1;
    localparam MW = (NM > 1) ? $clog2(NM) : 1;
    localparam [31:0] NM_32 = NM;
    localparam [31:0] BURST_32 = BURST;
    localparam [31:0] RATE_32 = RATE;
    // at or above this, a byte received fills the credit to BURST
    localparam [15:0] BURST_LESS_RATE = (BURST > RATE) ? BURST_32[15:0] - RATE_32[15:0] : 16'd0;
    localparam [31:0] CS_32 = COUNT_START;
    localparam [31:0] DST_32 = DST_AT;
    localparam [31:0] BASE_32 = BASE_AT;
    localparam [15:0] DST_FIRST = DST_32[15:0], DST_END = DST_32[15:0] + 16'd12;
    localparam [15:0] BASE_FIRST = BASE_32[15:0], BASE_END = BASE_32[15:0] + 16'd8;
    localparam DST_AT_0 = (DST_32 == 0), BASE_AT_0 = (BASE_32 == 0);
    // the byte two after the one at pos is in a field: pos in [FIRST - 2, END - 3] (the low
    // end at least 0; constants: no adder on the path); after the first byte (pos 0), byte 1
    // is when 1 is in [FIRST, END)
    localparam [15:0] DST_LO2 = (DST_FIRST >= 16'd2) ? DST_FIRST - 16'd2 : 16'd0;
    localparam [15:0] DST_HI2 = DST_END - 16'd3;
    localparam [15:0] BASE_LO2 = (BASE_FIRST >= 16'd2) ? BASE_FIRST - 16'd2 : 16'd0;
    localparam [15:0] BASE_HI2 = BASE_END - 16'd3;
    localparam DST_AT_1 = (DST_32 <= 1) && (DST_32 + 12 > 1);
    localparam BASE_AT_1 = (BASE_32 <= 1) && (BASE_32 + 8 > 1);

    reg [7:0]  rom [0:RB-1];
    reg [47:0] table_mem [0:NM-1];
    generate
        if (ROM_FILE != "") begin : g_rom_file
            initial $readmemh(ROM_FILE, rom);
        end
        if (TABLE_FILE != "") begin : g_table_file
            initial $readmemh(TABLE_FILE, table_mem);
        end
    endgenerate

    reg req;                                    // a request taken: its entry is read
    reg look;                                   // its entry held: the answer starts or not
    reg [7:0] r_msg;
    reg [95:0] r_prefix;
    reg [47:0] entry_r;
    reg afford;                                 // the credit holds its length (it only grows
                                                // until an answer starts)
    reg [95:0] pfx_sh;                          // the prefix, a byte out per INFO_DST byte
    reg [63:0] base_sh;                         // the base in wire order, a byte out per byte
    reg [31:0] count, cnt_sh;
    reg sending, r_base;
    reg [AW-1:0] addr;                          // the byte after the one offered
    reg [7:0] rom_q;                            // the ROM's read register (a block RAM's)
    reg [7:0] q;                                // a written field's byte
    reg q_rom;                                  // the byte offered is rom_q (else q)
    reg [15:0] left;                            // bytes of the datagram from the one offered
    reg [15:0] pos;                             // the byte of the datagram offered
    reg [DEST_BITS-1:0] dest;
    reg [15:0] cred;
    reg [COUNT_BITS-1:0] n_ans, n_poor;

    wire take = sending && m_axis_tready;
    reg left1, left5;                           // left == 1, left <= 5 (registered: timing)
    wire last = left1;
    wire done = take && last;
    assign s_axis_tready = !sending && !req && !look;
    wire accept = s_axis_tvalid && s_axis_tready;

    wire [47:0] entry;                          // the table's entry of r_msg
    wire [7:0] rom_byte;                        // the ROM's byte at raddr
    wire [15:0] e_len = entry_r[15:0];
    wire start = look && afford;
    wire [AW-1:0] raddr = start ? entry_r[16 +: AW] : addr;
`ifdef FORMAL
    (* anyseq *) wire [47:0] fv_entry;
    (* anyseq *) wire [7:0] fv_byte;
    assign entry = fv_entry;
    assign rom_byte = fv_byte;
`else
    assign entry = table_mem[r_msg[MW-1:0]];
    assign rom_byte = rom[raddr];
`endif

    // the byte read next (start: the first; a beat taken: the next) and where it is
    wire [15:0] ld_pos = start ? 16'd0 : pos + 16'd1;
    // whether the byte after the one read is in a field, registered as it is read (timing)
    reg dst_nx, base_nx;
    wire in_dst = start ? DST_AT_0 : dst_nx;
    wire in_base = start ? (entry_r[40] && BASE_AT_0) : (r_base && base_nx);
    wire in_count = start ? (e_len <= 16'd4) : left5;
    wire [95:0] pfx_now = start ? r_prefix : pfx_sh;
    wire ld = start || (take && !last);

    assign m_axis_tdata = q_rom ? rom_q : q;
    assign m_axis_tvalid = sending;
    assign m_axis_tlast = sending && last;
    assign m_axis_tdest = dest;
    assign m_dst_prefix = r_prefix;
    assign credit = cred;
    assign cnt_answers = n_ans;
    assign cnt_no_credit = n_poor;

    // an entry's flags and destination are wider than this module uses: their top bits are 0
    wire [15:0] e_dest = {8'd0, entry_r[39:32]};   // (wide enough for any DEST_BITS refused)
    wire unused_ok = &{1'b0, entry_r, e_dest, r_msg};

    always @(posedge clk) begin
        if (!rst_n) begin
            req <= 1'b0;
            look <= 1'b0;
            sending <= 1'b0;
            count <= CS_32;
            cred <= BURST_32[15:0];
            n_ans <= {COUNT_BITS{1'b0}};
            n_poor <= {COUNT_BITS{1'b0}};
            left <= 16'd0;
            left1 <= 1'b0;
            left5 <= 1'b0;
            pos <= 16'd0;
            q <= 8'd0;
            q_rom <= 1'b1;
            addr <= {AW{1'b0}};
            dest <= {DEST_BITS{1'b0}};
            r_base <= 1'b0;
        end else begin
            // the credit: an answer's length spent as it starts (a byte received that clock
            // earns nothing: the bound only gains), else RATE a byte received, at most BURST
            if (start) cred <= cred - e_len;
            else if (rx_byte) cred <= (cred >= BURST_LESS_RATE) ? BURST_32[15:0]
                                                                 : cred + RATE_32[15:0];
            if (accept) begin
                req <= 1'b1;
                r_msg <= s_axis_tdata[7:0];
                r_prefix <= s_axis_tdata[103:8];
                // the base as on the wire: high half little endian, then low half
                base_sh <= {s_axis_tdata[143:136], s_axis_tdata[151:144], s_axis_tdata[159:152],
                            s_axis_tdata[167:160], s_axis_tdata[111:104], s_axis_tdata[119:112],
                            s_axis_tdata[127:120], s_axis_tdata[135:128]};
                cnt_sh <= count;                // little endian: the low byte first
            end
            if (req) begin
                req <= 1'b0;
                look <= 1'b1;
                entry_r <= entry;
                // (a request past the table: dropped)
                afford <= ({24'd0, r_msg} < NM_32) && (cred >= entry[15:0]) &&
                          (entry[15:0] != 16'd0);
            end
            if (look) begin
                look <= 1'b0;
                if (!afford) n_poor <= n_poor + 1'b1;
            end
            if (ld) begin
                rom_q <= rom_byte;
                addr <= raddr + 1'b1;
                pos <= ld_pos;
                dst_nx <= start ? DST_AT_1 : (pos >= DST_LO2 && pos <= DST_HI2);
                base_nx <= start ? BASE_AT_1 : (pos >= BASE_LO2 && pos <= BASE_HI2);
                q_rom <= !(in_dst || in_base || in_count);
                q <= in_dst ? pfx_now[95:88] : in_base ? base_sh[63:56] : cnt_sh[7:0];
                if (in_dst) pfx_sh <= {pfx_now[87:0], 8'd0};
                else if (start) pfx_sh <= r_prefix;
                if (in_base) base_sh <= {base_sh[55:0], 8'd0};
                if (in_count) cnt_sh <= {8'd0, cnt_sh[31:8]};
            end
            if (start) begin
                sending <= 1'b1;
                left <= e_len;
                left1 <= (e_len == 16'd1);
                left5 <= (e_len <= 16'd5);
                dest <= e_dest[DEST_BITS-1:0];
                r_base <= entry_r[40];
            end else if (done) begin
                sending <= 1'b0;
                count <= count + 1'b1;
                n_ans <= n_ans + 1'b1;
            end else if (take) begin
                left <= left - 1'b1;
                left1 <= (left == 16'd2);
                left5 <= (left <= 16'd6);
            end
        end
    end

`ifdef FORMAL
    // The byte bound on the ports, with the invariants that make it inductive (fv_rtps_disc_answer
    // proves them): f_allow, BURST + RATE x the bytes received - the bytes sent (kept at most
    // 2 x BURST, which only lowers it), always covers the credit and the bytes still to send of
    // the answer going out; so it never goes below 0: the bytes sent are never more than
    // BURST + RATE x the bytes received.
    localparam [31:0] F_MAX = 2 * BURST;
    reg [31:0] f_allow;
    wire [31:0] f_earn = f_allow + (rx_byte ? RATE_32 : 32'd0);
    always @(posedge clk) begin
        if (!rst_n) f_allow <= BURST_32;
        else f_allow <= ((f_earn > F_MAX) ? F_MAX : f_earn) - {31'd0, take};
    end
    always @(*) if (rst_n) begin
        assert(cred <= BURST_32[15:0]);
        assert(f_allow <= F_MAX);
        assert(f_allow >= {16'd0, cred} + (sending ? {16'd0, left} : 32'd0));
        if (sending) assert(left != 16'd0 && left <= BURST_32[15:0] && left1 == (left == 16'd1));
        if (req || look) assert(!sending);
        if (look && afford) assert(cred >= e_len && e_len != 16'd0);
    end
`endif
endmodule

`default_nettype wire
