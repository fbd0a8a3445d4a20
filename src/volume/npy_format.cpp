// dsreg — NumPy .npy arrays (format versions 1, 2 and 3), read and written by dsreg itself.
//
// Layout: the magic "\x93NUMPY", the version (2 bytes), the header length (2 bytes little-endian
// in version 1, 4 bytes in versions 2 and 3), then a Python dict literal such as
// {'descr': '<u2', 'fortran_order': False, 'shape': (64, 48, 32), } padded with spaces to a
// multiple of 64 bytes and ended by '\n', then the values, exactly shape product × item size
// bytes. Voxel (i,j,k) is array[i, j, k] whatever the memory order: a Fortran-order array is
// stored with i fastest, like dsreg's grids; a C-order array with k fastest, so it is read plane
// by plane (one i at a time) and each plane is transposed into place.
#include <algorithm>
#include <cctype>
#include <cstring>

#include "dsreg/atomic_file.hpp"
#include "dsreg/volume_io.hpp"
#include "image_geometry.hpp"
#include "text_header.hpp"
#include "volume_io_internal.hpp"

namespace dsreg {

namespace volume_io_detail {

namespace {

constexpr char kMagic[] = "\x93NUMPY";
constexpr std::size_t kMagicBytes = 6;
constexpr std::uint64_t kMaxHeaderBytes = 1 << 20;

struct NpyHeader {
    SampleFormat sample;
    std::string value_type;
    bool fortran_order = false;
    std::vector<std::int64_t> shape;
};

/// A minimal reader of the header's dict literal: quoted strings, True/False, tuples of integers.
class DictScanner {
public:
    DictScanner(const InputFile& file, const std::string& text) : file_(file), text_(text) {}

    void skip_spaces() {
        while (position_ < text_.size() && std::isspace(static_cast<unsigned char>(text_[position_]))) ++position_;
    }
    bool accept(char c) {
        skip_spaces();
        if (position_ < text_.size() && text_[position_] == c) {
            ++position_;
            return true;
        }
        return false;
    }
    void expect(char c, const char* what) {
        if (!accept(c)) file_.fail(std::string("malformed .npy header: expected ") + what + " in " + quote_excerpt(text_));
    }
    std::string quoted() {
        skip_spaces();
        if (position_ >= text_.size() || (text_[position_] != '\'' && text_[position_] != '"'))
            file_.fail("malformed .npy header: expected a quoted string in " + quote_excerpt(text_));
        const char quote = text_[position_++];
        const std::size_t end = text_.find(quote, position_);
        if (end == std::string::npos) file_.fail("malformed .npy header: unterminated string in " + quote_excerpt(text_));
        std::string value = text_.substr(position_, end - position_);
        position_ = end + 1;
        return value;
    }
    std::string word() {
        skip_spaces();
        std::string value;
        while (position_ < text_.size() && (std::isalnum(static_cast<unsigned char>(text_[position_])) || text_[position_] == '_'))
            value.push_back(text_[position_++]);
        return value;
    }
    bool at_end() {
        skip_spaces();
        return position_ >= text_.size();
    }

private:
    const InputFile& file_;
    const std::string& text_;
    std::size_t position_ = 0;
};

SampleFormat npy_type(const InputFile& file, const std::string& descr) {
    if (descr.size() < 3) file.fail("unsupported .npy dtype " + quote_excerpt(descr));
    const char order = descr[0], kind = descr[1];
    std::int64_t bytes = 0;
    if ((order != '<' && order != '>' && order != '|' && order != '=') || !parse_positive_integer(descr.substr(2), bytes))
        file.fail("unsupported .npy dtype " + quote_excerpt(descr) + " (a structured or non-numeric type?)");
    SampleFormat format;
    format.bytes = static_cast<int>(bytes);
    format.big_endian = order == '>' || (order == '=' && native_sample(1, SampleKind::Unsigned).big_endian);
    if ((kind == 'u' || kind == 'b') && (bytes == 1 || bytes == 2 || bytes == 4 || bytes == 8) && (kind == 'u' || bytes == 1))
        format.kind = SampleKind::Unsigned;
    else if (kind == 'i' && (bytes == 1 || bytes == 2 || bytes == 4 || bytes == 8))
        format.kind = SampleKind::Signed;
    else if (kind == 'f' && (bytes == 4 || bytes == 8))
        format.kind = SampleKind::Float;
    else if (kind == 'c')
        file.fail("complex values (.npy dtype " + quote_excerpt(descr) + "): dsreg needs real scalar values");
    else
        file.fail("unsupported .npy dtype " + quote_excerpt(descr) +
                  " (integers of 1 to 8 bytes, booleans, float32 and float64 are supported)");
    return format;
}

NpyHeader parse_npy_header(InputFile& file) {
    std::uint8_t prefix[kMagicBytes + 2];
    if (file.read(prefix, sizeof prefix) != sizeof prefix || std::memcmp(prefix, kMagic, kMagicBytes) != 0)
        file.fail("not a NumPy .npy file (no \\x93NUMPY magic)");
    const int major = prefix[kMagicBytes];
    if (major < 1 || major > 3) file.fail(".npy format version " + std::to_string(major) + " is not supported (1 to 3 are)");
    const int length_bytes = major == 1 ? 2 : 4;
    std::uint8_t length_field[4] = {};
    if (file.read(length_field, static_cast<std::size_t>(length_bytes)) != static_cast<std::size_t>(length_bytes))
        file.fail("truncated .npy header");
    std::uint64_t length = 0;
    for (int i = length_bytes - 1; i >= 0; --i) length = (length << 8) | length_field[i];
    if (length > kMaxHeaderBytes || length > file.remaining())
        file.fail("the .npy header claims " + std::to_string(length) + " bytes, the file holds " + std::to_string(file.remaining()) +
                  " after its prefix");
    std::string text(static_cast<std::size_t>(length), '\0');
    file.read(reinterpret_cast<std::uint8_t*>(text.data()), text.size());

    NpyHeader header;
    bool has_descr = false, has_order = false, has_shape = false;
    DictScanner scan(file, text);
    scan.expect('{', "'{'");
    while (!scan.accept('}')) {
        const std::string key = scan.quoted();
        scan.expect(':', "':'");
        if (key == "descr") {
            header.sample = npy_type(file, scan.quoted());
            has_descr = true;
        } else if (key == "fortran_order") {
            const std::string value = scan.word();
            if (value != "True" && value != "False") file.fail("fortran_order is " + quote_excerpt(value) + ", not True or False");
            header.fortran_order = value == "True";
            has_order = true;
        } else if (key == "shape") {
            scan.expect('(', "a shape tuple");
            while (!scan.accept(')')) {
                std::int64_t size = 0;
                const std::string number = scan.word();
                if (!parse_integer(number, size) || size < 0) file.fail("shape entry " + quote_excerpt(number) + " is not a size");
                header.shape.push_back(size);
                if (header.shape.size() > 32) file.fail("the .npy shape has more than 32 dimensions");
                if (!scan.accept(',')) {
                    scan.expect(')', "')' ending the shape");
                    break;
                }
            }
            has_shape = true;
        } else {
            file.fail("unexpected key " + quote_excerpt(key) + " in the .npy header");
        }
        if (!scan.accept(',')) {
            scan.expect('}', "'}'");
            break;
        }
    }
    if (!has_descr || !has_order || !has_shape) file.fail("the .npy header lacks 'descr', 'fortran_order' or 'shape'");
    header.value_type = sample_type_name(header.sample);
    return header;
}

}  // namespace

void read_npy_voxels(const std::string& path, const VolumeLimits& limits, VoxelDestination& destination) {
    InputFile file(path);
    const NpyHeader npy = parse_npy_header(file);
    ImageHeader header;
    header.format = "NumPy .npy";
    header.sizes = npy.shape;
    header.value_type = npy.value_type;
    header.value_type_supported = true;
    header.sample = npy.sample;
    if (header.sizes.empty()) fail(path, "a 0-dimensional .npy array holds one value, not a volume");
    for (const std::int64_t size : header.sizes)
        if (size == 0) fail(path, "the .npy array is empty (shape with a zero)");
    const Index3 dims = image_dims(path, header);
    const std::int64_t voxels = checked_voxel_count(path, dims, limits);
    const std::uint64_t bytes = payload_bytes(path, voxels, npy.sample.bytes);
    require_exact_payload(file, bytes, "header says " + describe_payload(dims, voxels, npy.sample.bytes));

    if (!destination.allocate(path, dims)) return;
    destination.info().format = header.format;
    destination.info().value_type = npy.value_type;
    // Fortran order, or at most one axis longer than 1 in the way: the file order is the grid's.
    const bool grid_order =
        npy.fortran_order || (dims[1] == 1 && dims[2] == 1) || dims[0] == 1 || !destination.keeps_voxel_order();
    if (grid_order) {
        SampleWriter sink = destination.writer(path, npy.sample);
        return decode_stored_payload(file, sink);
    }
    // C order: the file holds the planes i = 0, 1, ... one after the other, each with k fastest.
    VoxelDestination plane = destination.like();
    plane.allocate(path, {dims[2], dims[1], 1});
    for (std::int64_t i = 0; i < dims[0]; ++i) {
        SampleWriter sink = plane.writer(path, npy.sample);
        decode_stored_prefix(file, sink);
        destination.store_x_plane(i, plane);
    }
    if (file.peek() != -1) file.fail("trailing bytes after the payload (the file grew while being read?)");
}

}  // namespace volume_io_detail

namespace {

using namespace volume_io_detail;

std::string npy_descr(RawVoxelType type) {
    switch (type) {
    case RawVoxelType::UInt8: return "|u1";
    case RawVoxelType::Int8: return "|i1";
    case RawVoxelType::UInt16: return "<u2";
    case RawVoxelType::Int16: return "<i2";
    case RawVoxelType::UInt32: return "<u4";
    case RawVoxelType::Int32: return "<i4";
    case RawVoxelType::UInt64: return "<u8";
    case RawVoxelType::Int64: return "<i8";
    case RawVoxelType::Float32: return "<f4";
    case RawVoxelType::Float64: return "<f8";
    }
    return "";
}

/// `value` converted to `type`, little-endian, appended to `out`.
void append_value(std::string& out, double value, RawVoxelType type) {
    std::uint64_t bits = 0;
    int bytes = 0;
    const auto store = [&](auto converted) {
        std::memcpy(&bits, &converted, sizeof converted);
        bytes = sizeof converted;
    };
    switch (type) {
    case RawVoxelType::UInt8: store(static_cast<std::uint8_t>(value)); break;
    case RawVoxelType::Int8: store(static_cast<std::int8_t>(value)); break;
    case RawVoxelType::UInt16: store(static_cast<std::uint16_t>(value)); break;
    case RawVoxelType::Int16: store(static_cast<std::int16_t>(value)); break;
    case RawVoxelType::UInt32: store(static_cast<std::uint32_t>(value)); break;
    case RawVoxelType::Int32: store(static_cast<std::int32_t>(value)); break;
    case RawVoxelType::UInt64: store(static_cast<std::uint64_t>(value)); break;
    case RawVoxelType::Int64: store(static_cast<std::int64_t>(value)); break;
    case RawVoxelType::Float32: store(static_cast<float>(value)); break;
    case RawVoxelType::Float64: store(value); break;
    }
    // memcpy put the value's bytes in host order; the file is little-endian.
    unsigned char raw[8];
    std::memcpy(raw, &bits, 8);
    const bool little = native_sample(1, SampleKind::Unsigned).big_endian == false;
    for (int b = 0; b < bytes; ++b) out.push_back(static_cast<char>(little ? raw[b] : raw[bytes - 1 - b]));
}

}  // namespace

void write_npy(const std::string& path, const Index3& dims, const std::vector<double>& values, RawVoxelType type,
               bool fortran_order) {
    check_writer_input(path, dims, values.size());
    std::string header = "{'descr': '" + npy_descr(type) + "', 'fortran_order': " + (fortran_order ? "True" : "False") +
                         ", 'shape': (" + std::to_string(dims[0]) + ", " + std::to_string(dims[1]) + ", " +
                         std::to_string(dims[2]) + "), }";
    // Pad with spaces so that magic + version + length + header + '\n' is a multiple of 64.
    const std::size_t prefix = kMagicBytes + 2 + 2;
    while ((prefix + header.size() + 1) % 64 != 0) header.push_back(' ');
    header.push_back('\n');
    write_file_atomically(path, [&](std::ostream& out) {
        out.write(kMagic, kMagicBytes);
        const char version[2] = {1, 0};
        out.write(version, 2);
        const char length[2] = {static_cast<char>(header.size() & 0xff), static_cast<char>(header.size() >> 8)};
        out.write(length, 2);
        out << header;
        std::string row;
        VoxelGrid grid;
        grid.dims = dims;
        if (fortran_order) {
            for (const double value : values) append_value(row, value, type);
            out << row;
            return;
        }
        for (std::int64_t i = 0; i < dims[0]; ++i) {
            row.clear();
            for (std::int64_t j = 0; j < dims[1]; ++j)
                for (std::int64_t k = 0; k < dims[2]; ++k)
                    append_value(row, values[static_cast<std::size_t>(grid.linear_index(i, j, k))], type);
            out << row;
        }
    });
}

}  // namespace dsreg
