// dsreg — a caller's array of voxel values (include/dsreg/voxel_array.hpp).
#include "dsreg/voxel_array.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include "dsreg/error.hpp"

namespace dsreg {

namespace {

bool host_is_big_endian() {
    const std::uint16_t one = 1;
    std::uint8_t first = 0;
    std::memcpy(&first, &one, 1);
    return first == 0;
}

/// The value of type T stored at p (any alignment), its bytes reversed first when Swap.
template <typename T, bool Swap>
struct Decoder {
    double operator()(const std::uint8_t* p) const {
        std::uint8_t bytes[sizeof(T)];
        std::memcpy(bytes, p, sizeof(T));
        if (Swap) std::reverse(bytes, bytes + sizeof(T));
        T value;
        std::memcpy(&value, bytes, sizeof(T));
        return static_cast<double>(value);
    }
};

/// IEEE 754 binary16 (numpy's float16): sign, 5 exponent bits (bias 15), 10 fraction bits.
/// Every half value is exactly a double.
template <bool Swap>
struct HalfDecoder {
    double operator()(const std::uint8_t* p) const {
        const std::uint16_t bits = static_cast<std::uint16_t>(Decoder<std::uint16_t, Swap>()(p));
        const int exponent = (bits >> 10) & 0x1f;
        const int fraction = bits & 0x3ff;
        double magnitude;
        if (exponent == 0)
            magnitude = std::ldexp(double(fraction), -24);  // zero and subnormals
        else if (exponent == 31)
            magnitude = fraction == 0 ? std::numeric_limits<double>::infinity() : std::numeric_limits<double>::quiet_NaN();
        else
            magnitude = std::ldexp(double(fraction + 1024), exponent - 25);
        return (bits & 0x8000) ? -magnitude : magnitude;
    }
};

template <typename T, typename Job>
void with_type(bool swap, Job&& job) {
    if (swap) job(Decoder<T, true>());
    else job(Decoder<T, false>());
}

/// Calls job(decoder) with the decoder of the array's value type and byte order.
template <typename Job>
void with_decoder(const VoxelArray& a, Job&& job) {
    const bool swap = a.bytes > 1 && a.big_endian != host_is_big_endian();
    switch (a.kind) {
        case ValueKind::Unsigned:
            if (a.bytes == 1) return with_type<std::uint8_t>(swap, job);
            if (a.bytes == 2) return with_type<std::uint16_t>(swap, job);
            if (a.bytes == 4) return with_type<std::uint32_t>(swap, job);
            return with_type<std::uint64_t>(swap, job);
        case ValueKind::Signed:
            if (a.bytes == 1) return with_type<std::int8_t>(swap, job);
            if (a.bytes == 2) return with_type<std::int16_t>(swap, job);
            if (a.bytes == 4) return with_type<std::int32_t>(swap, job);
            return with_type<std::int64_t>(swap, job);
        case ValueKind::Float:
            if (a.bytes == 2) {
                if (swap) return job(HalfDecoder<true>());
                return job(HalfDecoder<false>());
            }
            if (a.bytes == 4) return with_type<float>(swap, job);
            return with_type<double>(swap, job);
    }
}

/// First byte of row (j, k) = row index j + ny·k.
const std::uint8_t* row_start(const VoxelArray& a, std::int64_t row) {
    const std::int64_t j = row % a.dims[1], k = row / a.dims[1];
    return a.data + j * a.byte_strides[1] + k * a.byte_strides[2];
}

}  // namespace

void check_voxel_array(const VoxelArray& a) {
    if (a.dims[0] <= 0 || a.dims[1] <= 0 || a.dims[2] <= 0)
        throw Error(a.description + ": every dimension must be positive (got " + std::to_string(a.dims[0]) + "x" +
                    std::to_string(a.dims[1]) + "x" + std::to_string(a.dims[2]) + ")");
    if (a.data == nullptr) throw Error(a.description + ": no data");
    const bool integer_size = a.bytes == 1 || a.bytes == 2 || a.bytes == 4 || a.bytes == 8;
    const bool float_size = a.bytes == 2 || a.bytes == 4 || a.bytes == 8;
    if (a.kind == ValueKind::Float ? !float_size : !integer_size)
        throw Error(a.description + ": unsupported value type (" + std::to_string(a.bytes) + "-byte " +
                    (a.kind == ValueKind::Float ? "floats" : "integers") + ")");
}

std::vector<std::uint8_t> threshold_voxel_array(const VoxelArray& a, const ValueRange& range) {
    check_voxel_array(a);
    const std::int64_t nx = a.dims[0], rows = a.dims[1] * a.dims[2], stride = a.byte_strides[0];
    std::vector<std::uint8_t> mask(static_cast<std::size_t>(nx * rows));
    with_decoder(a, [&](auto decode) {
#pragma omp parallel for schedule(static)
        for (std::int64_t row = 0; row < rows; ++row) {
            const std::uint8_t* in = row_start(a, row);
            std::uint8_t* out = mask.data() + row * nx;
            for (std::int64_t i = 0; i < nx; ++i) out[i] = range.contains(decode(in + i * stride)) ? 1 : 0;
        }
    });
    return mask;
}

std::optional<std::pair<double, double>> voxel_array_value_range(const VoxelArray& a) {
    check_voxel_array(a);
    const std::int64_t nx = a.dims[0], rows = a.dims[1] * a.dims[2], stride = a.byte_strides[0];
    double low = std::numeric_limits<double>::infinity(), high = -low;
    with_decoder(a, [&](auto decode) {
#pragma omp parallel for schedule(static) reduction(min : low) reduction(max : high)
        for (std::int64_t row = 0; row < rows; ++row) {
            const std::uint8_t* in = row_start(a, row);
            for (std::int64_t i = 0; i < nx; ++i) {
                const double value = decode(in + i * stride);
                if (value < low) low = value;  // NaN compares false both ways: left out
                if (value > high) high = value;
            }
        }
    });
    if (low > high) return std::nullopt;
    return std::make_pair(low, high);
}

std::string value_type_name(const VoxelArray& a) {
    const char* kind = a.kind == ValueKind::Float ? "float" : a.kind == ValueKind::Signed ? "int" : "uint";
    return kind + std::to_string(8 * a.bytes);
}

}  // namespace dsreg
