// dsreg — a caller's array of voxel values (include/dsreg/voxel_array.hpp).
#include "dsreg/voxel_array.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include "dsreg/error.hpp"
#include "volume_io_internal.hpp"

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

/// Calls visit(address of the value, linear index) for every voxel, tile by tile (tiles in
/// parallel), within a tile in the array's memory order (its axes by increasing |stride|). When x
/// is the fastest axis in memory (Fortran order, dsreg's own), a tile is a whole row: values and
/// mask are both read and written in order. Otherwise (a C-ordered numpy array, say) a row along
/// x would touch a new cache line at every voxel; small tiles keep the lines of both the values
/// and the mask in cache instead. Tiles of 12 voxels along the fastest axis and 128 × 64 (x
/// first) along the others, measured on a 512 × 512 × 300 C-ordered uint8 array (one thread):
/// 0.22 s instead of 0.80 s row by row (0.084 s in Fortran order); 16 or 32 along the fastest
/// axis are slower (0.30, 0.41 s: their writes, a whole x-y plane apart, share cache sets).
/// With `parallel` false the tiles are visited one after the other, on the calling thread, outside
/// any OpenMP region (for a visitor that is not thread-safe or may throw, such as the label table
/// of a label map).
template <typename Visit>
void for_each_voxel(const VoxelArray& a, Visit&& visit, bool parallel = true) {
    const std::array<std::int64_t, 3> linear_step{1, a.dims[0], a.dims[0] * a.dims[1]};
    std::array<int, 3> axes{0, 1, 2};  // fastest in memory first
    std::stable_sort(axes.begin(), axes.end(),
                     [&](int p, int q) { return std::abs(a.byte_strides[p]) < std::abs(a.byte_strides[q]); });
    std::array<std::int64_t, 3> tile_size{128, 64, 64};
    if (axes[0] == 0)
        tile_size = {a.dims[0], 1, 1};
    else
        tile_size[axes[0]] = 12;
    std::array<std::int64_t, 3> tiles{};
    for (int d = 0; d < 3; ++d) tiles[d] = (a.dims[d] + tile_size[d] - 1) / tile_size[d];
    const std::int64_t tile_count = tiles[0] * tiles[1] * tiles[2];
    const auto visit_tile = [&](std::int64_t t) {
        const std::array<std::int64_t, 3> tile{t % tiles[0], (t / tiles[0]) % tiles[1], t / (tiles[0] * tiles[1])};
        std::array<std::int64_t, 3> low{}, high{};
        for (int d = 0; d < 3; ++d) {
            low[d] = tile[d] * tile_size[d];
            high[d] = std::min(a.dims[d], low[d] + tile_size[d]);
        }
        const int inner = axes[0], middle = axes[1], outer = axes[2];
        std::array<std::int64_t, 3> x = low;
        for (x[outer] = low[outer]; x[outer] < high[outer]; ++x[outer])
            for (x[middle] = low[middle]; x[middle] < high[middle]; ++x[middle]) {
                x[inner] = low[inner];
                const std::uint8_t* in = a.data + x[0] * a.byte_strides[0] + x[1] * a.byte_strides[1] + x[2] * a.byte_strides[2];
                std::int64_t out = x[0] * linear_step[0] + x[1] * linear_step[1] + x[2] * linear_step[2];
                for (std::int64_t n = low[inner]; n < high[inner]; ++n) {
                    visit(in, out);
                    in += a.byte_strides[inner];
                    out += linear_step[inner];
                }
            }
    };
    if (!parallel) {
        for (std::int64_t t = 0; t < tile_count; ++t) visit_tile(t);
        return;
    }
#pragma omp parallel for schedule(static)
    for (std::int64_t t = 0; t < tile_count; ++t) visit_tile(t);
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
    std::vector<std::uint8_t> mask(static_cast<std::size_t>(a.dims[0] * a.dims[1] * a.dims[2]));
    std::uint8_t* out = mask.data();
    with_decoder(a, [&](auto decode) {
        for_each_voxel(a, [&](const std::uint8_t* value, std::int64_t index) {
            out[index] = range.contains(decode(value)) ? 1 : 0;
        });
    });
    return mask;
}

LabelVolume label_voxel_array(const VoxelArray& a, std::int64_t max_labels) {
    check_voxel_array(a);
    // The file readers' label decoding (values → compact indices, the checks and their messages),
    // fed from the array instead of a file's payload.
    auto destination = volume_io_detail::VoxelDestination::labels(max_labels);
    destination.allocate(a.description, a.dims);
    with_decoder(a, [&](auto decode) {
        for_each_voxel(
            a, [&](const std::uint8_t* value, std::int64_t index) { destination.set(std::uint64_t(index), decode(value)); },
            false);
    });
    return destination.take_labels();
}

std::optional<std::pair<double, double>> voxel_array_value_range(const VoxelArray& a) {
    check_voxel_array(a);
    const std::int64_t voxels = a.dims[0] * a.dims[1] * a.dims[2];
    double low = std::numeric_limits<double>::infinity(), high = -low;
    with_decoder(a, [&](auto decode) {
#pragma omp parallel for schedule(static) reduction(min : low) reduction(max : high)
        for (std::int64_t v = 0; v < voxels; ++v) {
            const std::int64_t i = v % a.dims[0], j = (v / a.dims[0]) % a.dims[1], k = v / (a.dims[0] * a.dims[1]);
            const double value = decode(a.data + i * a.byte_strides[0] + j * a.byte_strides[1] + k * a.byte_strides[2]);
            if (value < low) low = value;  // NaN compares false both ways: left out
            if (value > high) high = value;
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
