// rfl_fabric_top_params.vh -- rfl_fabric_top's parameters (its own, then rfl_fabric_node's), the
// one list rfl_board_5a75b (and the board's proof model of the top) declares too: included in a
// module's #( ... ) list, last; rfl_fabric_top_pass.vh passes them on.
    parameter SPDP_PORT = 0,                    // all four: rtl.discrom.top_parameters
    parameter META_PORT = 0,
    parameter USER_PORT = 0,
    parameter [31:0] SPDP_GROUP = 32'd0,
    parameter COUNTERS_PORT = 0,                // the counter readout's: rtl.discrom too
    parameter COUNTERS_GAP = 0,                 // its clocks between answers (fabriccounters)
    // rfl_spdp_peer's constants, all from rtl.discrom.spdp_parameters (the software's builders)
    parameter [31:0] SPDP_WRITER_ID = 32'd0,
    parameter [79:0] SPDP_PIDS = 80'd0,         // {status, sentinel, lease, default, meta}
    parameter [31:0] SPDP_ENCAPS = 32'd0,       // {PL_CDR_BE, PL_CDR_LE}
    parameter [31:0] SPDP_LOCATOR_KIND = 32'd0,
    parameter SPDP_LEASE_DEFAULT = 100,         // seconds
    parameter SPDP_LEASE_MAX = 300,
    parameter RX_BITS = 11,                     // rfl_udp_port's buffers and queues
    parameter TX_BITS = 11,
    parameter QUEUE_BITS = 2,
`include "rfl_fabric_node_params.vh"
