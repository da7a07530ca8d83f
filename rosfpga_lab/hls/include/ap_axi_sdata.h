// ap_axi_sdata.h -- the AXI4-Stream side-channel struct of Xilinx's HLS libraries, for C
// simulation with g++. One ap_axiu<D, U, TI, TD> is one beat (one transfer) of an AXI4-Stream:
// TDATA (D bits), TKEEP and TSTRB (one bit per byte of TDATA), TUSER (U bits; video streams
// use bit 0 for "first pixel of the frame"), TLAST (end of a line in a video stream), TID and
// TDEST. Same member names and widths as Xilinx's header.
#ifndef ROSFPGA_LAB_AP_AXI_SDATA_H
#define ROSFPGA_LAB_AP_AXI_SDATA_H

#include "ap_int.h"

template <int D, int U, int TI, int TD>
struct ap_axiu {
    ap_uint<D> data;
    ap_uint<(D + 7) / 8> keep;
    ap_uint<(D + 7) / 8> strb;
    ap_uint<U> user;
    ap_uint<1> last;
    ap_uint<TI> id;
    ap_uint<TD> dest;
};

#endif  // ROSFPGA_LAB_AP_AXI_SDATA_H
