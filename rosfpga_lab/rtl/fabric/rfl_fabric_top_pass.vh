// rfl_fabric_top_pass.vh -- rfl_fabric_top_params.vh's parameters passed on as they are:
// included in an instance's #( ... ) list, last.
        .SPDP_PORT(SPDP_PORT), .META_PORT(META_PORT), .USER_PORT(USER_PORT),
        .SPDP_GROUP(SPDP_GROUP), .COUNTERS_PORT(COUNTERS_PORT), .COUNTERS_GAP(COUNTERS_GAP),
        .SPDP_WRITER_ID(SPDP_WRITER_ID), .SPDP_PIDS(SPDP_PIDS),
        .SPDP_ENCAPS(SPDP_ENCAPS), .SPDP_LOCATOR_KIND(SPDP_LOCATOR_KIND),
        .SPDP_LEASE_DEFAULT(SPDP_LEASE_DEFAULT), .SPDP_LEASE_MAX(SPDP_LEASE_MAX),
        .RX_BITS(RX_BITS), .TX_BITS(TX_BITS), .QUEUE_BITS(QUEUE_BITS),
`include "rfl_fabric_node_pass.vh"
