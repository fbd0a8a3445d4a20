// dsreg — DGtal .vol (8-bit voxels) and .longvol (64-bit voxels), versions 2 and 3.
//
// Layout: ASCII header lines "Key: value", then a line holding a single ".", then the payload:
// X·Y·Z values, x fastest, stored as is (Version 2) or as one zlib stream (Version 3).
// .longvol values are 8-byte little-endian unsigned integers, as DGtal's LongvolWriter writes
// them (least significant byte first).
#include <algorithm>
#include <map>

#include "dsreg/atomic_file.hpp"
#include "dsreg/volume_io.hpp"
#include "text_header.hpp"
#include "volume_io_internal.hpp"

namespace dsreg {

namespace {

using namespace volume_io_detail;

using HeaderFields = std::map<std::string, std::string>;

/// Generous bound: real headers are a dozen short lines.
constexpr std::uint64_t kMaxHeaderBytes = 1 << 16;

constexpr SampleFormat kVolSample{1, SampleKind::Unsigned, false};
constexpr SampleFormat kLongvolSample{8, SampleKind::Unsigned, false};

struct DgtalHeader {
    Index3 dims{0, 0, 0};
    int version = 0;
    HeaderFields fields;
};

/// Reads one header line (without its '\n'); returns false at end of file before any '\n'.
bool read_header_line(InputFile& file, std::string& line) {
    line.clear();
    for (int c = file.get(); c != -1; c = file.get()) {
        if (c == '\n') return true;
        if (file.position() > kMaxHeaderBytes)
            file.fail("no '.' line ending the header within its first " + std::to_string(kMaxHeaderBytes) + " bytes");
        line.push_back(static_cast<char>(c));
    }
    return false;
}

/// Reads the "Key: value" lines up to and including the "." line.
HeaderFields read_header_fields(InputFile& file) {
    HeaderFields fields;
    std::string line;
    for (int line_number = 1;; ++line_number) {
        if (!read_header_line(file, line))
            file.fail("missing '.' line ending the header (the file ends after " + std::to_string(line_number - 1) +
                      " header lines)");
        if (trim(line) == ".") return fields;
        const std::size_t colon = line.find(':');
        const std::string key = colon == std::string::npos ? "" : trim(line.substr(0, colon));
        if (key.empty())
            file.fail("header line " + std::to_string(line_number) + " is not 'Key: value': " + quote_excerpt(line));
        if (!fields.emplace(key, trim(line.substr(colon + 1))).second)
            file.fail("duplicate header key '" + key + "' (line " + std::to_string(line_number) + ")");
    }
}

const std::string& required_field(const InputFile& file, const HeaderFields& fields, const std::string& key) {
    const auto found = fields.find(key);
    if (found == fields.end()) file.fail("missing required header key '" + key + "'");
    return found->second;
}

std::int64_t required_dimension(const InputFile& file, const HeaderFields& fields, const std::string& key) {
    const std::string& text = required_field(file, fields, key);
    std::int64_t value = 0;
    if (!parse_positive_integer(text, value)) file.fail("header key " + key + ": " + quote_excerpt(text) + " is not a positive integer");
    return value;
}

DgtalHeader read_dgtal_header(InputFile& file) {
    DgtalHeader header;
    header.fields = read_header_fields(file);
    header.dims = {required_dimension(file, header.fields, "X"), required_dimension(file, header.fields, "Y"),
                   required_dimension(file, header.fields, "Z")};
    const std::string& version = required_field(file, header.fields, "Version");
    if (version == "2")
        header.version = 2;
    else if (version == "3")
        header.version = 3;
    else
        file.fail("unsupported Version " + quote_excerpt(version) + " (expected 2: raw payload, or 3: zlib payload)");
    return header;
}

/// .vol voxels are single bytes; a file announcing another size is not one we can read.
void require_byte_voxels(const InputFile& file, const HeaderFields& fields) {
    const auto found = fields.find("Voxel-Size");
    if (found != fields.end() && found->second != "1")
        file.fail("unsupported Voxel-Size " + quote_excerpt(found->second) + " (a .vol voxel is 1 byte)");
}

void decode_dgtal_payload(InputFile& file, const DgtalHeader& header, SampleFormat sample, const VolumeLimits& limits,
                          VoxelDestination& destination) {
    const std::int64_t voxels = checked_voxel_count(file.path(), header.dims, limits);
    const std::uint64_t expected = payload_bytes(file.path(), voxels, sample.bytes);
    const std::string description = "header says " + describe_payload(header.dims, voxels, sample.bytes);
    if (header.version == 2)
        require_exact_payload(file, expected, description);
    else
        require_plausible_zlib_payload(file, expected, description);

    if (!destination.allocate(file.path(), header.dims)) return;
    SampleWriter sink = destination.writer(file.path(), sample);
    if (header.version == 2)
        decode_stored_payload(file, sink);
    else
        decode_zlib_payload(file, expected, sink, description);
}

/// The header DGtal's writers produce (all the keys its readers require), without Center-*
/// keys so that DGtal reads the domain as starting at (0,0,0), like we do.
void write_dgtal_header(std::ostream& out, const Index3& dims, const std::string& size_key, int value_bytes,
                        const std::string& endian_key, int version) {
    out << "X: " << dims[0] << "\n"
        << "Y: " << dims[1] << "\n"
        << "Z: " << dims[2] << "\n"
        << size_key << ": " << value_bytes << "\n"
        << "Alpha-Color: 0\n"
        << endian_key << ": 0\n"
        << "Int-Endian: 0123\n"
        << "Version: " << version << "\n"
        << ".\n";
}

void check_version(const std::string& path, int version) {
    if (version != 2 && version != 3)
        fail(path, "cannot write: unsupported version " + std::to_string(version) + " (expected 2: raw payload, or 3: zlib payload)");
}

}  // namespace

namespace volume_io_detail {

void read_vol_voxels(const std::string& path, const VolumeLimits& limits, VoxelDestination& destination) {
    InputFile file(path);
    const DgtalHeader header = read_dgtal_header(file);
    require_byte_voxels(file, header.fields);
    decode_dgtal_payload(file, header, kVolSample, limits, destination);
}

void read_longvol_voxels(const std::string& path, const VolumeLimits& limits, VoxelDestination& destination) {
    // Lvoxel-Size is not checked: DGtal writes "Lvoxel-Size: 4" for its 8-byte values.
    InputFile file(path);
    const DgtalHeader header = read_dgtal_header(file);
    decode_dgtal_payload(file, header, kLongvolSample, limits, destination);
}

}  // namespace volume_io_detail

BinaryVolume read_vol(const std::string& path, const ValueRange& range, const VolumeLimits& limits) {
    auto destination = VoxelDestination::mask(range);
    read_vol_voxels(path, limits, destination);
    return destination.take_mask();
}

BinaryVolume read_longvol(const std::string& path, const ValueRange& range, const VolumeLimits& limits) {
    auto destination = VoxelDestination::mask(range);
    read_longvol_voxels(path, limits, destination);
    return destination.take_mask();
}

void write_vol(const std::string& path, const Index3& dims, const std::vector<std::uint8_t>& values, int version) {
    check_writer_input(path, dims, values.size());
    check_version(path, version);
    write_file_atomically(path, [&](std::ostream& out) {
        write_dgtal_header(out, dims, "Voxel-Size", 1, "Voxel-Endian", version);
        PayloadWriter payload(path, out, version == 3);
        payload.write(values.data(), values.size());
        payload.finish();
    });
}

void write_longvol(const std::string& path, const Index3& dims, const std::vector<std::uint64_t>& values, int version) {
    check_writer_input(path, dims, values.size());
    check_version(path, version);
    write_file_atomically(path, [&](std::ostream& out) {
        write_dgtal_header(out, dims, "Lvoxel-Size", 8, "Lvoxel-Endian", version);
        PayloadWriter payload(path, out, version == 3);
        constexpr std::size_t values_per_chunk = 1 << 13;
        std::vector<std::uint8_t> chunk;
        chunk.reserve(values_per_chunk * 8);
        for (std::size_t start = 0; start < values.size(); start += values_per_chunk) {
            chunk.clear();
            const std::size_t end = std::min(values.size(), start + values_per_chunk);
            for (std::size_t i = start; i < end; ++i)
                for (int byte = 0; byte < 8; ++byte) chunk.push_back(static_cast<std::uint8_t>(values[i] >> (8 * byte)));
            payload.write(chunk.data(), chunk.size());
        }
        payload.finish();
    });
}

}  // namespace dsreg
