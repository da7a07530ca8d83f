// ap_int.h -- the part of Xilinx's arbitrary-precision integers that rosfpga_lab's generated
// HLS code uses, for C simulation with plain g++ (no Xilinx tools needed).
//
// How it works: an ap_uint<N> (1 <= N <= 64) keeps its value in a uint64_t masked to N bits,
// so assignment wraps modulo 2^N exactly as in hardware (assigning -1 sets every bit). It
// converts implicitly to unsigned long long, so ordinary C++ arithmetic and comparisons work;
// write the result back into an ap_uint to truncate it to N bits again. Bit ranges
// (x.range(hi, lo), x(hi, lo)) and single bits (x[i]) can be read and assigned.
//
// Not provided: ap_int (signed), widths above 64 bits, ap_fixed. The real header is used when
// synthesising with Vivado HLS; this one must never be on the include path there.
#ifndef ROSFPGA_LAB_AP_INT_H
#define ROSFPGA_LAB_AP_INT_H

#include <cstdint>
#include <type_traits>

namespace rosfpga_lab_ap {

// All-ones mask of n bits (n in 1..64), written so that no shift ever reaches 64.
constexpr uint64_t mask_of(int n) {
    return n >= 64 ? ~uint64_t(0) : ((uint64_t(1) << (n % 64)) - 1);
}

}  // namespace rosfpga_lab_ap

template <int N> class ap_uint;

// A reference to bits hi..lo of an ap_uint (an lvalue: assigning writes those bits only).
template <int N>
class ap_range_ref {
public:
    ap_range_ref(ap_uint<N>& ref, int hi, int lo) : ref_(ref), hi_(hi), lo_(lo) {}
    operator unsigned long long() const {
        return (ref_.to_uint64() >> lo_) & rosfpga_lab_ap::mask_of(hi_ - lo_ + 1);
    }
    ap_range_ref& operator=(unsigned long long value) {
        const uint64_t field = rosfpga_lab_ap::mask_of(hi_ - lo_ + 1);
        uint64_t v = ref_.to_uint64() & ~(field << lo_);
        v |= (uint64_t(value) & field) << lo_;
        ref_ = v;
        return *this;
    }
    ap_range_ref& operator=(const ap_range_ref& other) {
        return *this = static_cast<unsigned long long>(other);
    }
    unsigned long long to_uint64() const { return *this; }
    unsigned to_uint() const { return static_cast<unsigned>(to_uint64()); }
    int to_int() const { return static_cast<int>(to_uint64()); }

private:
    ap_uint<N>& ref_;
    int hi_;
    int lo_;
};

// A reference to one bit of an ap_uint.
template <int N>
class ap_bit_ref {
public:
    ap_bit_ref(ap_uint<N>& ref, int bit) : ref_(ref), bit_(bit) {}
    operator bool() const { return (ref_.to_uint64() >> bit_) & 1u; }
    ap_bit_ref& operator=(bool value) {
        uint64_t v = ref_.to_uint64() & ~(uint64_t(1) << bit_);
        ref_ = v | (uint64_t(value ? 1 : 0) << bit_);
        return *this;
    }
    ap_bit_ref& operator=(const ap_bit_ref& other) { return *this = static_cast<bool>(other); }

private:
    ap_uint<N>& ref_;
    int bit_;
};

// An unsigned integer of exactly N bits (1 <= N <= 64).
template <int N>
class ap_uint {
    static_assert(N >= 1 && N <= 64, "the lab's ap_uint supports 1 to 64 bits");

public:
    ap_uint() : v_(0) {}
    template <typename T, typename = typename std::enable_if<std::is_integral<T>::value>::type>
    ap_uint(T value) : v_(static_cast<uint64_t>(value) & rosfpga_lab_ap::mask_of(N)) {}
    template <int M>
    ap_uint(const ap_uint<M>& other) : v_(other.to_uint64() & rosfpga_lab_ap::mask_of(N)) {}
    template <int M>
    ap_uint(const ap_range_ref<M>& r) : v_(r.to_uint64() & rosfpga_lab_ap::mask_of(N)) {}

    operator unsigned long long() const { return v_; }

    unsigned long long to_uint64() const { return v_; }
    unsigned to_uint() const { return static_cast<unsigned>(v_); }
    int to_int() const { return static_cast<int>(v_); }
    long long to_int64() const { return static_cast<long long>(v_); }
    bool to_bool() const { return v_ != 0; }
    static constexpr int length() { return N; }

    ap_range_ref<N> range(int hi, int lo) { return ap_range_ref<N>(*this, hi, lo); }
    unsigned long long range(int hi, int lo) const {
        return (v_ >> lo) & rosfpga_lab_ap::mask_of(hi - lo + 1);
    }
    ap_range_ref<N> operator()(int hi, int lo) { return range(hi, lo); }
    unsigned long long operator()(int hi, int lo) const { return range(hi, lo); }
    ap_bit_ref<N> operator[](int bit) { return ap_bit_ref<N>(*this, bit); }
    bool operator[](int bit) const { return (v_ >> bit) & 1u; }

    ap_uint& operator+=(unsigned long long x) { return *this = v_ + x; }
    ap_uint& operator-=(unsigned long long x) { return *this = v_ - x; }
    ap_uint& operator|=(unsigned long long x) { return *this = v_ | x; }
    ap_uint& operator&=(unsigned long long x) { return *this = v_ & x; }
    ap_uint& operator^=(unsigned long long x) { return *this = v_ ^ x; }
    ap_uint& operator<<=(int s) { return *this = (s >= 64 ? 0 : v_ << s); }
    ap_uint& operator>>=(int s) { return *this = (s >= 64 ? 0 : v_ >> s); }
    ap_uint& operator++() { return *this = v_ + 1; }
    ap_uint& operator--() { return *this = v_ - 1; }
    ap_uint operator++(int) { ap_uint old = *this; ++*this; return old; }
    ap_uint operator--(int) { ap_uint old = *this; --*this; return old; }

private:
    uint64_t v_;
};

#endif  // ROSFPGA_LAB_AP_INT_H
