// rfl_status.vh -- the subscriber's status codes (0: accepted, else the refused field).
// Generated from rosfpga_lab.rtl.exhibit.params.SUBSCRIBER_STATUSES by
// rosfpga_lab.rtl.exhibit.params.status_header(); a test keeps this file equal
// to it.
localparam [3:0] SUB_OK = 4'd0;  // frame accepted
localparam [3:0] SUB_BAD_FRAME_LENGTH = 4'd1;  // frame length
localparam [3:0] SUB_BAD_FRAME_ID_LENGTH = 4'd2;  // header.frame_id length
localparam [3:0] SUB_BAD_HEIGHT = 4'd3;  // height
localparam [3:0] SUB_BAD_WIDTH = 4'd4;  // width
localparam [3:0] SUB_BAD_ENCODING_LENGTH = 4'd5;  // encoding length
localparam [3:0] SUB_BAD_ENCODING = 4'd6;  // encoding
localparam [3:0] SUB_BAD_STEP = 4'd7;  // step
localparam [3:0] SUB_BAD_DATA_LENGTH = 4'd8;  // data length
