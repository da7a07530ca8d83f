// hls_stream.h -- hls::stream<T> as Xilinx's C simulation models it, for g++.
//
// How it works: in C simulation a stream is an unbounded first-in first-out queue (the depth
// given by "#pragma HLS STREAM depth=..." matters only in hardware). Reading an empty stream
// prints Xilinx's warning and returns a default-constructed value (in hardware the reader
// would stall for ever); a stream destroyed while still holding data prints a warning too,
// since that usually means a producer and a consumer disagree about how much to transfer.
#ifndef ROSFPGA_LAB_HLS_STREAM_H
#define ROSFPGA_LAB_HLS_STREAM_H

#include <cstddef>
#include <deque>
#include <iostream>
#include <string>

namespace hls {

template <typename T>
class stream {
public:
    stream() : name_("hls::stream") {}
    explicit stream(const char* name) : name_(name) {}
    stream(const stream&) = delete;
    stream& operator=(const stream&) = delete;
    ~stream() {
        if (!queue_.empty()) {
            std::cerr << "WARNING: Hls::stream '" << name_ << "' contains leftover data ("
                      << queue_.size() << " elements)\n";
        }
    }

    bool empty() const { return queue_.empty(); }
    bool full() const { return false; }
    std::size_t size() const { return queue_.size(); }

    void write(const T& value) { queue_.push_back(value); }
    void operator<<(const T& value) { write(value); }
    bool write_nb(const T& value) { write(value); return true; }

    T read() {
        if (queue_.empty()) {
            std::cerr << "WARNING: Hls::stream '" << name_
                      << "' is read while empty, which may result in RTL simulation hanging.\n";
            return T();
        }
        T value = queue_.front();
        queue_.pop_front();
        return value;
    }
    void read(T& value) { value = read(); }
    void operator>>(T& value) { value = read(); }
    bool read_nb(T& value) {
        if (queue_.empty()) return false;
        value = read();
        return true;
    }

private:
    std::string name_;
    std::deque<T> queue_;
};

}  // namespace hls

#endif  // ROSFPGA_LAB_HLS_STREAM_H
