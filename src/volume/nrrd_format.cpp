// dsreg — NRRD images: .nrrd (data attached after the header) and .nhdr (detached data file).
//
// Header: the magic line "NRRD000N", then "field: value" lines ('#' comments, "key:=value" pairs
// ignored) ended by a blank line (attached data follows) or the end of the file (.nhdr). dsreg
// parses what locates and types the payload (type, dimension, sizes, encoding, endian, data file,
// line skip, byte skip) and checks it against the file before anything else reads it; ITK's
// NrrdImageIO then reads the header for the geometry (space, space directions, space origin,
// kinds), and must agree with dsreg on the sizes and the value type. The payload (raw or gzip
// encoding) is decoded here as it streams from the file. Not supported: ascii, hex and bzip2
// encodings, and data split over several files.
#include <filesystem>
#include <map>
#include <memory>

#include "dsreg/volume_io.hpp"
#include "image_geometry.hpp"
#include "image_payload.hpp"
#include "itk_bridge.hpp"
#include "text_header.hpp"
#include "volume_io_internal.hpp"

namespace dsreg::volume_io_detail {

namespace {

/// Generous: a header is a few hundred bytes; long "space directions" or comments stay far below.
constexpr std::uint64_t kMaxHeaderBytes = 1 << 20;
constexpr std::size_t kMaxFieldLineBytes = 400;  ///< a field line but content and sample units (teem's messages hold ~1 KiB)

struct NrrdHeader {
    std::vector<std::int64_t> sizes;
    SampleFormat sample;
    std::string value_type;
    bool gzip = false;
    std::string data_file;  ///< empty: attached
    std::int64_t line_skip = 0;
    std::int64_t byte_skip = 0;
};

using Fields = std::map<std::string, std::string>;

/// Field names are compared without case and without spaces ("byte skip" = "byteskip").
std::string field_key(const std::string& name) {
    std::string key;
    for (const char c : to_lower(trim(name)))
        if (c != ' ') key.push_back(c);
    return key;
}

Fields read_fields(InputFile& file) {
    std::string line;
    if (!read_header_line(file, line, kMaxHeaderBytes) || line.size() != 8 || line.compare(0, 7, "NRRD000") != 0 ||
        line[7] < '1' || line[7] > '5')
        file.fail("not a NRRD file: the first line is " + quote_excerpt(line) + ", not the magic NRRD0001 ... NRRD0005");
    Fields fields;
    for (int line_number = 2; read_header_line(file, line, kMaxHeaderBytes); ++line_number) {
        if (trim(line).empty()) break;  // attached data follows
        if (line[0] == '#') continue;
        const std::size_t colon = line.find(": ");
        if (line.find(":=") != std::string::npos && (colon == std::string::npos || line.find(":=") < colon)) continue;
        if (colon == std::string::npos)
            file.fail("header line " + std::to_string(line_number) + " is not 'field: value': " + quote_excerpt(line));
        const std::string key = field_key(line.substr(0, colon));
        // ITK's NRRD reader (teem) quotes a field it cannot parse into a message buffer of about
        // 1 KiB without a bound (a 1 000-byte 'space' value overflows it: found by trying every
        // field with long values); only the free-text fields are stored as they come.
        if (line.size() > kMaxFieldLineBytes && key != "content" && key != "sampleunits")
            file.fail("header line " + std::to_string(line_number) + " ('" + trim(line.substr(0, colon)).substr(0, 40) +
                      "') is " + std::to_string(line.size()) + " bytes long (at most " +
                      std::to_string(kMaxFieldLineBytes) + " here but for 'content' and 'sample units')");
        if (!fields.emplace(key, trim(line.substr(colon + 2))).second)
            file.fail("field '" + key + "' appears twice (line " + std::to_string(line_number) + ")");
    }
    return fields;
}

const std::string& required(const InputFile& file, const Fields& fields, const std::string& key) {
    const auto found = fields.find(key);
    if (found == fields.end()) file.fail("missing required field '" + key + "'");
    return found->second;
}

SampleFormat nrrd_type(const InputFile& file, const std::string& name) {
    static const std::map<std::string, std::pair<int, SampleKind>> types = {
        {"signed char", {1, SampleKind::Signed}},         {"int8", {1, SampleKind::Signed}},
        {"int8_t", {1, SampleKind::Signed}},              {"uchar", {1, SampleKind::Unsigned}},
        {"unsigned char", {1, SampleKind::Unsigned}},     {"uint8", {1, SampleKind::Unsigned}},
        {"uint8_t", {1, SampleKind::Unsigned}},           {"short", {2, SampleKind::Signed}},
        {"short int", {2, SampleKind::Signed}},           {"signed short", {2, SampleKind::Signed}},
        {"signed short int", {2, SampleKind::Signed}},    {"int16", {2, SampleKind::Signed}},
        {"int16_t", {2, SampleKind::Signed}},             {"ushort", {2, SampleKind::Unsigned}},
        {"unsigned short", {2, SampleKind::Unsigned}},    {"unsigned short int", {2, SampleKind::Unsigned}},
        {"uint16", {2, SampleKind::Unsigned}},            {"uint16_t", {2, SampleKind::Unsigned}},
        {"int", {4, SampleKind::Signed}},                 {"signed int", {4, SampleKind::Signed}},
        {"int32", {4, SampleKind::Signed}},               {"int32_t", {4, SampleKind::Signed}},
        {"uint", {4, SampleKind::Unsigned}},              {"unsigned int", {4, SampleKind::Unsigned}},
        {"uint32", {4, SampleKind::Unsigned}},            {"uint32_t", {4, SampleKind::Unsigned}},
        {"longlong", {8, SampleKind::Signed}},            {"long long", {8, SampleKind::Signed}},
        {"long long int", {8, SampleKind::Signed}},       {"signed long long", {8, SampleKind::Signed}},
        {"signed long long int", {8, SampleKind::Signed}}, {"int64", {8, SampleKind::Signed}},
        {"int64_t", {8, SampleKind::Signed}},             {"ulonglong", {8, SampleKind::Unsigned}},
        {"unsigned long long", {8, SampleKind::Unsigned}}, {"unsigned long long int", {8, SampleKind::Unsigned}},
        {"uint64", {8, SampleKind::Unsigned}},            {"uint64_t", {8, SampleKind::Unsigned}},
        {"float", {4, SampleKind::Float}},                {"double", {8, SampleKind::Float}},
    };
    const auto found = types.find(to_lower(name));
    if (found == types.end()) file.fail("unsupported value type " + quote_excerpt(name));
    return SampleFormat{found->second.first, found->second.second, false};
}

std::int64_t integer_field(const InputFile& file, const Fields& fields, const std::string& key, std::int64_t fallback) {
    const auto found = fields.find(key);
    if (found == fields.end()) return fallback;
    std::int64_t value = 0;
    if (!parse_integer(found->second, value)) file.fail("field '" + key + "': " + quote_excerpt(found->second) + " is not an integer");
    return value;
}

NrrdHeader parse_header(InputFile& file) {
    const Fields fields = read_fields(file);
    NrrdHeader header;
    header.sample = nrrd_type(file, required(file, fields, "type"));
    header.value_type = sample_type_name(header.sample);

    const std::string& dimension_text = required(file, fields, "dimension");
    std::int64_t dimension = 0;
    if (!parse_positive_integer(dimension_text, dimension) || dimension > 16)
        file.fail("field 'dimension': " + quote_excerpt(dimension_text) + " is not a number of dimensions (1 to 16)");
    const std::vector<std::string> sizes = split_words(required(file, fields, "sizes"));
    if (static_cast<std::int64_t>(sizes.size()) != dimension)
        file.fail("field 'sizes' gives " + std::to_string(sizes.size()) + " sizes for dimension " + std::to_string(dimension));
    for (const std::string& size : sizes) {
        std::int64_t value = 0;
        if (!parse_positive_integer(size, value)) file.fail("field 'sizes': " + quote_excerpt(size) + " is not a positive integer");
        header.sizes.push_back(value);
    }

    const std::string encoding = to_lower(required(file, fields, "encoding"));
    if (encoding == "gzip" || encoding == "gz")
        header.gzip = true;
    else if (encoding != "raw")
        file.fail("encoding '" + encoding + "' is not supported (dsreg reads the raw and gzip encodings)");

    if (header.sample.bytes > 1) {
        const std::string endian = to_lower(required(file, fields, "endian"));
        if (endian != "little" && endian != "big") file.fail("field 'endian': " + quote_excerpt(endian) + " is neither little nor big");
        header.sample.big_endian = endian == "big";
    }

    const auto data_file = fields.find("datafile");
    if (data_file != fields.end()) {
        header.data_file = data_file->second;
        if (header.data_file.empty()) file.fail("field 'data file' is empty");
        if (header.data_file.rfind("LIST", 0) == 0 || header.data_file.find('%') != std::string::npos)
            file.fail("data split over several files ('data file: " + quote_excerpt(header.data_file) + "') is not supported");
    }
    // Geometry is ITK's to read, but its values must be sane before ITK sees them.
    for (const auto& [key, name] : {std::pair<const char*, const char*>{"spacedirections", "space directions"},
                                    {"spaceorigin", "space origin"}, {"spacings", "spacings"}}) {
        const auto found = fields.find(key);
        // NaN spacings are NRRD's way of saying "no spacing" (non-spatial axes).
        const bool nan_spacing = std::string(key) == "spacings" && to_lower(found == fields.end() ? "" : found->second).find("nan") != std::string::npos;
        if (found != fields.end() && !nan_spacing) check_geometry_numbers(file, std::string("field '") + name + "'", found->second);
    }
    header.line_skip = integer_field(file, fields, "lineskip", 0);
    header.byte_skip = integer_field(file, fields, "byteskip", 0);
    if (header.line_skip < 0) file.fail("field 'line skip' is negative");
    if (header.byte_skip < -1) file.fail("field 'byte skip' must be -1 (data at the end of the file) or at least 0");
    if (header.byte_skip == -1 && header.gzip) file.fail("'byte skip: -1' is only meaningful with the raw encoding");
    return header;
}

}  // namespace

void read_nrrd_voxels(const std::string& path, const VolumeLimits& limits, VoxelDestination& destination) {
    InputFile file(path);
    const NrrdHeader header = parse_header(file);
    std::unique_ptr<InputFile> detached;
    if (!header.data_file.empty()) detached = open_data_file(path, header.data_file, "data file");
    InputFile& data = detached ? *detached : file;
    naming_header(path, [&] { skip_lines(data, header.line_skip, "line skip"); });
    PayloadLayout layout;
    layout.format = "NRRD";
    layout.sizes_field = "sizes";
    layout.sizes = header.sizes;
    layout.sample = header.sample;
    layout.value_type = header.value_type;
    layout.compressed = header.gzip;
    // "byte skip" counts stored bytes for raw data, inflated bytes for gzip data.
    if (header.gzip)
        layout.inflated_skip = static_cast<std::uint64_t>(header.byte_skip);
    else
        layout.skip = header.byte_skip;
    naming_header(path, [&] { read_image_payload(path, ItkFormat::Nrrd, layout, data, limits, destination); });
}

}  // namespace dsreg::volume_io_detail
