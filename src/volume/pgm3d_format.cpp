// dsreg — PGM3D, the 3D variant of Netpbm's PGM used by DGtal.
//
// Header: magic "P2-3D" (ASCII values) or "P5-3D" (binary values), then width height depth
// maxval as whitespace-separated decimal integers, with '#' comments (to the end of the line)
// allowed between them. P2-3D: width·height·depth whitespace-separated decimal values. P5-3D:
// exactly one whitespace character after maxval, then the values as 1 byte each if maxval < 256,
// else 2 bytes big-endian. Values are in [0, maxval], x fastest.
#include <algorithm>

#include "dsreg/atomic_file.hpp"
#include "dsreg/volume_io.hpp"
#include "volume_io_internal.hpp"

namespace dsreg {

namespace {

using namespace volume_io_detail;

constexpr int kMaxMaxval = 65535;
/// Header tokens are short numbers; reading stops a little past this length.
constexpr std::size_t kMaxTokenLength = 32;

struct Pgm3dHeader {
    bool binary = false;
    Index3 dims{0, 0, 0};
    int maxval = 0;
};

bool is_pgm_space(int c) { return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\v' || c == '\f'; }

void skip_spaces(InputFile& file) {
    while (is_pgm_space(file.peek())) file.get();
}

/// Skips whitespace and '#' comments (which run to the end of the line) between header tokens.
void skip_header_separators(InputFile& file) {
    for (;;) {
        skip_spaces(file);
        if (file.peek() != '#') return;
        for (int c = file.get(); c != -1 && c != '\n'; c = file.get()) {
        }
    }
}

/// The characters up to the next whitespace or '#' (bounded: longer tokens are invalid anyway).
std::string read_token_here(InputFile& file) {
    std::string token;
    for (int c = file.peek(); c != -1 && !is_pgm_space(c) && c != '#' && token.size() <= kMaxTokenLength; c = file.peek()) {
        token.push_back(static_cast<char>(c));
        file.get();
    }
    return token;
}

std::int64_t read_header_dimension(InputFile& file, const std::string& name) {
    skip_header_separators(file);
    const std::string token = read_token_here(file);
    if (token.empty()) file.fail("the header ends before the " + name);
    std::int64_t value = 0;
    if (!parse_positive_integer(token, value)) file.fail(name + " " + quote_excerpt(token) + " is not a positive integer");
    return value;
}

int read_maxval(InputFile& file) {
    skip_header_separators(file);
    const std::string token = read_token_here(file);
    if (token.empty()) file.fail("the header ends before maxval");
    std::int64_t value = 0;
    if (!parse_positive_integer(token, value) || value > kMaxMaxval)
        file.fail("maxval " + quote_excerpt(token) + " is not an integer in 1.." + std::to_string(kMaxMaxval));
    return static_cast<int>(value);
}

Pgm3dHeader read_pgm3d_header(InputFile& file) {
    Pgm3dHeader header;
    const std::string magic = read_token_here(file);
    if (magic == "P5-3D")
        header.binary = true;
    else if (magic != "P2-3D")
        file.fail("bad magic " + quote_excerpt(magic) + ": a PGM3D file starts with 'P2-3D' (ASCII) or 'P5-3D' (binary)");
    header.dims = {read_header_dimension(file, "width"), read_header_dimension(file, "height"),
                   read_header_dimension(file, "depth")};
    header.maxval = read_maxval(file);
    return header;
}

/// Reads the next whitespace-separated ASCII value into `value`; false at end of file.
bool read_ascii_value(InputFile& file, std::int64_t index, int maxval, int& value) {
    skip_spaces(file);
    if (file.peek() == -1) return false;
    std::int64_t number = 0;
    bool numeric = true;
    std::string excerpt;
    for (int c = file.peek(); c != -1 && !is_pgm_space(c); c = file.peek()) {
        file.get();
        if (excerpt.size() <= kMaxTokenLength) excerpt.push_back(static_cast<char>(c));
        if (c < '0' || c > '9')
            numeric = false;
        else if (number <= maxval)  // stop growing once too large: no overflow, still rejected below
            number = number * 10 + (c - '0');
    }
    if (!numeric) file.fail("value of voxel #" + std::to_string(index) + " " + quote_excerpt(excerpt) + " is not a non-negative integer");
    if (number > maxval)
        file.fail("value " + quote_excerpt(excerpt) + " of voxel #" + std::to_string(index) + " exceeds maxval " + std::to_string(maxval));
    value = static_cast<int>(number);
    return true;
}

void decode_ascii_values(InputFile& file, const Pgm3dHeader& header, const std::string& description,
                         VoxelDestination& destination) {
    const auto voxels = static_cast<std::int64_t>(destination.size());
    for (std::int64_t index = 0; index < voxels; ++index) {
        int value = 0;
        if (!read_ascii_value(file, index, header.maxval, value))
            file.fail("truncated ASCII data: " + description + ", the file holds only " + std::to_string(index) + " values");
        destination.set(static_cast<std::uint64_t>(index), value);
    }
    skip_spaces(file);
    if (file.peek() != -1) file.fail("trailing data after the " + std::to_string(voxels) + " values: " + quote_excerpt(read_token_here(file)));
}

/// Each ASCII value takes at least one digit and one separator (except the last).
void require_plausible_ascii_payload(const InputFile& file, std::int64_t voxels, const std::string& description) {
    const std::uint64_t max_values = (file.remaining() + 1) / 2;
    if (static_cast<std::uint64_t>(voxels) > max_values)
        file.fail("truncated ASCII data: " + description + ", but the " + std::to_string(file.remaining()) +
                  " bytes after the header can hold at most " + std::to_string(max_values) + " values");
}

void decode_binary_values(InputFile& file, const Pgm3dHeader& header, std::int64_t voxels, const std::string& path,
                          VoxelDestination& destination) {
    if (!is_pgm_space(file.get())) file.fail("expected a single whitespace character between maxval and the binary data");
    const SampleFormat sample{header.maxval < 256 ? 1 : 2, SampleKind::Unsigned, true};
    const std::uint64_t expected = payload_bytes(path, voxels, sample.bytes);
    require_exact_payload(file, expected, "header says " + describe_payload(header.dims, voxels, sample.bytes));
    if (!destination.allocate(path, header.dims)) return;
    SampleWriter sink = destination.writer(path, sample);
    sink.reject_values_above(header.maxval, "maxval");
    decode_stored_payload(file, sink);
}

void write_binary_values(std::ostream& out, const std::vector<std::uint16_t>& values, bool two_bytes) {
    std::vector<char> chunk;
    constexpr std::size_t values_per_chunk = 1 << 15;
    for (std::size_t start = 0; start < values.size(); start += values_per_chunk) {
        chunk.clear();
        const std::size_t end = std::min(values.size(), start + values_per_chunk);
        for (std::size_t i = start; i < end; ++i) {
            if (two_bytes) chunk.push_back(static_cast<char>(values[i] >> 8));
            chunk.push_back(static_cast<char>(values[i] & 0xff));
        }
        out.write(chunk.data(), static_cast<std::streamsize>(chunk.size()));
    }
}

/// One line per row of the volume.
void write_ascii_values(std::ostream& out, const std::vector<std::uint16_t>& values, std::int64_t row_length) {
    for (std::size_t i = 0; i < values.size(); ++i) {
        out << values[i];
        out << ((static_cast<std::int64_t>(i + 1) % row_length == 0) ? '\n' : ' ');
    }
}

}  // namespace

namespace volume_io_detail {

void read_pgm3d_voxels(const std::string& path, const VolumeLimits& limits, VoxelDestination& destination) {
    InputFile file(path);
    const Pgm3dHeader header = read_pgm3d_header(file);
    const std::int64_t voxels = checked_voxel_count(path, header.dims, limits);
    if (header.binary) return decode_binary_values(file, header, voxels, path, destination);

    const std::string description = "header says " + describe_payload(header.dims, voxels, 1);
    require_plausible_ascii_payload(file, voxels, description);
    if (!destination.allocate(path, header.dims)) return;
    decode_ascii_values(file, header, description, destination);
}

}  // namespace volume_io_detail

BinaryVolume read_pgm3d(const std::string& path, const ValueRange& range, const VolumeLimits& limits) {
    auto destination = VoxelDestination::mask(range);
    read_pgm3d_voxels(path, limits, destination);
    return destination.take_mask();
}

void write_pgm3d(const std::string& path, const Index3& dims, const std::vector<std::uint16_t>& values, bool binary) {
    check_writer_input(path, dims, values.size());
    // PGM requires maxval ≥ 1; the smallest valid maxval keeps binary files at 1 byte per value when possible.
    const int maxval = std::max<int>(1, *std::max_element(values.begin(), values.end()));
    write_file_atomically(path, [&](std::ostream& out) {
        out << (binary ? "P5-3D" : "P2-3D") << "\n# written by dsreg\n"
            << dims[0] << ' ' << dims[1] << ' ' << dims[2] << '\n'
            << maxval << '\n';
        if (binary)
            write_binary_values(out, values, maxval >= 256);
        else
            write_ascii_values(out, values, dims[0]);
    });
}

}  // namespace dsreg
