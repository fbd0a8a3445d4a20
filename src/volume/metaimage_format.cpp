// dsreg — MetaImage: .mha (data in the same file) and .mhd (data in the file it names).
//
// Header: "Key = Value" lines; ElementDataFile is the last one: LOCAL (the data follows that
// line) or the name of the data file, relative to the header. dsreg parses what locates and types
// the payload (NDims, DimSize, ElementType, ElementNumberOfChannels, BinaryData, byte order,
// HeaderSize, CompressedData, CompressedDataSize, ElementDataFile) and checks it against the
// file(s) before anything else reads them; ITK's MetaImageIO then reads the header for the
// geometry (Offset, ElementSpacing, TransformMatrix) and must agree on the sizes and value type.
// The payload (raw, or one zlib stream with CompressedData) is decoded here as it streams.
// Not supported: ASCII data (BinaryData = False), data split over several files (LIST, patterns).
#include <filesystem>
#include <map>
#include <memory>

#include "dsreg/text.hpp"
#include "dsreg/volume_io.hpp"
#include "image_geometry.hpp"
#include "image_payload.hpp"
#include "itk_bridge.hpp"
#include "text_header.hpp"
#include "volume_io_internal.hpp"

namespace dsreg::volume_io_detail {

namespace {

constexpr std::uint64_t kMaxHeaderBytes = 1 << 20;

struct MetaHeader {
    std::vector<std::int64_t> sizes;
    std::int64_t channels = 1;
    SampleFormat sample;
    std::string value_type;
    bool compressed = false;
    std::int64_t compressed_size = -1;  ///< -1: the rest of the data file
    std::int64_t header_size = 0;       ///< bytes to skip in the data file; -1: data at its end
    std::string data_file;              ///< "LOCAL" or a file name
};

using Fields = std::map<std::string, std::string>;

constexpr std::size_t kMaxKeyBytes = 200;        ///< the text before '=' (ITK's field names hold 254)
constexpr std::size_t kMaxTextValueBytes = 200;  ///< a value that is not a list of numbers (ITK's text fields hold 254)

/// The geometry keys MetaIO reads as lists of numbers, with how many numbers each must give: one
/// per dimension, or NDims² for a matrix. DimSize, also a list, is checked on its own.
struct NumberListKey {
    const char* name;
    bool matrix;
};
constexpr NumberListKey kGeometryKeys[] = {{"Offset", false},         {"Position", false},         {"Origin", false},
                                           {"ElementSpacing", false}, {"ElementSize", false},      {"TransformMatrix", true},
                                           {"Rotation", true},        {"Orientation", true},       {"CenterOfRotation", false}};

/// Keys whose values MetaIO reads as lists of numbers (DimSize and the geometry keys): the only
/// values allowed to be long. Every other value is copied by MetaIO into a 255-byte field
/// (Comment, Name…) or is a single word.
bool is_number_list_key(const std::string& lower_key) {
    if (lower_key == "dimsize") return true;
    for (const NumberListKey& key : kGeometryKeys)
        if (lower_key == to_lower(key.name)) return true;
    return false;
}

Fields read_fields(InputFile& file) {
    Fields fields;
    std::string line;
    for (int line_number = 1;; ++line_number) {
        if (!read_header_line(file, line, kMaxHeaderBytes))
            file.fail("the header ends without an ElementDataFile line (not a MetaImage file?)");
        if (trim(line).empty()) continue;
        const std::size_t equals = line.find('=');
        const std::string key = equals == std::string::npos ? "" : to_lower(trim(line.substr(0, equals)));
        if (key.empty())
            file.fail("header line " + std::to_string(line_number) + " is not 'Key = Value': " + quote_excerpt(line));
        // ITK's MetaIO copies each key into a 255-byte field name without a bound (a longer one
        // overflows it: found by fuzzing); no MetaImage key is near this long.
        if (equals > kMaxKeyBytes)
            file.fail("header line " + std::to_string(line_number) + " has a key of " + std::to_string(equals) +
                      " bytes (MetaImage keys are words, at most " + std::to_string(kMaxKeyBytes) + " bytes here)");
        // Text values (Comment, Name, ObjectSubType…) are copied by MetaIO into 255-byte fields
        // without a bound as well (found by trying every key with long values; a Comment made of
        // numbers overflows as well: found by fuzzing). Measured untrimmed: MetaIO may keep the
        // spaces around it.
        const std::string value = trim(line.substr(equals + 1));
        const std::size_t value_bytes = line.size() - equals - 1;
        if (value_bytes > kMaxTextValueBytes && !is_number_list_key(key))
            file.fail("header line " + std::to_string(line_number) + ": the value of '" + trim(line.substr(0, equals)) +
                      "' is " + std::to_string(value_bytes) + " bytes (at most " + std::to_string(kMaxTextValueBytes) +
                      " here but for lists of numbers such as DimSize: ITK's MetaImage reader cannot hold longer ones)");
        if (!fields.emplace(key, value).second)
            file.fail("key '" + trim(line.substr(0, equals)) + "' appears twice (line " + std::to_string(line_number) + ")");
        // The data (if LOCAL) starts on the next line. ITK's MetaIO matches keys case-sensitively:
        // past "ElementdataFile" it reads on as header, through the payload, whose lines dsreg
        // never checked (a binary key of 400 bytes there overflowed its 255-byte field name:
        // found by fuzzing). So the header ends where MetaIO ends it, and another spelling is refused.
        if (key == "elementdatafile") {
            const std::string spelled = trim(line.substr(0, equals));
            if (spelled != "ElementDataFile")
                file.fail("header line " + std::to_string(line_number) + ": '" + spelled +
                          "' must be spelled 'ElementDataFile' (ITK's MetaImage reader matches keys case by case)");
            return fields;
        }
    }
}

bool boolean_field(const InputFile& file, const Fields& fields, const std::string& key, bool fallback) {
    const auto found = fields.find(key);
    if (found == fields.end()) return fallback;
    const std::string value = to_lower(found->second);
    if (value == "true" || value == "1") return true;
    if (value == "false" || value == "0") return false;
    file.fail("key '" + key + "': " + quote_excerpt(found->second) + " is neither True nor False");
}

std::int64_t integer_field(const InputFile& file, const Fields& fields, const std::string& key, std::int64_t fallback) {
    const auto found = fields.find(key);
    if (found == fields.end()) return fallback;
    std::int64_t value = 0;
    if (!parse_integer(found->second, value)) file.fail("key '" + key + "': " + quote_excerpt(found->second) + " is not an integer");
    return value;
}

SampleFormat meta_type(const InputFile& file, const std::string& name) {
    // Sizes as MetaIO defines them (MET_LONG and MET_ULONG are 4 bytes there).
    static const std::map<std::string, std::pair<int, SampleKind>> types = {
        {"MET_CHAR", {1, SampleKind::Signed}},       {"MET_UCHAR", {1, SampleKind::Unsigned}},
        {"MET_SHORT", {2, SampleKind::Signed}},      {"MET_USHORT", {2, SampleKind::Unsigned}},
        {"MET_INT", {4, SampleKind::Signed}},        {"MET_UINT", {4, SampleKind::Unsigned}},
        {"MET_LONG", {4, SampleKind::Signed}},       {"MET_ULONG", {4, SampleKind::Unsigned}},
        {"MET_LONG_LONG", {8, SampleKind::Signed}},  {"MET_ULONG_LONG", {8, SampleKind::Unsigned}},
        {"MET_FLOAT", {4, SampleKind::Float}},       {"MET_DOUBLE", {8, SampleKind::Float}},
    };
    const auto found = types.find(name);
    if (found != types.end()) return SampleFormat{found->second.first, found->second.second, false};
    if (name.find("_ARRAY") != std::string::npos)
        file.fail("ElementType " + quote_excerpt(name) + " is a vector type: dsreg needs a scalar image");
    file.fail("unsupported ElementType " + quote_excerpt(name));
}

MetaHeader parse_header(InputFile& file) {
    const Fields fields = read_fields(file);
    MetaHeader header;
    const auto object_type = fields.find("objecttype");
    if (object_type != fields.end() && to_lower(object_type->second) != "image")
        file.fail("ObjectType is " + quote_excerpt(object_type->second) + ", not Image");
    const auto dims = fields.find("ndims");
    const auto sizes = fields.find("dimsize");
    const auto type = fields.find("elementtype");
    if (dims == fields.end() || sizes == fields.end() || type == fields.end())
        file.fail("missing required key (NDims, DimSize and ElementType are needed)");
    std::int64_t rank = 0;
    // MetaIO's arrays hold 10 dimensions (it would read a larger NDims as 10).
    if (!parse_positive_integer(dims->second, rank) || rank > 10)
        file.fail("NDims " + quote_excerpt(dims->second) + " is not a number of dimensions (1 to 10)");
    const std::vector<std::string> words = split_words(sizes->second);
    if (static_cast<std::int64_t>(words.size()) != rank)
        file.fail("DimSize gives " + std::to_string(words.size()) + " sizes for NDims = " + std::to_string(rank));
    for (const std::string& word : words) {
        std::int64_t size = 0;
        if (!parse_positive_integer(word, size)) file.fail("DimSize: " + quote_excerpt(word) + " is not a positive integer");
        header.sizes.push_back(size);
    }
    // Geometry is ITK's to read, but its values must be sane before ITK sees them: one number a
    // dimension, NDims² for a matrix.
    for (const NumberListKey& key : kGeometryKeys) {
        const auto found = fields.find(to_lower(key.name));
        if (found == fields.end()) continue;
        check_geometry_numbers(file, std::string(key.name), found->second);
        const std::size_t expected = static_cast<std::size_t>(key.matrix ? rank * rank : rank);
        const std::size_t given = split_words(found->second).size();
        if (given != expected)
            file.fail(std::string(key.name) + " gives " + std::to_string(given) + " numbers for NDims = " + std::to_string(rank) +
                      " (" + std::to_string(expected) + " expected)");
    }
    header.channels = integer_field(file, fields, "elementnumberofchannels", 1);
    if (header.channels < 1) file.fail("ElementNumberOfChannels must be at least 1");
    header.sample = meta_type(file, type->second);
    header.value_type = sample_type_name(header.sample);
    if (!boolean_field(file, fields, "binarydata", true)) file.fail("ASCII data (BinaryData = False) is not supported");
    header.sample.big_endian = boolean_field(file, fields, "binarydatabyteordermsb", false) ||
                               boolean_field(file, fields, "elementbyteordermsb", false);
    header.compressed = boolean_field(file, fields, "compresseddata", false);
    header.compressed_size = integer_field(file, fields, "compresseddatasize", -1);
    if (header.compressed_size < -1 || header.compressed_size == 0) file.fail("CompressedDataSize must be positive");
    header.header_size = integer_field(file, fields, "headersize", 0);
    if (header.header_size < -1) file.fail("HeaderSize must be -1 (data at the end of the file) or at least 0");
    if (header.header_size == -1 && header.compressed) file.fail("HeaderSize = -1 is only meaningful for uncompressed data");
    header.data_file = fields.at("elementdatafile");
    const std::string lower = to_lower(header.data_file);
    if (lower.rfind("list", 0) == 0 || header.data_file.find('%') != std::string::npos)
        file.fail("data split over several files (ElementDataFile = " + quote_excerpt(header.data_file) + ") is not supported");
    if (header.data_file.empty()) file.fail("ElementDataFile is empty");
    return header;
}

}  // namespace

void read_metaimage_voxels(const std::string& path, const VolumeLimits& limits, VoxelDestination& destination) {
    InputFile file(path);
    const MetaHeader header = parse_header(file);
    std::unique_ptr<InputFile> detached;
    if (to_lower(header.data_file) != "local") detached = open_data_file(path, header.data_file, "ElementDataFile");
    InputFile& data = detached ? *detached : file;
    PayloadLayout layout;
    layout.format = "MetaImage";
    layout.sizes_field = "DimSize";
    layout.sizes = header.sizes;
    layout.components = header.channels;
    layout.sample = header.sample;
    layout.value_type = header.value_type;
    layout.skip = header.header_size;
    layout.compressed = header.compressed;
    layout.container = CompressedContainer::ZlibOrGzip;
    layout.compressed_size = header.compressed_size;
    naming_header(path, [&] { read_image_payload(path, ItkFormat::MetaImage, layout, data, limits, destination); });
}

}  // namespace dsreg::volume_io_detail
