// hls_video.h -- the pieces of Xilinx's HLS video library (Vivado HLS <= 2019.2) that
// rosfpga_lab's generated image_filter uses, for C simulation with g++: hls::Mat,
// hls::Scalar, hls::Window, AXIvideo2Mat, Mat2AXIvideo, hls::Dilate and hls::Erode.
//
// How it works:
// * hls::Mat<ROWS, COLS, T> is, as in Xilinx's library, not a frame buffer but one
//   hls::stream per channel: pixels are written once and read once, in raster order.
// * AXIvideo2Mat waits for a beat with TUSER set (start of frame), then reads `cols` beats per
//   line; a line that ends early (TLAST before the last column) or late (no TLAST on the
//   last column: the extra beats are skipped) sets the returned error bits. Channel k of a
//   pixel is TDATA bits [8k+7 : 8k].
// * Mat2AXIvideo writes one beat per pixel: TUSER on the first pixel of the frame, TLAST on
//   the last pixel of every line, TKEEP all ones and, like Xilinx's, TDATA bits not covered
//   by a channel set to 1 (it assigns -1 before filling the channels).
// * Dilate/Erode replace each pixel, channel by channel, by the maximum/minimum over the
//   kernel window; pixels outside the image are replicated from the border
//   (BORDER_REPLICATE), which for these operators equals taking the maximum/minimum over the
//   part of the window inside the image. The C-simulation model buffers the whole frame;
//   the hardware uses line buffers, with the same result.
//
// Only 8-bit unsigned channel types (HLS_8UC1 .. HLS_8UC4) are provided.
#ifndef ROSFPGA_LAB_HLS_VIDEO_H
#define ROSFPGA_LAB_HLS_VIDEO_H

#include <cassert>
#include <vector>

#include "ap_axi_sdata.h"
#include "ap_int.h"
#include "hls_stream.h"

#define HLS_8U 0
#define HLS_CN_SHIFT 11
#define HLS_MAT_CN_MASK (((1 << 9) - 1) << HLS_CN_SHIFT)
#define HLS_MAKETYPE(depth, cn) ((depth) + (((cn) - 1) << HLS_CN_SHIFT))
#define HLS_8UC1 HLS_MAKETYPE(HLS_8U, 1)
#define HLS_8UC2 HLS_MAKETYPE(HLS_8U, 2)
#define HLS_8UC3 HLS_MAKETYPE(HLS_8U, 3)
#define HLS_8UC4 HLS_MAKETYPE(HLS_8U, 4)
#define HLS_MAT_CN(flags) ((((flags) & HLS_MAT_CN_MASK) >> HLS_CN_SHIFT) + 1)
#define HLS_TBITDEPTH(flags) 8
#define HLS_TNAME(flags) unsigned char

namespace hls {

typedef int HLS_SIZE_T;
typedef int HLS_CHANNEL_T;

enum { MORPH_RECT = 0, MORPH_CROSS = 1, MORPH_ELLIPSE = 2 };
enum { ERROR_IO_EOL_EARLY = 1 << 0, ERROR_IO_EOL_LATE = 1 << 1, ERROR_IO_SOF_EARLY = 1 << 2 };

// One pixel: N channel values.
template <int N, typename T>
class Scalar {
public:
    Scalar() {
        for (int k = 0; k < N; k++) val[k] = T();
    }
    T val[N];
};

// A small 2-D array, used here as a morphology kernel (non-zero entries are in the shape).
template <int ROWS, int COLS, typename T>
class Window {
public:
    Window() {
        for (int r = 0; r < ROWS; r++)
            for (int c = 0; c < COLS; c++) val[r][c] = T();
    }
    T& operator()(int row, int col) { return val[row][col]; }
    T getval(int row, int col) const { return val[row][col]; }
    T val[ROWS][COLS];
};

// An image as a stream of pixels (one hls::stream per channel), raster order.
template <int ROWS, int COLS, int T>
class Mat {
    static_assert(HLS_MAT_CN(T) >= 1 && HLS_MAT_CN(T) <= 4, "the lab supports 1 to 4 channels");

public:
    Mat() : rows(ROWS), cols(COLS) {}
    Mat(int rows_, int cols_) : rows(rows_), cols(cols_) {
        assert(rows_ > 0 && rows_ <= ROWS && cols_ > 0 && cols_ <= COLS);
    }
    void init(int rows_, int cols_) { rows = rows_; cols = cols_; }

    Scalar<HLS_MAT_CN(T), HLS_TNAME(T)> read() {
        Scalar<HLS_MAT_CN(T), HLS_TNAME(T)> pix;
        for (int k = 0; k < HLS_MAT_CN(T); k++) pix.val[k] = data_stream[k].read();
        return pix;
    }
    void write(const Scalar<HLS_MAT_CN(T), HLS_TNAME(T)>& pix) {
        for (int k = 0; k < HLS_MAT_CN(T); k++) data_stream[k].write(pix.val[k]);
    }
    void operator>>(Scalar<HLS_MAT_CN(T), HLS_TNAME(T)>& pix) { pix = read(); }
    void operator<<(const Scalar<HLS_MAT_CN(T), HLS_TNAME(T)>& pix) { write(pix); }

    HLS_SIZE_T rows;
    HLS_SIZE_T cols;
    stream<HLS_TNAME(T)> data_stream[HLS_MAT_CN(T)];
};

// AXI4-Stream video (one pixel per beat) -> Mat. Returns 0, or ERROR_IO_* bits.
template <int W, int ROWS, int COLS, int T>
int AXIvideo2Mat(stream<ap_axiu<W, 1, 1, 1> >& AXI_video_strm, Mat<ROWS, COLS, T>& img) {
    static_assert(W >= 8 * HLS_MAT_CN(T), "TDATA narrower than a pixel");
    int res = 0;
    ap_axiu<W, 1, 1, 1> axi;
    bool sof = false;
    while (!sof) {  // skip beats until the start of a frame
        AXI_video_strm >> axi;
        sof = axi.user.to_int() != 0;
    }
    for (HLS_SIZE_T i = 0; i < img.rows; i++) {
        bool eol = false;
        for (HLS_SIZE_T j = 0; j < img.cols; j++) {
            if (sof || eol) {
                // The beat that started the frame, or a line that ended early: reuse it.
                sof = false;
                eol = axi.last.to_int() != 0;
            } else {
                AXI_video_strm >> axi;
                eol = axi.last.to_int() != 0;
                if (axi.user.to_int() != 0) res |= ERROR_IO_SOF_EARLY;
            }
            if (eol && j != img.cols - 1) res |= ERROR_IO_EOL_EARLY;
            Scalar<HLS_MAT_CN(T), HLS_TNAME(T)> pix;
            for (HLS_CHANNEL_T k = 0; k < HLS_MAT_CN(T); k++) {
                pix.val[k] = static_cast<HLS_TNAME(T)>(axi.data.range(8 * k + 7, 8 * k));
            }
            img << pix;
        }
        while (!eol) {  // skip the rest of a line that is too long
            AXI_video_strm >> axi;
            eol = axi.last.to_int() != 0;
            res |= ERROR_IO_EOL_LATE;
        }
    }
    return res;
}

// Mat -> AXI4-Stream video (one pixel per beat). Returns 0.
template <int W, int ROWS, int COLS, int T>
int Mat2AXIvideo(Mat<ROWS, COLS, T>& img, stream<ap_axiu<W, 1, 1, 1> >& AXI_video_strm) {
    static_assert(W >= 8 * HLS_MAT_CN(T), "TDATA narrower than a pixel");
    bool sof = true;
    for (HLS_SIZE_T i = 0; i < img.rows; i++) {
        for (HLS_SIZE_T j = 0; j < img.cols; j++) {
            ap_axiu<W, 1, 1, 1> axi;
            axi.user = sof ? 1 : 0;
            sof = false;
            axi.last = (j == img.cols - 1) ? 1 : 0;
            Scalar<HLS_MAT_CN(T), HLS_TNAME(T)> pix;
            img >> pix;
            axi.data = -1;  // bits above the last channel stay 1, as in Xilinx's library
            for (HLS_CHANNEL_T k = 0; k < HLS_MAT_CN(T); k++) {
                axi.data.range(8 * k + 7, 8 * k) = pix.val[k];
            }
            axi.keep = -1;
            axi.strb = -1;
            AXI_video_strm << axi;
        }
    }
    return 0;
}

namespace detail {

// Max (dilate) or min (erode) over the kernel's non-zero entries, border replicated.
template <bool IS_DILATE, int K_HEIGHT, int K_WIDTH, typename KN_T, int ROWS, int COLS,
          int SRC_T, int DST_T>
void morphology(Mat<ROWS, COLS, SRC_T>& src, Mat<ROWS, COLS, DST_T>& dst,
                const Window<K_HEIGHT, K_WIDTH, KN_T>& kernel, int iterations) {
    static_assert(HLS_MAT_CN(SRC_T) == HLS_MAT_CN(DST_T), "source and destination channels differ");
    const int cn = HLS_MAT_CN(SRC_T);
    const int rows = src.rows, cols = src.cols;
    std::vector<unsigned char> img(static_cast<std::size_t>(rows) * cols * cn);
    for (std::size_t p = 0; p < img.size(); p += cn) {
        Scalar<HLS_MAT_CN(SRC_T), HLS_TNAME(SRC_T)> pix;
        src >> pix;
        for (int k = 0; k < cn; k++) img[p + k] = pix.val[k];
    }
    std::vector<unsigned char> out(img.size());
    for (int it = 0; it < iterations; it++) {
        for (int y = 0; y < rows; y++) {
            for (int x = 0; x < cols; x++) {
                for (int k = 0; k < cn; k++) {
                    int best = IS_DILATE ? 0 : 255;
                    for (int ky = 0; ky < K_HEIGHT; ky++) {
                        for (int kx = 0; kx < K_WIDTH; kx++) {
                            if (!kernel.getval(ky, kx)) continue;
                            int yy = y + ky - K_HEIGHT / 2, xx = x + kx - K_WIDTH / 2;
                            yy = yy < 0 ? 0 : (yy >= rows ? rows - 1 : yy);  // replicate
                            xx = xx < 0 ? 0 : (xx >= cols ? cols - 1 : xx);
                            int v = img[(static_cast<std::size_t>(yy) * cols + xx) * cn + k];
                            best = IS_DILATE ? (v > best ? v : best) : (v < best ? v : best);
                        }
                    }
                    out[(static_cast<std::size_t>(y) * cols + x) * cn + k] =
                        static_cast<unsigned char>(best);
                }
            }
        }
        img.swap(out);
    }
    dst.rows = rows;
    dst.cols = cols;
    for (std::size_t p = 0; p < img.size(); p += cn) {
        Scalar<HLS_MAT_CN(DST_T), HLS_TNAME(DST_T)> pix;
        for (int k = 0; k < cn; k++) pix.val[k] = img[p + k];
        dst << pix;
    }
}

template <typename KN_T>
Window<3, 3, KN_T> rect3x3() {
    Window<3, 3, KN_T> kernel;
    for (int r = 0; r < 3; r++)
        for (int c = 0; c < 3; c++) kernel.val[r][c] = 1;
    return kernel;
}

}  // namespace detail

// Dilate with the default 3x3 rectangle.
template <int SRC_T, int DST_T, int IMG_HEIGHT, int IMG_WIDTH>
void Dilate(Mat<IMG_HEIGHT, IMG_WIDTH, SRC_T>& _src, Mat<IMG_HEIGHT, IMG_WIDTH, DST_T>& _dst) {
    detail::morphology<true>(_src, _dst, detail::rect3x3<unsigned char>(), 1);
}

// Dilate with a kernel (anchor at its centre), applied ITERATIONS times.
template <int Shape_type, int ITERATIONS, int SRC_T, int DST_T, typename KN_T, int IMG_HEIGHT,
          int IMG_WIDTH, int K_HEIGHT, int K_WIDTH>
void Dilate(Mat<IMG_HEIGHT, IMG_WIDTH, SRC_T>& _src, Mat<IMG_HEIGHT, IMG_WIDTH, DST_T>& _dst,
            Window<K_HEIGHT, K_WIDTH, KN_T>& _kernel) {
    detail::morphology<true>(_src, _dst, _kernel, ITERATIONS);
}

// Erode with the default 3x3 rectangle.
template <int SRC_T, int DST_T, int IMG_HEIGHT, int IMG_WIDTH>
void Erode(Mat<IMG_HEIGHT, IMG_WIDTH, SRC_T>& _src, Mat<IMG_HEIGHT, IMG_WIDTH, DST_T>& _dst) {
    detail::morphology<false>(_src, _dst, detail::rect3x3<unsigned char>(), 1);
}

// Erode with a kernel (anchor at its centre), applied ITERATIONS times.
template <int Shape_type, int ITERATIONS, int SRC_T, int DST_T, typename KN_T, int IMG_HEIGHT,
          int IMG_WIDTH, int K_HEIGHT, int K_WIDTH>
void Erode(Mat<IMG_HEIGHT, IMG_WIDTH, SRC_T>& _src, Mat<IMG_HEIGHT, IMG_WIDTH, DST_T>& _dst,
           Window<K_HEIGHT, K_WIDTH, KN_T>& _kernel) {
    detail::morphology<false>(_src, _dst, _kernel, ITERATIONS);
}

}  // namespace hls

#endif  // ROSFPGA_LAB_HLS_VIDEO_H
