// rfl_fabric_node_params.vh -- rfl_fabric_node's parameters, the one list the tops above it
// (rfl_fabric_top, rfl_board_5a75b, through rfl_fabric_top_params.vh) declare too: included in
// a module's #( ... ) list, last (no comma after it); rfl_fabric_node_pass.vh passes them on.
    parameter MAX_BYTES = 2048,                 // the seam's longest sample
    // this participant's GUID prefix, the one the ROMs were rendered with
    // (rtl.discrom.tx_parameters): the transmit path's source, and the receive side's and
    // rfl_rtps_ctrl's own (INFO_DST to it taken, its own messages looped back dropped)
    parameter [95:0] GUID_PREFIX = 96'h010f_7266_6c46_4142_5249_4300,
    parameter [31:0] WRITER_ID = 32'h00000203,
    parameter [31:0] READER_ID = 32'd0,
    parameter FRAG_BYTES = 1344,
    parameter MAX_DATAGRAM = 1472,
    parameter INFO_TS = 1,
    parameter ROM_FILE = "",                    // discovery ROM (rtl.discrom.write_rom)
    parameter TABLE_FILE = "",
    parameter ROM_BYTES = 1472,
    parameter MESSAGES = 3,
    parameter PERIOD = 100000000,               // clocks between SPDP announcements, >= 1
    parameter SLOTS = 5,                        // answers (rtl.discrom.answer_params)
    parameter [32*SLOTS-1:0] SLOT_IDS = 0,
    parameter [8*SLOTS-1:0] SLOT_MSGS = 0,
    parameter [8*SLOTS-1:0] SLOT_LASTS = 0,
    parameter ANSWER_FILE = "",
    parameter ANSWER_TABLE_FILE = "",
    parameter ANSWER_BYTES = 2048,
    parameter ANSWERS = 9,
    parameter DST_AT = 24,
    parameter BASE_AT = 48,
    parameter COUNT_START = 3,
    parameter BURST = 4096,
    parameter RATE = 4
