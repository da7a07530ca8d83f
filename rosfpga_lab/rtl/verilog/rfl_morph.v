// rfl_morph -- the application circuit: rectangular dilate / erode of an AXI4-Stream video frame.
//
// One pixel per beat (tdata byte i = channel i, BYTES lanes used, the rest zero), tuser on the
// first pixel of a frame, tlast on the last pixel of each line: the lab's packing rule
// (rosfpga_lab/hw/encodings.py). Each output byte lane is the maximum (dilate) or minimum
// (erode) of that lane over the KSIZE x KSIZE window centred on the pixel, clipped to the image:
// cv2.dilate / cv2.erode with their default border. OP 2 copies the frame.
//
// How it works: the frame is a sequence of steps, one per clock when neither side stalls.
// Step s scans position (vrow, vcol) of an image extended by D = KSIZE/2 rows below: it takes
// the input pixel (rows < HEIGHT), writes it into one of KSIZE-1 line memories (row r lives in
// memory r mod (KSIZE-1), so no data moves between memories) and reads the KSIZE-1 rows above
// it, giving the vertical extreme V of column vcol over rows vrow-KSIZE+1 .. vrow (the rows in
// the image only). V goes into a KSIZE-long shift register; the output pixel D rows and D
// columns behind the scan takes the extreme of the entries that lie on its own line. The
// window's right part of the last pixel needs D more steps without input (the flush). A frame
// is (HEIGHT + D) * WIDTH + D steps; the first output leaves D * WIDTH + D steps after the first
// input, plus the six pipeline registers. No input is taken during the flush, so the next
// frame's first pixel goes in (HEIGHT + D) * WIDTH + D clocks after this frame's first one.
//
// Handshake: the step pipeline (issue, line-memory read, its register, the column's pairs,
// shift register, the row's pairs, output register) advances as a whole when the output register is empty or being taken (adv); s_axis_tready is
// adv while the step needs a pixel.
//
// Framing (as Xilinx's AXI4-Stream video IP): every frame the circuit starts comes out whole,
// WIDTH x HEIGHT beats with TUSER on the first and TLAST at each line end, whatever the input
// did, so the stages after it keep their byte count; a damaged frame is repaired and flagged
// and the next clean frame comes out right. The rules, beat by beat (hw.framing models them):
//   - beats before a TUSER beat are dropped (wait for the start of frame): sof_missing;
//   - TLAST before the line's last pixel: the rest of the line is zero pixels: eol_early;
//   - no TLAST on the line's last pixel: the beats after it are dropped up to and with the next
//     TLAST (a TUSER beat ends the dropping): eol_late;
//   - TUSER inside a frame: the rest of the frame is zero pixels, and the TUSER beat starts
//     the next frame: sof_early.
// framing holds these flags since reset: bit 0 sof_early, 1 eol_early, 2 eol_late,
// 3 sof_missing (the order of hw.framing.FRAMING_FLAGS).
`default_nettype none

module rfl_morph #(
    parameter WIDTH  = 640,
    parameter HEIGHT = 480,
    parameter KSIZE  = 3,
    parameter OP     = 0,   // 0 dilate, 1 erode, 2 passthrough
    parameter BYTES  = 4    // bytes per pixel: 4, 3 or 1
) (
    input  wire        aclk,
    input  wire        aresetn,
    input  wire [31:0] s_axis_tdata,
    input  wire [3:0]  s_axis_tkeep,
    input  wire        s_axis_tuser,
    input  wire        s_axis_tlast,
    input  wire        s_axis_tvalid,
    output wire        s_axis_tready,
    output reg  [31:0] m_axis_tdata,
    output wire [3:0]  m_axis_tkeep,
    output reg         m_axis_tuser,
    output reg         m_axis_tlast,
    output reg         m_axis_tvalid,
    input  wire        m_axis_tready,
    output reg  [3:0]  framing      // sticky since reset: sof_missing, eol_late, eol_early, sof_early
);

    // Parameter contracts: an illegal value is refused at elaboration (Verilator, Yosys);
    // Icarus -g2005 has no elaboration tasks, so it stops at time 0, before any clock.
`ifdef __ICARUS__
    initial begin
        if (BYTES < 1 || BYTES > 4)
            $fatal(1, "rfl_morph: BYTES must be 1..4 (one pixel per 32-bit beat)");
        if (OP < 0 || OP > 2)
            $fatal(1, "rfl_morph: OP must be 0 (dilate), 1 (erode) or 2 (passthrough)");
        if (OP != 2 && (KSIZE < 1 || KSIZE % 2 == 0))
            $fatal(1, "rfl_morph: KSIZE must be odd and at least 1");
        if (WIDTH < 1 || HEIGHT < 1) $fatal(1, "rfl_morph: WIDTH and HEIGHT must be at least 1");
    end
`else
    if (BYTES < 1 || BYTES > 4) begin : g_bad_bytes
        $error("rfl_morph: BYTES must be 1..4 (one pixel per 32-bit beat)");
    end
    if (OP < 0 || OP > 2) begin : g_bad_op
        $error("rfl_morph: OP must be 0 (dilate), 1 (erode) or 2 (passthrough)");
    end
    if (OP != 2 && (KSIZE < 1 || KSIZE % 2 == 0)) begin : g_bad_ksize
        $error("rfl_morph: KSIZE must be odd and at least 1");
    end
    if (WIDTH < 1 || HEIGHT < 1) begin : g_bad_size
        $error("rfl_morph: WIDTH and HEIGHT must be at least 1");
    end
`endif

    localparam K    = (OP == 2) ? 1 : KSIZE;
    localparam D    = K / 2;
    localparam W    = 8 * BYTES;
    localparam NL   = (K > 1) ? K - 1 : 1;           // line memories (1 unused when K == 1)
    localparam LEAD = D * WIDTH + D;                 // steps before the first output
    localparam VROWS = HEIGHT + D;                   // scan rows
    localparam RW   = $clog2(VROWS + 1);
    localparam CW   = $clog2(WIDTH + 1);
    localparam AW   = (WIDTH > 1) ? $clog2(WIDTH) : 1;  // a line memory's address (< CW when WIDTH is 2^n)
    localparam OW   = $clog2(HEIGHT + 1);
    localparam LW   = (LEAD > 0) ? $clog2(LEAD + 1) : 1;
    localparam SW   = (NL > 1) ? $clog2(NL) : 1;
    localparam [W-1:0] ID = (OP == 1) ? {W{1'b1}} : {W{1'b0}};  // identity of max / min
    // the same constants at the widths of the counters they are compared with
    localparam [31:0] LAST_VROW_32 = VROWS - 1, LAST_ROW_32 = HEIGHT - 1,
                      LAST_COL_32 = WIDTH - 1, LEAD_32 = LEAD, LAST_LINE_32 = NL - 1;
    localparam [RW-1:0] LAST_VROW = LAST_VROW_32[RW-1:0];
    localparam [RW-1:0] LAST_IROW = LAST_ROW_32[RW-1:0];
    localparam [OW-1:0] LAST_ROW  = LAST_ROW_32[OW-1:0];
    localparam [CW-1:0] LAST_COL  = LAST_COL_32[CW-1:0];
    localparam [LW-1:0] LEAD_R    = LEAD_32[LW-1:0];
    localparam [SW-1:0] LAST_LINE = LAST_LINE_32[SW-1:0];
    localparam [3:0] KEEP = (BYTES == 4) ? 4'b1111 : (BYTES == 3) ? 4'b0111 :
                            (BYTES == 2) ? 4'b0011 : 4'b0001;

    // per-lane maximum (dilate) or minimum (erode)
    function [W-1:0] pick(input [W-1:0] a, input [W-1:0] b);
        integer l;
        begin
            for (l = 0; l < BYTES; l = l + 1)
                if (OP == 1)
                    pick[8*l +: 8] = (b[8*l +: 8] < a[8*l +: 8]) ? b[8*l +: 8] : a[8*l +: 8];
                else
                    pick[8*l +: 8] = (b[8*l +: 8] > a[8*l +: 8]) ? b[8*l +: 8] : a[8*l +: 8];
        end
    endfunction

    // ---- step issue ------------------------------------------------------------------------
    reg           run;         // inside a frame (else waiting for a tuser beat)
    reg [RW-1:0]  vrow;        // scan position
    reg [CW-1:0]  vcol;
    reg [LW-1:0]  lead;        // steps left before outputs start
    reg [OW-1:0]  orow;        // position of the next output pixel
    reg [CW-1:0]  ocol;
    reg [NL-1:0]  mvalid;      // line memory m holds a row of this frame's image
    reg [SW-1:0]  wsel;        // line memory the current scan row is written to

    reg           vact_r;      // vrow < VROWS: the scan is inside the extended image
    reg           inrow_r;     // vrow < HEIGHT: the scan row takes input pixels
    reg           padl;        // an early TLAST: the rest of this line is zero pixels
    reg           padf;        // an early TUSER: the rest of this frame is zero pixels
    reg           drop;        // no TLAST at the line end: drop beats up to the next TLAST

    wire adv     = !m_axis_tvalid || m_axis_tready;
    wire vact    = (D > 0) ? vact_r : inrow_r;     // registered: no compare before fire
    wire in_row  = inrow_r;
    wire need_in = run && vact && in_row;          // the step takes a pixel of the frame
    wire sof_in  = s_axis_tvalid && s_axis_tuser;
    wire dropping = drop && !sof_in;               // a TUSER beat is never dropped here
    wire pad     = padl || padf || sof_in;         // the step's pixel is zero, no beat taken
    wire take_px = adv && (run ? (need_in && !pad && !dropping && s_axis_tvalid)
                               : (sof_in && !dropping));
    wire fire    = run ? adv && (!need_in || pad || take_px) : take_px;
    wire emit    = (lead == 0);
    wire last_px = emit && (orow == LAST_ROW) && (ocol == LAST_COL);
    wire         pz  = run && pad;                 // the step's pixel is a zero (padding)
    wire [W-1:0] pix = pz ? {W{1'b0}} : s_axis_tdata[W-1:0];    // into the line memories
    wire skip    = s_axis_tvalid && (dropping || (!run && adv && !s_axis_tuser));

    assign s_axis_tready = dropping || (run ? adv && need_in && !pad : adv);

    // which shift-register entries lie on the output pixel's line (entry j is column ocol+D-j)
    reg [K-1:0] hmask_n;
    integer j, oc;
    always @* begin
        oc = {{(32 - CW){1'b0}}, ocol} + D;
        for (j = 0; j < K; j = j + 1)
            hmask_n[j] = (oc >= j) && (oc <= WIDTH - 1 + j);
    end

    always @(posedge aclk) begin
        if (!aresetn) begin
            run <= 1'b0;
            vrow <= 0; vcol <= 0; lead <= LEAD_R; orow <= 0; ocol <= 0;
            mvalid <= 0; wsel <= 0; vact_r <= 1'b1; inrow_r <= 1'b1;
            padl <= 1'b0; padf <= 1'b0; drop <= 1'b0; framing <= 4'd0;
        end else begin
          if (skip) begin                              // a beat dropped
            if (!dropping) framing[3] <= 1'b1;         // before the start of frame
            if (dropping && s_axis_tlast) drop <= 1'b0;
          end
          if (drop && sof_in) drop <= 1'b0;
          if (fire && run && need_in && pad && !padl && !padf) begin
            padf <= 1'b1;                              // TUSER inside the frame
            framing[0] <= 1'b1;
          end
          if (take_px) begin
            if (s_axis_tlast && vcol != LAST_COL) begin
                padl <= 1'b1;                          // line too short
                framing[1] <= 1'b1;
            end
            if (!s_axis_tlast && vcol == LAST_COL) begin
                drop <= 1'b1;                          // line too long
                framing[2] <= 1'b1;
            end
          end
          if (fire) begin
            run <= 1'b1;
            if (vact) begin
                if (vcol == LAST_COL) begin
                    padl <= 1'b0;
                    vcol <= 0;
                    vrow <= vrow + 1'b1;
                    vact_r <= (vrow != LAST_VROW);
                    inrow_r <= inrow_r && (vrow != LAST_IROW);
                    mvalid[wsel] <= in_row;
                    wsel <= (wsel == LAST_LINE) ? {SW{1'b0}} : wsel + 1'b1;
                end else begin
                    vcol <= vcol + 1'b1;
                end
            end
            if (!emit) begin
                lead <= lead - 1'b1;
            end else if (ocol == LAST_COL) begin
                ocol <= 0;
                orow <= orow + 1'b1;
            end else begin
                ocol <= ocol + 1'b1;
            end
            if (last_px) begin       // frame done: back to waiting for the next tuser
                run <= 1'b0;
                vrow <= 0; vcol <= 0; lead <= LEAD_R; orow <= 0; ocol <= 0;
                mvalid <= 0; wsel <= 0; vact_r <= 1'b1; inrow_r <= 1'b1;
                padl <= 1'b0; padf <= 1'b0;
            end
          end
        end
    end

    // ---- stage 1: line memories read, current pixel, validity flags --------------------------
    reg           valid1;
    reg [W-1:0]   p1;
    reg           pv1;         // p1 is an image pixel
    reg           pz1;         // ... and a zero of padding
    reg [NL-1:0]  mv1;         // line memory outputs that are image pixels
    reg           emit1, first1, eol1;
    reg [K-1:0]   hmask1;
    wire [NL*W-1:0] qall;

    genvar m;
    generate
        if (K > 1) begin : lines
            for (m = 0; m < NL; m = m + 1) begin : line
                localparam [SW-1:0] SEL = m;
                reg [W-1:0] mem [0:WIDTH-1];
                reg [W-1:0] q;
                always @(posedge aclk) begin
                    if (fire && vact) begin
                        if (wsel == SEL) mem[vcol[AW-1:0]] <= pix;
                        q <= mem[vcol[AW-1:0]];  // read-first: the row written KSIZE-1 rows ago
                    end
                end
                assign qall[m*W +: W] = q;
            end
        end else begin : nolines
            assign qall = {NL*W{1'b0}};
        end
    endgenerate

    always @(posedge aclk) begin
        if (!aresetn) begin
            valid1 <= 1'b0;
        end else if (adv) begin
            valid1 <= fire;
        end
        if (aresetn && adv && fire) begin      // the step's payload (see stage 1r)
            p1     <= s_axis_tdata[W-1:0];
            pz1    <= pz;
            pv1    <= vact && in_row;
            mv1    <= vact ? mvalid : {NL{1'b0}};
            emit1  <= emit;
            first1 <= (orow == 0) && (ocol == 0);
            eol1   <= (ocol == LAST_COL);
            hmask1 <= hmask_n;
        end
    end

    // ---- stage 1r: the line memories' outputs registered (a block RAM's clock-to-output is
    // slow; the window's extremes start from flip-flops), those outside the image replaced by
    // the identity of the extreme on the way ----------------------------------------------------
    // The candidates, pairs and tree nodes below are one W-bit word per generate block, indexed
    // by constants, not wide vectors walked by functions: the same logic, and a Verilated
    // model that evaluates only the words that exist (the simulation's speed). These data
    // registers load only with a step (their stage's valid): a bubble leaves them as they
    // were, which nothing reads, and the simulation skips their comparisons then (a pixel
    // comes every BYTES clocks from the byte stream).
    reg           valid1r, emit1r, first1r, eol1r;
    reg [K-1:0]   hmask1r;

    always @(posedge aclk) begin
        if (!aresetn) begin
            valid1r <= 1'b0;
        end else if (adv) begin
            valid1r <= valid1;
        end
        if (aresetn && adv && valid1) begin
            emit1r  <= emit1;
            first1r <= first1;
            eol1r   <= eol1;
            hmask1r <= hmask1;
        end
    end

    // candidates of the vertical extreme, vc[c].v: the pixel (c = 0), then the lines; one more
    // (the identity) when their count is odd, so that every pair below has two
    localparam NC = NL + 1 + ((NL + 1) % 2);
    genvar c;
    generate
        for (c = 0; c < NC; c = c + 1) begin : vc
            reg  [W-1:0] v;
            wire [W-1:0] src;
            if (c == 0) begin : pixel
                assign src = pv1 ? (pz1 ? {W{1'b0}} : p1) : ID;
            end else if (K > 1 && c <= NL) begin : line
                assign src = mv1[c-1] ? qall[(c-1)*W +: W] : ID;
            end else begin : pad
                assign src = ID;
            end
            always @(posedge aclk) if (aresetn && adv && valid1) v <= src;
        end
    endgenerate

    // ---- stage 1v: the vertical candidates paired (the tree's first level) and registered ----
    localparam VP = NC / 2;                    // pairs of the NL + 1 candidates
    localparam VT = 1 << $clog2(VP);           // leaves of the tree: VP, rounded up to 2**n
    reg           valid1v, emit1v, first1v, eol1v;
    reg [K-1:0]   hmask1v;
    always @(posedge aclk) begin
        if (!aresetn) begin
            valid1v <= 1'b0;
        end else if (adv) begin
            valid1v <= valid1r;
        end
        if (aresetn && adv && valid1r) begin
            emit1v  <= emit1r;
            first1v <= first1r;
            eol1v   <= eol1r;
            hmask1v <= hmask1r;
        end
    end

    // The extreme of the VP pairs as a balanced tree of pick (ceil(log2 VP) comparisons deep),
    // numbered as a heap: node n (1 <= n < VT) picks from nodes 2n and 2n+1, node VT + p is
    // pair p (registered; the identity past VP), the root is node 1.
    generate
        for (c = 1; c < 2 * VT; c = c + 1) begin : vt
            wire [W-1:0] w;
            if (c >= VT && c - VT < VP) begin : pair
                reg [W-1:0] r;
                always @(posedge aclk)
                    if (aresetn && adv && valid1r) r <= pick(vc[2*(c-VT)].v, vc[2*(c-VT)+1].v);
                assign w = r;
            end else if (c >= VT) begin : pad
                assign w = ID;
            end else begin : node
                assign w = pick(vt[2*c].w, vt[2*c+1].w);
            end
        end
    endgenerate

    // vertical extreme of the column over the image rows of the window
    wire [W-1:0] vext = vt[1].w;

    // ---- stage 2: horizontal shift register of vertical extremes -----------------------------
    reg           valid2, emit2, first2, eol2;
    reg [K-1:0]   hmask2;

    always @(posedge aclk) begin
        if (!aresetn) begin
            valid2 <= 1'b0;
        end else if (adv) begin
            valid2 <= valid1v;
        end
        if (aresetn && adv && valid1v) begin
            emit2  <= emit1v;
            first2 <= first1v;
            eol2   <= eol1v;
            hmask2 <= hmask1v;
        end
    end

    // the shift register, one word per entry (sh[0].e newest), as the trees are; sr shows the
    // whole register as one bus in waveforms (nothing reads it)
    wire [K*W-1:0] sr;
    generate
        for (c = 0; c < K; c = c + 1) begin : sh
            reg [W-1:0] e;
            if (c == 0) begin : newest
                always @(posedge aclk) if (adv && valid1v) e <= vext;
            end else begin : older
                always @(posedge aclk) if (adv && valid1v) e <= sh[c-1].e;
            end
            assign sr[c*W +: W] = e;
        end
    endgenerate

    // ---- stage 2b: the entries on the output pixel's line (else the identity), paired (the
    // first level of the horizontal tree; K is odd, the last pair's second word is the
    // identity) and registered; the rest of the tree after them, numbered as vt ---------------
    localparam HP = (K + 1) / 2;
    localparam HT = 1 << $clog2(HP);
    reg           valid2b, emit2b, first2b, eol2b;
    always @(posedge aclk) begin
        if (!aresetn) begin
            valid2b <= 1'b0;
        end else if (adv) begin
            valid2b <= valid2;
        end
        if (aresetn && adv && valid2) begin
            emit2b  <= emit2;
            first2b <= first2;
            eol2b   <= eol2;
        end
    end
    generate
        for (c = 0; c < 2 * HP; c = c + 1) begin : hc
            wire [W-1:0] w;
            if (c < K) begin : entry
                assign w = hmask2[c] ? sh[c].e : ID;
            end else begin : pad
                assign w = ID;
            end
        end
        for (c = 1; c < 2 * HT; c = c + 1) begin : ht
            wire [W-1:0] w;
            if (c >= HT && c - HT < HP) begin : pair
                reg [W-1:0] r;
                always @(posedge aclk)
                    if (aresetn && adv && valid2) r <= pick(hc[2*(c-HT)].w, hc[2*(c-HT)+1].w);
                assign w = r;
            end else if (c >= HT) begin : pad
                assign w = ID;
            end else begin : node
                assign w = pick(ht[2*c].w, ht[2*c+1].w);
            end
        end
    endgenerate
    wire [W-1:0] hext = ht[1].w;

    // ---- stage 3: output register ------------------------------------------------------------
    assign m_axis_tkeep = KEEP;

    always @(posedge aclk) begin
        if (!aresetn) begin
            m_axis_tvalid <= 1'b0;
            m_axis_tdata  <= 32'd0;
            m_axis_tuser  <= 1'b0;
            m_axis_tlast  <= 1'b0;
        end else if (adv) begin
            m_axis_tvalid <= valid2b && emit2b;
            if (valid2b) begin
                m_axis_tdata  <= 32'd0;
                m_axis_tdata[W-1:0] <= hext;
                m_axis_tuser  <= first2b;
                m_axis_tlast  <= eol2b;
            end
        end
    end

    // tkeep and the unused lanes of the input are not needed; sr is for waveforms
    // pix, mv1, qall: K == 1 has no lines
    wire unused_ok = &{1'b0, s_axis_tkeep, s_axis_tdata, pix, mv1, qall, sr};

endmodule

`default_nettype wire
