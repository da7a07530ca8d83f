// rfl_window1d -- the 1-D application: every element of the streamed array is replaced by the
// maximum (OP 0, dilate) or the minimum (OP 1, erode) over the KSIZE elements centred on it,
// counting only the elements inside the array (OpenCV's border rule for dilate/erode); OP 2
// passes the elements through. One element per AXI4-Stream beat, TUSER on the array's first,
// TLAST on its last; one beat per clock when the output is ready.
//
// Ordering (KIND): 0 unsigned integers, 1 two's-complement signed integers, 2 IEEE-754 floats
// (EBYTES 4: float32, 8: float64). The window is folded oldest element first as numpy's
// maximum/minimum fold it (rosfpga_lab.hw.morph1d): acc = max2(acc, x) is acc if acc is NaN,
// else x if x is NaN, else (acc > x ? acc : x), compared by value (-0.0 equals +0.0, so of two
// zeros the later one wins); min2 likewise with <. A window holding a NaN gives its first NaN,
// bits unchanged.
//
// How it works: a shift register of KSIZE entries (valid, TUSER, TLAST), the newest in entry 0.
// An element's result is ready once R = KSIZE/2 later elements are in, so it is computed when
// the element reaches entry R; after an array's TLAST, R empty entries are shifted in (the
// input waits meanwhile) to finish its last R elements. Those R empties also keep the next
// array's window clear of this one. The fold is kept as it goes (100 MHz on an ECP5: one
// comparison per clock, not KSIZE - 1 in a row): for g = 1 .. KSIZE-1 a register holds the
// fold of the newest g entries (element, order key, NaN flag, whether any entry is valid), and
// a step folds the new element into each (the fold of g entries becomes that of g + 1). The
// window's result is the fold of the newest KSIZE-1 entries with the new element. The rule
// folded (the first NaN, else the last of the largest, or smallest, keys) picks the same
// element however the entries are grouped, so this equals numpy's left fold.
`default_nettype none

module rfl_window1d #(
    parameter EBYTES = 4,                       // bytes per element: 1, 2, 4 or 8
    parameter KSIZE = 3,                        // odd, 1..15
    parameter OP = 0,                           // 0 max (dilate), 1 min (erode), 2 passthrough
    parameter KIND = 0                          // 0 unsigned, 1 signed, 2 float
) (
    input  wire                aclk,
    input  wire                aresetn,
    input  wire [8*EBYTES-1:0] s_axis_tdata,
    input  wire                s_axis_tuser,
    input  wire                s_axis_tlast,
    input  wire                s_axis_tvalid,
    output wire                s_axis_tready,
    output reg  [8*EBYTES-1:0] m_axis_tdata,
    output wire [EBYTES-1:0]   m_axis_tkeep,
    output reg                 m_axis_tuser,
    output reg                 m_axis_tlast,
    output reg                 m_axis_tvalid,
    input  wire                m_axis_tready
);
    // Parameter contracts: an illegal value is refused at elaboration (Verilator, Yosys);
    // Icarus -g2005 has no elaboration tasks, so it stops at time 0, before any clock.
`ifdef __ICARUS__
    initial begin
        if (EBYTES != 1 && EBYTES != 2 && EBYTES != 4 && EBYTES != 8)
            $fatal(1, "rfl_window1d: EBYTES must be 1, 2, 4 or 8");
        if (KSIZE < 1 || KSIZE > 15 || KSIZE % 2 != 1)
            $fatal(1, "rfl_window1d: KSIZE must be odd, 1..15");
        if (OP < 0 || OP > 2)
            $fatal(1, "rfl_window1d: OP must be 0 (dilate), 1 (erode) or 2 (passthrough)");
        if (KIND < 0 || KIND > 2)
            $fatal(1, "rfl_window1d: KIND must be 0 (unsigned), 1 (signed) or 2 (float)");
    end
`else
    if (EBYTES != 1 && EBYTES != 2 && EBYTES != 4 && EBYTES != 8) begin : g_bad_ebytes
        $error("rfl_window1d: EBYTES must be 1, 2, 4 or 8");
    end
    if (KSIZE < 1 || KSIZE > 15 || KSIZE % 2 != 1) begin : g_bad_ksize
        $error("rfl_window1d: KSIZE must be odd, 1..15");
    end
    if (OP < 0 || OP > 2) begin : g_bad_op
        $error("rfl_window1d: OP must be 0 (dilate), 1 (erode) or 2 (passthrough)");
    end
    if (KIND < 0 || KIND > 2) begin : g_bad_kind
        $error("rfl_window1d: KIND must be 0 (unsigned), 1 (signed) or 2 (float)");
    end
`endif

    localparam EW = 8 * EBYTES;
    localparam K = (OP == 2) ? 1 : KSIZE;       // a pass-through has a window of one
    localparam R = K / 2;
    localparam [3:0] RFLUSH = R[3:0];
    localparam [EW-1:0] SIGN = {1'b1, {(EW-1){1'b0}}};

    localparam G = (K > 1) ? K - 1 : 1;         // folds kept (one unused for a window of one)

    reg [K-1:0]    wval, wuser, wlast;          // the window, entry 0 newest
    reg [G*EW-1:0] gdata, gkey;                 // fold of the newest g+1 entries: its element, key
    reg [G-1:0]    gnan, gval;                  // its NaN flag; whether it holds an element
    reg [3:0]      flush;                       // empty entries still to shift in

    wire out_free = !m_axis_tvalid || m_axis_tready;
    wire step_in = out_free && (flush == 4'd0) && s_axis_tvalid;
    wire step_empty = out_free && (flush != 4'd0);
    wire step = step_in || step_empty;

    assign s_axis_tready = out_free && (flush == 4'd0);
    assign m_axis_tkeep = {EBYTES{1'b1}};

    // The window after this step: the new element (or an empty entry) shifted in.
    wire [K-1:0]    nw_val = (wval << 1) | {{(K-1){1'b0}}, step_in};
    wire [K-1:0]    nw_user = (wuser << 1) | {{(K-1){1'b0}}, step_in && s_axis_tuser};
    wire [K-1:0]    nw_last = (wlast << 1) | {{(K-1){1'b0}}, step_in && s_axis_tlast};

    // The order key of an element by value (larger key, larger value; floats: -0.0 as +0.0).
    function [EW-1:0] order_key(input [EW-1:0] x);
        begin
            if (KIND == 2) order_key = (x == SIGN) ? SIGN : x[EW-1] ? ~x : (x | SIGN);
            else if (KIND == 1) order_key = x ^ SIGN;
            else order_key = x;
        end
    endfunction

    /* verilator lint_off UNUSEDSIGNAL */
    function is_nan(input [EW-1:0] x);
        reg [63:0] v;                           // x widened (the sign bit is not looked at)
        begin
            v = 64'd0;
            v[EW-1:0] = x;
            if (KIND != 2) is_nan = 1'b0;
            else if (EBYTES == 4) is_nan = (v[30:23] == 8'hff) && (v[22:0] != 23'd0);
            else is_nan = (v[62:52] == 11'h7ff) && (v[51:0] != 52'd0);
        end
    endfunction
    /* verilator lint_on UNUSEDSIGNAL */

    // the new entry; its key is compared as xkey_raw (a LUT from the FIFO's output), or as
    // -0.0's key SIGN, chosen after the comparison (xnegz, found beside it)
    wire [EW-1:0] x = s_axis_tdata;
    wire [EW-1:0] xkey = order_key(s_axis_tdata);
    wire          xnegz = (KIND == 2) && (s_axis_tdata == SIGN);
    wire [EW-1:0] xkey_raw = (KIND == 2) ? (x[EW-1] ? ~x : (x | SIGN)) : xkey;
    wire          xnan = is_nan(s_axis_tdata);

    // The older fold keeps its element against the new one: it is the only one valid, or it
    // holds a NaN (the first NaN wins), or the new one is no NaN and is smaller (larger for OP
    // 1): of equal keys the later element wins, as numpy's fold gives it.
    function keeps(input oval, input onan, input [EW-1:0] okey,
                   input nval, input nnan, input [EW-1:0] nkey_raw, input nnegz);
        begin
            if (!oval) keeps = 1'b0;
            else if (!nval) keeps = 1'b1;
            else if (onan) keeps = 1'b1;
            else if (nnan) keeps = 1'b0;
            else if (nnegz) keeps = (OP == 1) ? (okey < SIGN) : (okey > SIGN);
            else keeps = (OP == 1) ? (okey < nkey_raw) : (okey > nkey_raw);
        end
    endfunction

    // the folds after this step (nf*), and the window's result (best)
    reg [G*EW-1:0] nfdata, nfkey;
    reg [G-1:0]    nfnan, nfval;
    reg [EW-1:0]   best;
    integer t;
    always @* begin
        nfdata = gdata;
        nfkey = gkey;
        nfnan = gnan;
        nfval = gval;
        // the fold of the newest entry alone: the new one
        nfdata[EW-1:0] = step_in ? x : {EW{1'b0}};
        nfkey[EW-1:0] = step_in ? xkey : {EW{1'b0}};
        nfnan[0] = step_in && xnan;
        nfval[0] = step_in;
        for (t = 1; t < G; t = t + 1) begin
            if (keeps(gval[t-1], gnan[t-1], gkey[(t-1)*EW +: EW], step_in, xnan, xkey_raw, xnegz)) begin
                nfdata[t*EW +: EW] = gdata[(t-1)*EW +: EW];
                nfkey[t*EW +: EW] = gkey[(t-1)*EW +: EW];
                nfnan[t] = gnan[t-1];
            end else begin
                nfdata[t*EW +: EW] = x;
                nfkey[t*EW +: EW] = xkey;
                nfnan[t] = xnan;
            end
            nfval[t] = gval[t-1] || step_in;
        end
        if (K == 1) best = x;
        else if (keeps(gval[G-1], gnan[G-1], gkey[(G-1)*EW +: EW], step_in, xnan, xkey_raw, xnegz))
            best = gdata[(G-1)*EW +: EW];
        else best = x;
    end

    always @(posedge aclk) begin
        if (!aresetn) begin
            wval <= {K{1'b0}};
            wuser <= {K{1'b0}};
            wlast <= {K{1'b0}};
            gdata <= {(G*EW){1'b0}};
            gkey <= {(G*EW){1'b0}};
            gnan <= {G{1'b0}};
            gval <= {G{1'b0}};
            flush <= 4'd0;
            m_axis_tdata <= {EW{1'b0}};
            m_axis_tuser <= 1'b0;
            m_axis_tlast <= 1'b0;
            m_axis_tvalid <= 1'b0;
        end else begin
            if (m_axis_tvalid && m_axis_tready) m_axis_tvalid <= 1'b0;
            if (step) begin
                wval <= nw_val;
                wuser <= nw_user;
                wlast <= nw_last;
                gdata <= nfdata;
                gkey <= nfkey;
                gnan <= nfnan;
                gval <= nfval;
                if (step_in) flush <= s_axis_tlast ? RFLUSH : 4'd0;
                else flush <= flush - 4'd1;
                if (nw_val[R]) begin
                    m_axis_tdata <= best;
                    m_axis_tuser <= nw_user[R];
                    m_axis_tlast <= nw_last[R];
                    m_axis_tvalid <= 1'b1;
                end
            end
        end
    end
endmodule

`default_nettype wire
