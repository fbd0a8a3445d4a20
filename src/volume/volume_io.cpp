// dsreg — volume I/O: format dispatch and the machinery shared by every reader (file access,
// dimension checks, payload size checks, the decoder into a mask or into values). The formats themselves live in
// vol_format.cpp, pgm3d_format.cpp and raw_format.cpp; zlib streams in zlib_payload.cpp.
#include "dsreg/volume_io.hpp"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <limits>
#include <new>
#include <numeric>
#include <sstream>
#include <type_traits>
#include <utility>

#include "dsreg/atomic_file.hpp"
#include "dsreg/error.hpp"
#include "itk_bridge.hpp"
#include "volume_io_internal.hpp"

namespace dsreg {

namespace volume_io_detail {

namespace {

/// Integers print exactly, other values with enough digits to be recognised.
std::string format_value(double value) {
    if (value > -9e18 && value < 9e18 && value == std::trunc(value))  // the range first: the cast of NaN or 1e19 is undefined
        return std::to_string(static_cast<std::int64_t>(value));
    std::ostringstream text;
    text.precision(17);
    text << value;
    return text.str();
}

/// The numeric value of one encoded sample.
double decode_sample(const std::uint8_t* sample, const SampleFormat& format) {
    std::uint64_t bits = 0;
    for (int i = 0; i < format.bytes; ++i) {
        const int index = format.big_endian ? i : format.bytes - 1 - i;
        bits = (bits << 8) | sample[index];
    }
    switch (format.kind) {
    case SampleKind::Unsigned:
        return static_cast<double>(bits);
    case SampleKind::Signed: {
        if (format.bytes == 8) {
            std::int64_t value;
            std::memcpy(&value, &bits, sizeof value);
            return static_cast<double>(value);
        }
        // Sign-extend: flipping the sign bit then subtracting it maps [0, 2^n) onto [-2^(n-1), 2^(n-1)).
        const std::uint64_t sign_bit = std::uint64_t(1) << (8 * format.bytes - 1);
        return static_cast<double>(static_cast<std::int64_t>(bits ^ sign_bit) - static_cast<std::int64_t>(sign_bit));
    }
    case SampleKind::Float:
        if (format.bytes == 4) {
            const auto narrow = static_cast<std::uint32_t>(bits);
            float value;
            std::memcpy(&value, &narrow, sizeof value);
            return static_cast<double>(value);
        } else {
            double value;
            std::memcpy(&value, &bits, sizeof value);
            return value;
        }
    }
    return 0.0;
}

}  // namespace

void fail(const std::string& path, const std::string& problem) { throw Error(path + ": " + problem); }

std::string quote_excerpt(const std::string& text) {
    constexpr std::size_t max_length = 40;
    std::string shown;
    for (std::size_t i = 0; i < text.size() && i < max_length; ++i) {
        const auto c = static_cast<unsigned char>(text[i]);
        shown.push_back(c >= 0x20 && c < 0x7f ? static_cast<char>(c) : '?');
    }
    if (text.size() > max_length) shown += "...";
    return "'" + shown + "'";
}

std::string format_dims(const Index3& dims) {
    return std::to_string(dims[0]) + "x" + std::to_string(dims[1]) + "x" + std::to_string(dims[2]);
}

bool parse_positive_integer(const std::string& text, std::int64_t& value) {
    if (text.empty()) return false;
    std::int64_t result = 0;
    for (const char c : text) {
        if (c < '0' || c > '9') return false;
        const int digit = c - '0';
        if (result > (std::numeric_limits<std::int64_t>::max() - digit) / 10) return false;
        result = result * 10 + digit;
    }
    if (result == 0) return false;
    value = result;
    return true;
}

std::int64_t checked_voxel_count(const std::string& path, const Index3& dims, const VolumeLimits& limits) {
    if (dims[0] <= 0 || dims[1] <= 0 || dims[2] <= 0)
        fail(path, "dimensions " + format_dims(dims) + " must all be positive");
    const std::int64_t limit = limits.max_voxels;
    const std::string too_many = "dimensions " + format_dims(dims) + " exceed the limit of " + std::to_string(limit) + " voxels";
    // Divide before multiplying so that the product never overflows.
    if (dims[0] > limit || dims[1] > limit / dims[0]) fail(path, too_many);
    const std::int64_t slice = dims[0] * dims[1];
    if (dims[2] > limit / slice) fail(path, too_many);
    return slice * dims[2];
}

// ----------------------------------------------------------------------------------------------
// VoxelDestination

VoxelDestination VoxelDestination::mask(const ValueRange& range) { return VoxelDestination(Kind::Mask, range); }

VoxelDestination VoxelDestination::values() { return VoxelDestination(Kind::Values, ValueRange{}); }

VoxelDestination VoxelDestination::labels(std::int64_t max_labels) {
    return VoxelDestination(Kind::Labels, ValueRange{}, nullptr, max_labels);
}

VoxelDestination VoxelDestination::statistics(ValueHistogram& histogram) {
    return VoxelDestination(Kind::Statistics, ValueRange{}, &histogram);
}

void VoxelDestination::set_geometry(const VoxelGrid& geometry) {
    grid_.spacing = geometry.spacing;
    grid_.origin = geometry.origin;
    grid_.direction = geometry.direction;
}

VoxelDestination VoxelDestination::header_only() {
    VoxelDestination destination(Kind::Mask, ValueRange{});
    destination.header_only_ = true;
    return destination;
}

void VoxelDestination::restrict_to(const VoxelBox& box) {
    has_region_ = true;
    region_.box = box;
}

bool VoxelDestination::allocate(const std::string& path, const Index3& dims) {
    dims_ = dims;
    grid_ = VoxelGrid{};
    grid_.dims = dims;
    if (header_only_) return false;
    if (has_region_) {
        if (kind_ == Kind::Labels) fail(path, "label maps are read whole (no box reads of label maps yet)");
        region_.dims = dims;
        if (region_.box.empty() || !VoxelBox{{0, 0, 0}, dims}.contains(region_.box))
            fail(path, "the box of voxels " + format_dims(region_.box.lo) + " to " + format_dims(region_.box.hi) +
                           " (excluded) is not inside the " + format_dims(dims) + " grid");
        grid_.dims = region_.box.size();
    }
    const auto count = static_cast<std::size_t>(grid_.voxel_count());
    const int bytes_per_voxel = kind_ == Kind::Mask ? 1 : 4;
    try {
        if (kind_ == Kind::Values)
            values_.assign(count, 0.0f);
        else if (kind_ == Kind::Labels)
            labels_.assign(count, 0u);
        else if (kind_ == Kind::Mask)
            mask_.assign(count, 0);
    } catch (const std::bad_alloc&) {
        const char* what = kind_ == Kind::Values ? " volume of values (" : kind_ == Kind::Labels ? " label map (" : " mask (";
        fail(path, "not enough memory for a " + format_dims(grid_.dims) + what +
                       std::to_string(grid_.voxel_count() * bytes_per_voxel) + " bytes)");
    }
    if (kind_ == Kind::Labels && label_table_ == nullptr) label_table_ = std::make_shared<LabelTable>(path, max_labels_);
    return true;
}

void VoxelDestination::store_x_plane(std::int64_t i, const VoxelDestination& plane) {
    const std::int64_t nx = dims_[0], ny = dims_[1], nz = dims_[2];
    for (std::int64_t k = 0; k < nz; ++k)
        for (std::int64_t j = 0; j < ny; ++j) {
            const auto source = static_cast<std::size_t>(k + nz * j);
            std::int64_t target = i + nx * (j + ny * k);
            if (has_region_ && (target = region_.local_index(std::uint64_t(target))) < 0) continue;
            if (kind_ == Kind::Values)
                values_[std::size_t(target)] = plane.values_[source];
            else if (kind_ == Kind::Mask)
                mask_[std::size_t(target)] = plane.mask_[source];
            else if (kind_ == Kind::Labels)
                labels_[std::size_t(target)] = plane.labels_[source];
        }
}

SampleWriter VoxelDestination::writer(const std::string& path, SampleFormat format) {
    const StreamRegion* region = has_region_ ? &region_ : nullptr;
    switch (kind_) {
    case Kind::Values: return SampleWriter(path, format, values_, region);
    case Kind::Mask: return SampleWriter(path, format, range_, mask_, region);
    case Kind::Labels: return SampleWriter(path, format, labels_, *label_table_);
    case Kind::Statistics: break;
    }
    return SampleWriter(path, format, *histogram_, size());
}

BinaryVolume VoxelDestination::take_mask() {
    BinaryVolume volume;
    volume.grid = grid_;
    volume.mask = std::move(mask_);
    return volume;
}

ScalarVolume VoxelDestination::take_values() {
    ScalarVolume volume;
    volume.grid = grid_;
    volume.values = std::move(values_);
    return volume;
}

LabelVolume VoxelDestination::take_labels() {
    LabelVolume volume;
    volume.grid = grid_;
    volume.values = label_table_->finish(labels_);
    volume.labels = std::move(labels_);
    return volume;
}

// ----------------------------------------------------------------------------------------------
// LabelTable

LabelTable::LabelTable(const std::string& path, std::int64_t max_labels) : path_(path), max_labels_(max_labels) {
    values_.push_back(0);
    index_.emplace(0, 0u);
}

std::uint32_t LabelTable::look_up(double value, std::uint64_t voxel) {
    // Integers of magnitude below 2^53 are exact in a double; anything else is not a label.
    if (!(std::abs(value) < 9007199254740992.0) || value != std::floor(value))
        fail(path_, "value " + format_value(value) + " of voxel #" + std::to_string(voxel) +
                        " is not an integer: a label map holds integer labels");
    const auto key = static_cast<std::int64_t>(value);
    auto it = index_.find(key);
    if (it == index_.end()) {
        if (static_cast<std::int64_t>(values_.size()) > max_labels_)
            fail(path_, "more than " + std::to_string(max_labels_) + " distinct labels (voxel #" + std::to_string(voxel) +
                            " has one more): not a label map?");
        it = index_.emplace(key, static_cast<std::uint32_t>(values_.size())).first;
        values_.push_back(key);
    }
    last_value_ = value;
    last_index_ = it->second;
    return last_index_;
}

std::vector<std::int64_t> LabelTable::finish(std::vector<std::uint32_t>& labels) const {
    // Index order: the background, then the other values increasing.
    std::vector<std::uint32_t> order(values_.size());
    std::iota(order.begin(), order.end(), 0u);
    std::sort(order.begin() + 1, order.end(), [&](std::uint32_t a, std::uint32_t b) { return values_[a] < values_[b]; });
    std::vector<std::uint32_t> renumbered(values_.size());
    std::vector<std::int64_t> sorted(values_.size());
    for (std::size_t rank = 0; rank < order.size(); ++rank) {
        renumbered[order[rank]] = static_cast<std::uint32_t>(rank);
        sorted[rank] = values_[order[rank]];
    }
#pragma omp parallel for schedule(static)
    for (std::int64_t v = 0; v < static_cast<std::int64_t>(labels.size()); ++v)
        labels[std::size_t(v)] = renumbered[labels[std::size_t(v)]];
    return sorted;
}

// ----------------------------------------------------------------------------------------------
// InputFile

InputFile::InputFile(const std::string& path) : path_(path) {
    namespace fs = std::filesystem;
    const auto refuse = [&](const std::string& problem, int error_number) {
        throw FileError(path + ": " + problem, error_number);
    };
    std::error_code error;
    const fs::file_status status = fs::status(path, error);
    if (status.type() == fs::file_type::not_found) refuse("cannot open: no such file", ENOENT);
    if (error) refuse("cannot open: " + error.message(), error.value());
    if (status.type() == fs::file_type::directory) refuse("cannot open: is a directory, not a volume file", EISDIR);
    if (status.type() != fs::file_type::regular) refuse("cannot open: not a regular file", 0);
    size_ = fs::file_size(path, error);
    if (error) refuse("cannot determine the file size: " + error.message(), error.value());
    errno = 0;
    if (buffer_.open(path, std::ios::in | std::ios::binary) == nullptr)
        refuse(std::string("cannot open for reading: ") + (errno != 0 ? std::strerror(errno) : "unknown error"), errno);
}

int InputFile::get() {
    const auto c = buffer_.sbumpc();
    if (c == std::filebuf::traits_type::eof()) return -1;
    ++position_;
    return c;
}

int InputFile::peek() {
    const auto c = buffer_.sgetc();
    return c == std::filebuf::traits_type::eof() ? -1 : c;
}

std::size_t InputFile::read(std::uint8_t* destination, std::size_t count) {
    const std::streamsize got = buffer_.sgetn(reinterpret_cast<char*>(destination), static_cast<std::streamsize>(count));
    const std::size_t read_count = got > 0 ? static_cast<std::size_t>(got) : 0;
    position_ += read_count;
    return read_count;
}

void InputFile::seek(std::uint64_t offset) {
    if (offset > size_)
        fail("the file holds " + std::to_string(size_) + " bytes, too few to reach offset " + std::to_string(offset));
    const auto target = static_cast<std::streamoff>(offset);
    if (buffer_.pubseekpos(target, std::ios::in) != std::streampos(target)) fail("cannot seek to offset " + std::to_string(target));
    position_ = offset;
}

void InputFile::skip(std::uint64_t count) {
    if (count > remaining())
        fail("the file holds " + std::to_string(size_) + " bytes, too few to skip " + std::to_string(count) +
             " bytes from offset " + std::to_string(position_));
    const auto target = static_cast<std::streamoff>(position_ + count);
    if (buffer_.pubseekpos(target, std::ios::in) != std::streampos(target)) fail("cannot seek to offset " + std::to_string(target));
    position_ += count;
}

// ----------------------------------------------------------------------------------------------
// SampleWriter

std::int64_t StreamRegion::local_index(std::uint64_t index) const {
    const auto linear = static_cast<std::int64_t>(index);
    const std::int64_t i = linear % dims[0], j = (linear / dims[0]) % dims[1], k = linear / (dims[0] * dims[1]);
    if (!box.contains(i, j, k)) return -1;
    const Index3 size = box.size();
    return (i - box.lo[0]) + size[0] * ((j - box.lo[1]) + size[1] * (k - box.lo[2]));
}

SampleWriter::SampleWriter(const std::string& path, SampleFormat format, std::uint64_t size, const StreamRegion* region)
    : path_(path), format_(format), size_(size) {
    if (region != nullptr) {
        has_region_ = true;
        region_ = *region;
        size_ = static_cast<std::uint64_t>(region->dims[0] * region->dims[1] * region->dims[2]);
    }
    use_byte_table_ = format_.bytes == 1;
}

void SampleWriter::build_byte_tables() {
    if (!use_byte_table_) return;
    for (int byte = 0; byte < 256; ++byte) {
        const auto encoded = static_cast<std::uint8_t>(byte);
        byte_table_[byte] = decode_sample(&encoded, format_);
        if (rescaled_) byte_table_[byte] = slope_ * byte_table_[byte] + intercept_;
        mask_table_[byte] = range_.contains(byte_table_[byte]) ? 1 : 0;
    }
}

SampleWriter::SampleWriter(const std::string& path, SampleFormat format, const ValueRange& range, std::vector<std::uint8_t>& mask,
                           const StreamRegion* region)
    : SampleWriter(path, format, mask.size(), region) {
    range_ = range;
    mask_ = mask.data();
    build_byte_tables();
}

SampleWriter::SampleWriter(const std::string& path, SampleFormat format, std::vector<float>& values, const StreamRegion* region)
    : SampleWriter(path, format, values.size(), region) {
    values_ = values.data();
    build_byte_tables();
}

SampleWriter::SampleWriter(const std::string& path, SampleFormat format, ValueHistogram& histogram, std::uint64_t size)
    : SampleWriter(path, format, size) {
    histogram_ = &histogram;
    build_byte_tables();
}

void SampleWriter::rescale(double slope, double intercept) {
    rescaled_ = true;
    slope_ = slope;
    intercept_ = intercept;
    build_byte_tables();
}

void SampleWriter::skip_to(std::uint64_t index) {
    if (index < written_ || index > size_ || pending_size_ != 0) fail(path_, "internal error: payload read out of order");
    written_ = index;
}

SampleWriter::SampleWriter(const std::string& path, SampleFormat format, std::vector<std::uint32_t>& labels,
                           LabelTable& table)
    : SampleWriter(path, format, labels.size()) {
    labels_ = labels.data();
    label_table_ = &table;
    build_byte_tables();
}

void SampleWriter::reject_values_above(double max_value, const std::string& limit_name) {
    has_max_ = true;
    max_value_ = max_value;
    max_name_ = limit_name;
}

void SampleWriter::emit(const std::uint8_t* sample) {
    if (written_ >= size_) fail(path_, "payload holds more values than the " + std::to_string(size_) + " voxels announced");
    std::int64_t slot = static_cast<std::int64_t>(written_);
    if (has_region_ && (slot = region_.local_index(written_)) < 0) {
        ++written_;  // outside the box (values there are not checked)
        return;
    }
    if (use_byte_table_ && mask_ != nullptr && !has_max_) {  // the common case of .vol files: one lookup
        mask_[slot] = mask_table_[*sample];
        ++written_;
        return;
    }
    double value = use_byte_table_ ? byte_table_[*sample] : decode_sample(sample, format_);
    if (rescaled_ && !use_byte_table_) value = slope_ * value + intercept_;
    if (has_max_ && value > max_value_)
        fail(path_, "value " + format_value(value) + " of voxel #" + std::to_string(written_) + " exceeds " + max_name_ + " " +
                        format_value(max_value_));
    if (mask_ != nullptr)
        mask_[slot] = range_.contains(value) ? 1 : 0;
    else if (labels_ != nullptr)
        labels_[slot] = label_table_->index_of(value, written_);
    else if (values_ != nullptr)
        values_[slot] = static_cast<float>(value);
    else
        histogram_->add(value);
    ++written_;
}

void SampleWriter::consume(const std::uint8_t* data, std::size_t count) {
    const auto width = static_cast<std::size_t>(format_.bytes);
    // Complete a sample left over from the previous chunk.
    if (pending_size_ > 0) {
        const std::size_t taken = std::min(count, width - pending_size_);
        std::memcpy(pending_ + pending_size_, data, taken);
        pending_size_ += taken;
        data += taken;
        count -= taken;
        if (pending_size_ < width) return;
        emit(pending_);
        pending_size_ = 0;
    }
    const std::size_t whole = count / width;
    if (has_max_) {
        for (std::size_t n = 0; n < whole; ++n) emit(data + n * width);  // PGM: each value checked against maxval
    } else {
        if (whole > size_ - written_) fail(path_, "payload holds more values than the " + std::to_string(size_) + " voxels announced");
        decode_run(data, whole);
    }
    data += whole * width;
    count -= whole * width;
    // Keep the incomplete tail (fewer than `width` ≤ 8 bytes) for the next chunk.
    pending_size_ = std::min(count, sizeof pending_);
    if (pending_size_ > 0) std::memcpy(pending_, data, pending_size_);
}

namespace {

template <typename Unsigned>
Unsigned byte_swapped(Unsigned bits) {
    if constexpr (sizeof(Unsigned) == 2) return static_cast<Unsigned>(__builtin_bswap16(bits));
    if constexpr (sizeof(Unsigned) == 4) return static_cast<Unsigned>(__builtin_bswap32(bits));
    if constexpr (sizeof(Unsigned) == 8) return static_cast<Unsigned>(__builtin_bswap64(bits));
    return bits;
}

bool host_big_endian() {
    const std::uint16_t probe = 1;
    std::uint8_t first;
    std::memcpy(&first, &probe, 1);
    return first == 0;
}

/// `count` values of type T (stored with bytes swapped if `swap`), each handed as a double to
/// `store(index, value)`: the loop every decoder spends its time in.
template <typename T, typename Store>
void decode_values(const std::uint8_t* data, std::size_t count, bool swap, double slope, double intercept, bool rescaled,
                   Store&& store) {
    using Bits = std::conditional_t<sizeof(T) == 1, std::uint8_t,
                                    std::conditional_t<sizeof(T) == 2, std::uint16_t,
                                                       std::conditional_t<sizeof(T) == 4, std::uint32_t, std::uint64_t>>>;
    for (std::size_t i = 0; i < count; ++i) {
        Bits bits;
        std::memcpy(&bits, data + i * sizeof(T), sizeof(T));
        if (swap) bits = byte_swapped(bits);
        T value;
        std::memcpy(&value, &bits, sizeof(T));
        double decoded = static_cast<double>(value);
        if (rescaled) decoded = slope * decoded + intercept;
        store(i, decoded);
    }
}

}  // namespace

template <typename T>
void SampleWriter::decode_typed(const std::uint8_t* data, std::size_t count, std::uint64_t slot) {
    const bool swap = format_.big_endian != host_big_endian();
    if (mask_ != nullptr) {
        std::uint8_t* out = mask_ + slot;
        const ValueRange range = range_;
        decode_values<T>(data, count, swap, slope_, intercept_, rescaled_,
                         [&](std::size_t i, double v) { out[i] = range.contains(v) ? 1 : 0; });
    } else if (values_ != nullptr) {
        float* out = values_ + slot;
        decode_values<T>(data, count, swap, slope_, intercept_, rescaled_,
                         [&](std::size_t i, double v) { out[i] = static_cast<float>(v); });
    } else if (labels_ != nullptr) {
        std::uint32_t* out = labels_ + slot;
        const std::uint64_t first = slot;  // whole grids only: the slot is the voxel number
        decode_values<T>(data, count, swap, slope_, intercept_, rescaled_,
                         [&](std::size_t i, double v) { out[i] = label_table_->index_of(v, first + i); });
    } else {
        decode_values<T>(data, count, swap, slope_, intercept_, rescaled_, [&](std::size_t, double v) { histogram_->add(v); });
    }
}

void SampleWriter::decode_run(const std::uint8_t* data, std::size_t count) {
    if (!has_region_) {
        decode_span(data, count, written_);
        written_ += count;
        return;
    }
    // A box of the grid: the stream voxels of one x-row that lie in the box go to consecutive slots.
    const auto width = static_cast<std::size_t>(format_.bytes);
    const Index3& d = region_.dims;
    const VoxelBox& box = region_.box;
    while (count > 0) {
        const auto linear = static_cast<std::int64_t>(written_);
        const std::int64_t i = linear % d[0], j = (linear / d[0]) % d[1], k = linear / (d[0] * d[1]);
        const std::size_t row = std::min(count, static_cast<std::size_t>(d[0] - i));
        const std::int64_t lo = std::max(i, box.lo[0]), hi = std::min(i + std::int64_t(row), box.hi[0]);
        if (lo < hi && box.contains(lo, j, k))
            decode_span(data + std::size_t(lo - i) * width, std::size_t(hi - lo),
                        static_cast<std::uint64_t>(region_.local_index(std::uint64_t(linear + lo - i))));
        data += row * width;
        count -= row;
        written_ += row;
    }
}

void SampleWriter::decode_span(const std::uint8_t* data, std::size_t count, std::uint64_t slot) {
    if (use_byte_table_) {  // 1-byte values: one table look-up each (the table holds the rescaled values)
        if (mask_ != nullptr)
            for (std::size_t i = 0; i < count; ++i) mask_[slot + i] = mask_table_[data[i]];
        else if (values_ != nullptr)
            for (std::size_t i = 0; i < count; ++i) values_[slot + i] = static_cast<float>(byte_table_[data[i]]);
        else if (labels_ != nullptr)
            for (std::size_t i = 0; i < count; ++i) labels_[slot + i] = label_table_->index_of(byte_table_[data[i]], slot + i);
        else
            for (std::size_t i = 0; i < count; ++i) histogram_->add(byte_table_[data[i]]);
    } else {
        switch (format_.kind) {
        case SampleKind::Unsigned:
            if (format_.bytes == 2) decode_typed<std::uint16_t>(data, count, slot);
            else if (format_.bytes == 4) decode_typed<std::uint32_t>(data, count, slot);
            else decode_typed<std::uint64_t>(data, count, slot);
            break;
        case SampleKind::Signed:
            if (format_.bytes == 2) decode_typed<std::int16_t>(data, count, slot);
            else if (format_.bytes == 4) decode_typed<std::int32_t>(data, count, slot);
            else decode_typed<std::int64_t>(data, count, slot);
            break;
        case SampleKind::Float:
            if (format_.bytes == 4) decode_typed<float>(data, count, slot);
            else decode_typed<double>(data, count, slot);
            break;
        }
    }
}

// ----------------------------------------------------------------------------------------------
// Payload size checks and stored (uncompressed) payloads

std::string describe_payload(const Index3& dims, std::int64_t voxels, int bytes_per_value) {
    std::string text = format_dims(dims) + " = " + std::to_string(voxels) + " voxels";
    if (bytes_per_value > 1)
        text += " x " + std::to_string(bytes_per_value) + " bytes = " + std::to_string(voxels * bytes_per_value) + " bytes";
    return text;
}

std::uint64_t payload_bytes(const std::string& path, std::int64_t voxels, int bytes_per_value) {
    if (voxels > std::numeric_limits<std::int64_t>::max() / bytes_per_value)
        fail(path, std::to_string(voxels) + " voxels of " + std::to_string(bytes_per_value) + " bytes overflow a 64-bit size");
    return static_cast<std::uint64_t>(voxels) * static_cast<std::uint64_t>(bytes_per_value);
}

void require_exact_payload(const InputFile& file, std::uint64_t expected_bytes, const std::string& description) {
    const std::uint64_t available = file.remaining();
    const std::string holds =
        "file holds " + std::to_string(available) + " bytes" + (file.position() > 0 ? " after the header" : "");
    if (available < expected_bytes) file.fail("truncated payload: " + description + ", " + holds);
    if (available > expected_bytes)
        file.fail(std::to_string(available - expected_bytes) + " trailing bytes after the payload: " + description + ", " + holds);
}

void decode_stored_prefix(InputFile& file, SampleWriter& sink) {
    if (const StreamRegion* region = sink.region()) {  // a box: seek to its first slice
        file.skip(region->first_needed() * static_cast<std::uint64_t>(sink.sample_bytes()));
        sink.skip_to(region->first_needed());
    }
    std::vector<std::uint8_t> chunk(std::size_t(1) << 20);
    while (sink.bytes_needed() > 0) {
        const std::uint64_t missing = sink.bytes_needed();
        const std::size_t got = file.read(chunk.data(), static_cast<std::size_t>(std::min<std::uint64_t>(chunk.size(), missing)));
        if (got == 0)
            file.fail("truncated payload: the file ended (or could not be read) after " + std::to_string(sink.samples_written()) +
                      " values");
        sink.consume(chunk.data(), got);
    }
}

void decode_stored_payload(InputFile& file, SampleWriter& sink) {
    decode_stored_prefix(file, sink);
    if (sink.complete() && file.peek() != -1) file.fail("trailing bytes after the payload (the file grew while being read?)");
}

void check_writer_input(const std::string& path, const Index3& dims, std::size_t value_count) {
    VolumeLimits unlimited;
    unlimited.max_voxels = std::numeric_limits<std::int64_t>::max();
    const std::int64_t voxels = checked_voxel_count(path, dims, unlimited);
    if (static_cast<std::uint64_t>(voxels) != value_count)
        fail(path, "cannot write: " + std::to_string(value_count) + " values given for dimensions " + format_dims(dims) + " (" +
                       std::to_string(voxels) + " voxels)");
}

}  // namespace volume_io_detail

// ----------------------------------------------------------------------------------------------
// Dispatch on the file extension

namespace volume_io_detail {

namespace {

bool name_ends_with(const std::string& name, const char* suffix) {
    const std::size_t length = std::strlen(suffix);
    return name.size() > length && name.compare(name.size() - length, length, suffix) == 0;
}

}  // namespace

VolumeFormat volume_format(const std::string& path) {
    std::error_code error;
    if (std::filesystem::is_directory(path, error)) return VolumeFormat::DicomSeries;
    std::string name = std::filesystem::path(path).filename().string();
    std::transform(name.begin(), name.end(), name.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    static const std::pair<const char*, VolumeFormat> suffixes[] = {
        {".vol", VolumeFormat::Vol},        {".longvol", VolumeFormat::Longvol},  {".lvol", VolumeFormat::Longvol},
        {".pgm3d", VolumeFormat::Pgm3d},    {".p3d", VolumeFormat::Pgm3d},        {".raw", VolumeFormat::Raw},
        {".nii", VolumeFormat::Nifti},      {".nii.gz", VolumeFormat::Nifti},     {".hdr", VolumeFormat::Nifti},
        {".hdr.gz", VolumeFormat::Nifti},   {".img", VolumeFormat::Nifti},        {".img.gz", VolumeFormat::Nifti},
        {".nrrd", VolumeFormat::Nrrd},      {".nhdr", VolumeFormat::Nrrd},        {".mha", VolumeFormat::MetaImage},
        {".mhd", VolumeFormat::MetaImage},  {".npy", VolumeFormat::Npy},          {".tif", VolumeFormat::Tiff},
        {".tiff", VolumeFormat::Tiff},      {".h5", VolumeFormat::Hdf5},          {".hdf5", VolumeFormat::Hdf5},
        {".hdf", VolumeFormat::Hdf5},       {".vtk", VolumeFormat::VtkImage},     {".dcm", VolumeFormat::DicomFile},
    };
    for (const auto& [suffix, format] : suffixes)
        if (name_ends_with(name, suffix)) return format;
    const std::size_t dot = name.find('.', 1);
    const std::string shown = dot == std::string::npos ? "no extension" : "unknown extension '" + name.substr(dot) + "'";
    fail(path, "cannot tell the volume format: " + shown +
                   " (expected .vol .longvol .pgm3d .raw .nii .nii.gz .hdr/.img .nrrd .nhdr .mha .mhd .npy .tif .h5 .vtk .dcm, "
                   "or a folder holding a DICOM series)");
}

void read_volume_voxels(const std::string& path, const RawVolumeLayout* raw_layout, const VolumeLimits& limits,
                        VoxelDestination& destination) {
    const VolumeFormat format = volume_format(path);
    VolumeFileInfo& info = destination.info();
    switch (format) {
    case VolumeFormat::Vol: info = {".vol", "uint8", {}}; return read_vol_voxels(path, limits, destination);
    case VolumeFormat::Longvol: info = {".longvol", "uint64", {}}; return read_longvol_voxels(path, limits, destination);
    case VolumeFormat::Pgm3d: info = {"PGM3D", "", {}}; return read_pgm3d_voxels(path, limits, destination);
    case VolumeFormat::Raw:
        if (raw_layout == nullptr)
            fail(path, "a .raw volume has no header: its layout (dimensions, voxel type, byte order) must be given");
        info = {"raw", "", {}};
        return read_raw_voxels(path, *raw_layout, limits, destination);
    case VolumeFormat::Nifti: return read_nifti_voxels(path, limits, destination);
    case VolumeFormat::Nrrd: return read_nrrd_voxels(path, limits, destination);
    case VolumeFormat::MetaImage: return read_metaimage_voxels(path, limits, destination);
    case VolumeFormat::Npy: return read_npy_voxels(path, limits, destination);
    case VolumeFormat::Tiff: return read_itk_voxels(path, ItkFormat::Tiff, limits, destination);
    case VolumeFormat::Hdf5: return read_itk_voxels(path, ItkFormat::Hdf5, limits, destination);
    case VolumeFormat::VtkImage: return read_itk_voxels(path, ItkFormat::VtkImage, limits, destination);
    case VolumeFormat::DicomFile: return read_itk_voxels(path, ItkFormat::DicomFile, limits, destination);
    case VolumeFormat::DicomSeries: return read_dicom_series_voxels(path, limits, destination);
    }
}

}  // namespace volume_io_detail

BinaryVolume read_volume(const std::string& path, const ValueRange& range, const RawVolumeLayout* raw_layout,
                         const VolumeLimits& limits, VolumeFileInfo* info) {
    auto destination = volume_io_detail::VoxelDestination::mask(range);
    volume_io_detail::read_volume_voxels(path, raw_layout, limits, destination);
    if (info != nullptr) *info = destination.info();
    return destination.take_mask();
}

namespace {

/// Box reads and header probes exist for the formats whose readers honour a region and a
/// header-only destination: all but a DICOM series (its reader holds the slices ITK reads).
/// The ITK reader refuses a box of the images ITK cannot read by slices (TIFF, DICOM files).
void require_block_format(const std::string& path) {
    using volume_io_detail::VolumeFormat;
    if (volume_io_detail::volume_format(path) == VolumeFormat::DicomSeries)
        volume_io_detail::fail(path, "block-wise runs (--block-size, dsreg-mpi) do not read DICOM series; convert the "
                                     "series to .nii or .raw (or run dsreg regularize without --block-size)");
}

}  // namespace

VoxelGrid read_volume_grid(const std::string& path, const RawVolumeLayout* raw_layout, const VolumeLimits& limits,
                           VolumeFileInfo* info) {
    require_block_format(path);
    auto destination = volume_io_detail::VoxelDestination::header_only();
    volume_io_detail::read_volume_voxels(path, raw_layout, limits, destination);
    if (info != nullptr) *info = destination.info();
    return destination.take_mask().grid;
}

Index3 read_volume_dims(const std::string& path, const RawVolumeLayout* raw_layout, const VolumeLimits& limits) {
    return read_volume_grid(path, raw_layout, limits).dims;
}

BinaryVolume read_volume_box(const std::string& path, const VoxelBox& box, const ValueRange& range,
                             const RawVolumeLayout* raw_layout, const VolumeLimits& limits) {
    require_block_format(path);
    auto destination = volume_io_detail::VoxelDestination::mask(range);
    destination.restrict_to(box);
    volume_io_detail::read_volume_voxels(path, raw_layout, limits, destination);
    BinaryVolume volume = destination.take_mask();
    volume.grid.origin += volume.grid.spacing.cwiseProduct(Eigen::Vector3d(double(box.lo[0]), double(box.lo[1]), double(box.lo[2])));
    return volume;
}

ScalarVolume read_volume_values(const std::string& path, const RawVolumeLayout* raw_layout, const VolumeLimits& limits,
                                VolumeFileInfo* info) {
    auto destination = volume_io_detail::VoxelDestination::values();
    volume_io_detail::read_volume_voxels(path, raw_layout, limits, destination);
    if (info != nullptr) *info = destination.info();
    return destination.take_values();
}

LabelVolume read_label_volume(const std::string& path, const RawVolumeLayout* raw_layout, const VolumeLimits& limits,
                              VolumeFileInfo* info) {
    auto destination = volume_io_detail::VoxelDestination::labels(limits.max_labels);
    volume_io_detail::read_volume_voxels(path, raw_layout, limits, destination);
    if (info != nullptr) *info = destination.info();
    return destination.take_labels();
}

}  // namespace dsreg
