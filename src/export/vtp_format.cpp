// dsreg — VTK XML PolyData (.vtp), 3D Slicer's other model format.
//
// Written: one Piece with Points (Float64), Polys (Int64 connectivity and offsets), CellData
// "u" (the face normals, when present), one Int32 CellData array per face integer (a label
// complex's inner_label/outer_label), one PointData array per vertex scalar, every array in
// the inline "binary" format (base64 of a UInt64 byte count followed by the values,
// little-endian), and, when the mesh has a coordinate system, the FieldData string array "SPACE"
// holding "LPS" or "RAS": where Slicer's vtkMRMLModelStorageNode writes it and looks for it.
// Read: what VTK's vtkXMLPolyDataWriter writes: ascii, inline binary and appended (raw or base64)
// arrays, UInt32 or UInt64 headers, uncompressed or vtkZLibDataCompressor blocks, little- or
// big-endian; one Piece; Verts and Lines skipped, Strips rejected; CellData Normals (or an array
// named "u") as face normals, other integer CellData arrays of one component as face integers;
// PointData arrays of one component as vertex scalars; FieldData
// "SPACE" as the coordinate system. Every size is checked against the file before allocating.
#include <zlib.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <map>

#include "dsreg/atomic_file.hpp"
#include "dsreg/error.hpp"
#include "mesh_format.hpp"

namespace dsreg::mesh_format {

namespace {

constexpr char kBase64Alphabet[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";

void append_base64(std::string& out, const std::uint8_t* data, std::size_t size) {
    for (std::size_t i = 0; i < size; i += 3) {
        const std::uint32_t a = data[i], b = i + 1 < size ? data[i + 1] : 0, c = i + 2 < size ? data[i + 2] : 0;
        const std::uint32_t triple = (a << 16) | (b << 8) | c;
        out.push_back(kBase64Alphabet[(triple >> 18) & 63]);
        out.push_back(kBase64Alphabet[(triple >> 12) & 63]);
        out.push_back(i + 1 < size ? kBase64Alphabet[(triple >> 6) & 63] : '=');
        out.push_back(i + 2 < size ? kBase64Alphabet[triple & 63] : '=');
    }
}

// ---- writing ----------------------------------------------------------------------------------

/// Little-endian bytes of `values` converted to T, preceded by their byte count (UInt64).
template <typename T, typename Values>
std::string binary_array(const Values& values, std::size_t count) {
    std::vector<std::uint8_t> bytes(8 + count * sizeof(T));
    const std::uint64_t size = count * sizeof(T);
    const bool little = host_is_little_endian();
    const auto put = [&](std::size_t at, const void* value, std::size_t width) {
        std::memcpy(bytes.data() + at, value, width);
        if (!little) std::reverse(bytes.begin() + static_cast<std::ptrdiff_t>(at), bytes.begin() + static_cast<std::ptrdiff_t>(at + width));
    };
    put(0, &size, 8);
    for (std::size_t i = 0; i < count; ++i) {
        const T value = static_cast<T>(values(i));
        put(8 + i * sizeof(T), &value, sizeof(T));
    }
    std::string text;
    append_base64(text, bytes.data(), bytes.size());
    return text;
}

void write_data_array(OutputBuffer& buffer, const char* type, const std::string& name, int components, const std::string& data) {
    buffer.append(std::string("        <DataArray type=\"") + type + "\" Name=\"" + name + "\" NumberOfComponents=\"" +
                  std::to_string(components) + "\" format=\"binary\">\n          ");
    buffer.append(data);
    buffer.append("\n        </DataArray>\n");
}

std::string xml_escaped(const std::string& text) {
    std::string out;
    for (const char c : text) {
        if (c == '&') out += "&amp;";
        else if (c == '<') out += "&lt;";
        else if (c == '>') out += "&gt;";
        else if (c == '"') out += "&quot;";
        else out.push_back(c);
    }
    return out;
}

void write_vtp_polydata(OutputBuffer& buffer, const PolygonMesh& mesh) {
    const Eigen::Index n = mesh.vertices.rows(), m = mesh.faces.rows(), k = m > 0 ? mesh.faces.cols() : 3;
    buffer.append("<?xml version=\"1.0\"?>\n<VTKFile type=\"PolyData\" version=\"1.0\" byte_order=\"LittleEndian\" "
                  "header_type=\"UInt64\">\n  <PolyData>\n");
    if (!mesh.coordinate_system.empty()) {
        // A vtkStringArray in ascii: the character codes, each string ended by 0.
        std::string codes;
        for (const unsigned char c : mesh.coordinate_system) codes += std::to_string(int(c)) + " ";
        buffer.append("    <FieldData>\n      <Array type=\"String\" Name=\"SPACE\" NumberOfTuples=\"1\" format=\"ascii\">\n        " +
                      codes + "0\n      </Array>\n    </FieldData>\n");
    }
    buffer.append("    <Piece NumberOfPoints=\"" + std::to_string(n) + "\" NumberOfVerts=\"0\" NumberOfLines=\"0\" "
                  "NumberOfStrips=\"0\" NumberOfPolys=\"" + std::to_string(m) + "\">\n");
    buffer.append("      <PointData>\n");
    for (const auto& scalar : mesh.vertex_scalars) {
        const Eigen::VectorXd& values = scalar.second;
        write_data_array(buffer, "Float64", xml_escaped(scalar.first), 1,
                         binary_array<double>([&](std::size_t i) { return values[static_cast<Eigen::Index>(i)]; }, std::size_t(n)));
    }
    buffer.append("      </PointData>\n      <CellData" + std::string(mesh.face_normals.rows() > 0 ? " Normals=\"u\"" : "") + ">\n");
    if (mesh.face_normals.rows() > 0)
        write_data_array(buffer, "Float64", "u", 3, binary_array<double>([&](std::size_t i) {
                             return mesh.face_normals(static_cast<Eigen::Index>(i / 3), static_cast<Eigen::Index>(i % 3));
                         }, std::size_t(3 * m)));
    for (const auto& integers : mesh.face_integers) {
        const auto& values = integers.second;  // not a structured binding: lambdas capture it (clang 14)
        write_data_array(buffer, "Int32", xml_escaped(integers.first), 1,
                         binary_array<std::int32_t>([&](std::size_t i) { return values[static_cast<Eigen::Index>(i)]; }, std::size_t(m)));
    }
    buffer.append("      </CellData>\n      <Points>\n");
    write_data_array(buffer, "Float64", "Points", 3, binary_array<double>([&](std::size_t i) {
                         return mesh.vertices(static_cast<Eigen::Index>(i / 3), static_cast<Eigen::Index>(i % 3));
                     }, std::size_t(3 * n)));
    buffer.append("      </Points>\n      <Polys>\n");
    write_data_array(buffer, "Int64", "connectivity", 1, binary_array<std::int64_t>([&](std::size_t i) {
                         return mesh.faces(static_cast<Eigen::Index>(i) / k, static_cast<Eigen::Index>(i) % k);
                     }, std::size_t(m * k)));
    write_data_array(buffer, "Int64", "offsets", 1,
                     binary_array<std::int64_t>([&](std::size_t i) { return std::int64_t(k) * std::int64_t(i + 1); }, std::size_t(m)));
    buffer.append("      </Polys>\n    </Piece>\n  </PolyData>\n</VTKFile>\n");
}

// ---- reading: a minimal XML scanner ---------------------------------------------------------------

struct XmlTag {
    std::string name;
    std::map<std::string, std::string> attributes;
    bool closing = false;       ///< </name>
    bool self_closing = false;  ///< <name ... />
    std::size_t end = 0;        ///< offset just after '>'
};

class XmlScanner {
public:
    XmlScanner(const std::string& path, std::string_view text) : path_(path), text_(text) {}

    /// The next tag at or after `position_`, skipping declarations and comments; false at the end.
    bool next(XmlTag& tag) {
        while (true) {
            const std::size_t open = text_.find('<', position_);
            if (open == std::string_view::npos) return false;
            if (text_.compare(open, 4, "<!--") == 0) {
                const std::size_t close = text_.find("-->", open + 4);
                if (close == std::string_view::npos) fail("unterminated XML comment");
                position_ = close + 3;
                continue;
            }
            if (text_.compare(open, 2, "<?") == 0 || text_.compare(open, 2, "<!") == 0) {
                const std::size_t close = text_.find('>', open);
                if (close == std::string_view::npos) fail("unterminated XML declaration");
                position_ = close + 1;
                continue;
            }
            parse_tag(open, tag);
            position_ = tag.end;
            return true;
        }
    }

    std::size_t position() const { return position_; }
    /// The text from `from` up to the next '<'.
    std::string_view text_until_tag(std::size_t from) const {
        const std::size_t open = text_.find('<', from);
        return text_.substr(from, (open == std::string_view::npos ? text_.size() : open) - from);
    }
    std::string_view text() const { return text_; }

    [[noreturn]] void fail(const std::string& problem) const { throw Error(path_ + ": " + problem); }

private:
    void parse_tag(std::size_t open, XmlTag& tag) {
        tag = XmlTag{};
        std::size_t i = open + 1;
        if (i < text_.size() && text_[i] == '/') {
            tag.closing = true;
            ++i;
        }
        const std::size_t name_start = i;
        while (i < text_.size() && !is_space(text_[i]) && text_[i] != '>' && text_[i] != '/') ++i;
        tag.name = std::string(text_.substr(name_start, i - name_start));
        if (tag.name.empty()) fail("malformed XML tag");
        while (true) {
            while (i < text_.size() && is_space(text_[i])) ++i;
            if (i >= text_.size()) fail("unterminated XML tag <" + tag.name.substr(0, 40) + ">");
            if (text_[i] == '>') {
                tag.end = i + 1;
                return;
            }
            if (text_[i] == '/' && i + 1 < text_.size() && text_[i + 1] == '>') {
                tag.self_closing = true;
                tag.end = i + 2;
                return;
            }
            const std::size_t key_start = i;
            while (i < text_.size() && text_[i] != '=' && !is_space(text_[i]) && text_[i] != '>') ++i;
            const std::string key(text_.substr(key_start, i - key_start));
            while (i < text_.size() && is_space(text_[i])) ++i;
            if (i >= text_.size() || text_[i] != '=') fail("XML attribute '" + key.substr(0, 40) + "' has no value");
            ++i;
            while (i < text_.size() && is_space(text_[i])) ++i;
            if (i >= text_.size() || (text_[i] != '"' && text_[i] != '\'')) fail("XML attribute value is not quoted");
            const char quote = text_[i++];
            const std::size_t close = text_.find(quote, i);
            if (close == std::string_view::npos) fail("unterminated XML attribute value");
            tag.attributes[key] = std::string(text_.substr(i, close - i));
            i = close + 1;
        }
    }

    const std::string& path_;
    std::string_view text_;
    std::size_t position_ = 0;
};

// ---- reading: data arrays ---------------------------------------------------------------------

int decode_base64_char(char c) {
    if (c >= 'A' && c <= 'Z') return c - 'A';
    if (c >= 'a' && c <= 'z') return c - 'a' + 26;
    if (c >= '0' && c <= '9') return c - '0' + 52;
    if (c == '+') return 62;
    if (c == '/') return 63;
    return -1;
}

/// Base64 text decoded in order, quartet by quartet: a padded quartet ends one encoded stream and
/// the next characters may start another (VTK encodes a compressed array's header and its data
/// separately), so reading on gives the concatenation of the streams. Whitespace is ignored.
class Base64Stream {
public:
    Base64Stream(const XmlScanner& xml, std::string_view text, std::size_t start) : xml_(xml), text_(text), cursor_(start) {}

    std::vector<std::uint8_t> read(std::uint64_t count) {
        if (count > text_.size()) xml_.fail("base64 data shorter than the sizes it announces");
        std::vector<std::uint8_t> out;
        out.reserve(static_cast<std::size_t>(count));
        while (out.size() < count) {
            if (pending_begin_ == pending_end_ && !decode_quartet()) xml_.fail("base64 data shorter than the sizes it announces");
            while (pending_begin_ < pending_end_ && out.size() < count) out.push_back(pending_[pending_begin_++]);
        }
        return out;
    }

private:
    bool decode_quartet() {
        int values[4];
        int filled = 0, padding = 0;
        while (filled < 4) {
            if (cursor_ >= text_.size() || text_[cursor_] == '<') return false;
            const char c = text_[cursor_++];
            if (is_space(c)) continue;
            if (c == '=') {
                values[filled++] = 0;
                ++padding;
                continue;
            }
            const int value = decode_base64_char(c);
            if (value < 0 || padding > 0) xml_.fail("invalid base64 data in a DataArray");
            values[filled++] = value;
        }
        if (padding > 2) xml_.fail("invalid base64 padding in a DataArray");
        const std::uint32_t triple = (std::uint32_t(values[0]) << 18) | (std::uint32_t(values[1]) << 12) |
                                     (std::uint32_t(values[2]) << 6) | std::uint32_t(values[3]);
        pending_[0] = static_cast<std::uint8_t>(triple >> 16);
        pending_[1] = static_cast<std::uint8_t>(triple >> 8);
        pending_[2] = static_cast<std::uint8_t>(triple);
        pending_begin_ = 0;
        pending_end_ = 3 - padding;
        return true;
    }

    const XmlScanner& xml_;
    std::string_view text_;
    std::size_t cursor_;
    std::uint8_t pending_[3] = {};
    int pending_begin_ = 0, pending_end_ = 0;
};

struct ArrayFormat {
    bool little_endian = true;
    int header_bytes = 4;  ///< UInt32 or UInt64 headers
    bool compressed = false;
};

std::size_t value_bytes(const XmlScanner& xml, const std::string& type) {
    static const std::pair<const char*, std::size_t> types[] = {
        {"Int8", 1},   {"UInt8", 1},   {"Int16", 2},   {"UInt16", 2},   {"Int32", 4},  {"UInt32", 4},
        {"Int64", 8},  {"UInt64", 8},  {"Float32", 4}, {"Float64", 8},  {"Char", 1},   {"String", 1},
    };
    for (const auto& [name, bytes] : types)
        if (type == name) return bytes;
    xml.fail("unsupported DataArray type '" + type.substr(0, 40) + "'");
}

double decode_value(const std::uint8_t* raw, const std::string& type, std::size_t bytes, bool little_endian) {
    std::uint8_t ordered[8];
    for (std::size_t b = 0; b < bytes; ++b) ordered[b] = raw[little_endian == host_is_little_endian() ? b : bytes - 1 - b];
    const auto as = [&](auto value) {
        std::memcpy(&value, ordered, sizeof value);
        return static_cast<double>(value);
    };
    if (type == "Float64") return as(double{});
    if (type == "Float32") return as(float{});
    if (type == "Int8" || type == "Char") return as(std::int8_t{});
    if (type == "UInt8" || type == "String") return as(std::uint8_t{});
    if (type == "Int16") return as(std::int16_t{});
    if (type == "UInt16") return as(std::uint16_t{});
    if (type == "Int32") return as(std::int32_t{});
    if (type == "UInt32") return as(std::uint32_t{});
    if (type == "Int64") return as(std::int64_t{});
    return as(std::uint64_t{});
}

/// Reads the array's raw (decompressed) bytes from binary data: `next(count)` gives the next
/// `count` bytes of the stored block (header, then the data or its compressed blocks).
template <typename Next>
std::vector<std::uint8_t> read_block(const XmlScanner& xml, const ArrayFormat& format, std::uint64_t max_bytes, Next&& next) {
    const auto header_word = [&](const std::vector<std::uint8_t>& bytes, std::size_t index) {
        std::uint64_t value = 0;
        for (int b = 0; b < format.header_bytes; ++b) {
            const std::size_t at = index * static_cast<std::size_t>(format.header_bytes) +
                                   static_cast<std::size_t>(format.little_endian ? b : format.header_bytes - 1 - b);
            value |= std::uint64_t(bytes[at]) << (8 * b);
        }
        return value;
    };
    if (!format.compressed) {
        const std::vector<std::uint8_t> header = next(static_cast<std::uint64_t>(format.header_bytes));
        const std::uint64_t size = header_word(header, 0);
        if (size > max_bytes) xml.fail("a DataArray announces " + std::to_string(size) + " bytes, more than the file can hold");
        return next(size);
    }
    std::vector<std::uint8_t> header = next(3 * static_cast<std::uint64_t>(format.header_bytes));
    const std::uint64_t blocks = header_word(header, 0), block_size = header_word(header, 1), last_size = header_word(header, 2);
    if (blocks > max_bytes || block_size > (std::uint64_t(1) << 32)) xml.fail("implausible compressed DataArray header");
    const std::vector<std::uint8_t> sizes = next(blocks * static_cast<std::uint64_t>(format.header_bytes));
    std::vector<std::uint64_t> compressed(static_cast<std::size_t>(blocks));
    std::uint64_t total_compressed = 0, total = 0;
    for (std::size_t b = 0; b < blocks; ++b) {
        compressed[b] = header_word(sizes, b);
        total_compressed += compressed[b];
        total += b + 1 == blocks && last_size != 0 ? last_size : block_size;
    }
    // Deflate cannot exceed 1032:1.
    if (total_compressed > max_bytes || total > 1032 * total_compressed + 1024 * blocks)
        xml.fail("a compressed DataArray announces more data than the file can hold");
    const std::vector<std::uint8_t> stored = next(total_compressed);
    std::vector<std::uint8_t> out(static_cast<std::size_t>(total));
    std::uint64_t in_at = 0, out_at = 0;
    for (std::size_t b = 0; b < blocks; ++b) {
        uLongf produced = static_cast<uLongf>(b + 1 == blocks && last_size != 0 ? last_size : block_size);
        const uLongf expected = produced;
        if (uncompress(out.data() + out_at, &produced, stored.data() + in_at, static_cast<uLong>(compressed[b])) != Z_OK ||
            produced != expected)
            xml.fail("corrupt zlib block in a compressed DataArray");
        in_at += compressed[b];
        out_at += produced;
    }
    return out;
}

class VtpParser {
public:
    VtpParser(const std::string& path, std::string_view content) : xml_(path, content), content_(content) {}

    PolygonMesh parse() {
        XmlTag tag;
        if (!xml_.next(tag) || tag.name != "VTKFile") xml_.fail("not a VTK XML file (no <VTKFile> element)");
        if (tag.attributes["type"] != "PolyData") xml_.fail("the VTK XML file holds " + tag.attributes["type"].substr(0, 40) + ", not PolyData");
        format_.little_endian = tag.attributes["byte_order"] != "BigEndian";
        format_.header_bytes = tag.attributes["header_type"] == "UInt64" ? 8 : 4;
        const std::string compressor = tag.attributes["compressor"];
        if (!compressor.empty() && compressor != "vtkZLibDataCompressor")
            xml_.fail("compressor " + compressor.substr(0, 40) + " is not supported (vtkZLibDataCompressor is)");
        format_.compressed = !compressor.empty();
        locate_appended_data();
        collect_arrays();
        return build_mesh();
    }

private:
    struct Array {
        std::string section;  ///< "Points", "Polys", "CellData", "PointData", "FieldData", ...
        std::map<std::string, std::string> attributes;
        std::size_t text_start = 0;  ///< inline data: offset of the element's text
    };

    /// AppendedData holds raw bytes, which may look like tags: find it first and scan only before it.
    void locate_appended_data() {
        const std::size_t at = content_.find("<AppendedData");
        if (at == std::string_view::npos) return;
        const std::size_t close = content_.find('>', at);
        const std::size_t underscore = close == std::string_view::npos ? close : content_.find('_', close);
        if (underscore == std::string_view::npos) xml_.fail("malformed AppendedData element");
        const std::string element(content_.substr(at, close - at));
        appended_raw_ = element.find("\"raw\"") != std::string::npos;
        appended_start_ = underscore + 1;
        scan_end_ = at;
    }

    void collect_arrays() {
        std::vector<std::string> open;
        XmlTag tag;
        cell_normals_ = "Normals";
        int pieces = 0;
        while (xml_.position() < scan_end_ && xml_.next(tag)) {
            if (tag.closing) {
                if (!open.empty()) open.pop_back();
                continue;
            }
            if (tag.name == "Piece") {
                if (++pieces > 1) xml_.fail("more than one Piece is not supported");
                piece_ = tag.attributes;
            }
            if (tag.name == "CellData" && tag.attributes.count("Normals")) cell_normals_ = tag.attributes["Normals"];
            if (tag.name == "DataArray" || tag.name == "Array") {
                Array array;
                array.section = open.empty() ? "" : open.back();
                array.attributes = tag.attributes;
                array.text_start = tag.end;
                arrays_.push_back(array);
            }
            if (!tag.self_closing) open.push_back(tag.name);
        }
        if (pieces == 0) xml_.fail("no Piece element");
    }

    std::uint64_t piece_count(const char* name) {
        const std::string& text = piece_[name];
        if (text.empty()) return 0;
        std::uint64_t value = 0;
        if (!parse_unsigned(text, value)) xml_.fail(std::string("Piece attribute ") + name + " is not a count");
        return value;
    }

    /// The values of an array as doubles.
    std::vector<double> values(const Array& array) {
        const auto attribute = [&](const char* name) {
            const auto found = array.attributes.find(name);
            return found == array.attributes.end() ? std::string() : found->second;
        };
        const std::string type = attribute("type");
        const std::size_t bytes = value_bytes(xml_, type);
        const std::string format = attribute("format");
        std::vector<double> out;
        if (format == "ascii") {
            TokenScanner tokens(xml_.text_until_tag(array.text_start), 1);
            for (std::string_view token = tokens.next(); !token.empty(); token = tokens.next()) {
                double value = 0;
                if (!parse_double(token, value)) xml_.fail("'" + std::string(token.substr(0, 40)) + "' is not a number in a DataArray");
                out.push_back(value);
            }
            return out;
        }
        std::vector<std::uint8_t> raw;
        const std::uint64_t max_bytes = content_.size();
        if (format == "binary") {
            Base64Stream stream(xml_, content_, array.text_start);
            raw = read_block(xml_, format_, max_bytes, [&](std::uint64_t count) { return stream.read(count); });
        } else if (format == "appended") {
            std::uint64_t offset = 0;
            if (!parse_unsigned(attribute("offset"), offset)) xml_.fail("appended DataArray without a valid offset");
            if (appended_start_ == std::string_view::npos || offset > content_.size() - appended_start_)
                xml_.fail("appended DataArray offset beyond the AppendedData");
            const auto at = static_cast<std::size_t>(appended_start_ + offset);
            if (appended_raw_) {
                std::size_t cursor = at;
                raw = read_block(xml_, format_, max_bytes, [&](std::uint64_t count) {
                    if (count > content_.size() - cursor) xml_.fail("appended data shorter than the sizes it announces");
                    std::vector<std::uint8_t> block(content_.begin() + static_cast<std::ptrdiff_t>(cursor),
                                                    content_.begin() + static_cast<std::ptrdiff_t>(cursor + count));
                    cursor += static_cast<std::size_t>(count);
                    return block;
                });
            } else {
                Base64Stream stream(xml_, content_, at);
                raw = read_block(xml_, format_, max_bytes, [&](std::uint64_t count) { return stream.read(count); });
            }
        } else {
            xml_.fail("DataArray format '" + format.substr(0, 40) + "' is not supported");
        }
        if (raw.size() % bytes != 0) xml_.fail("DataArray byte count is not a multiple of its value size");
        out.resize(raw.size() / bytes);
        for (std::size_t i = 0; i < out.size(); ++i) out[i] = decode_value(raw.data() + i * bytes, type, bytes, format_.little_endian);
        return out;
    }

    /// A named array of one integer component per tuple (a face property when in CellData).
    static bool is_integer_array(const Array& array) {
        const auto name = array.attributes.find("Name"), type = array.attributes.find("type");
        const auto components = array.attributes.find("NumberOfComponents");
        if (name == array.attributes.end() || type == array.attributes.end()) return false;
        if (components != array.attributes.end() && components->second != "1") return false;
        static const char* const integer_types[] = {"Int8", "UInt8", "Int16", "UInt16", "Int32", "UInt32", "Int64", "UInt64"};
        for (const char* integer : integer_types)
            if (type->second == integer) return true;
        return false;
    }

    const Array* find(const std::string& section, const std::string& name) const {
        for (const Array& array : arrays_) {
            const auto found = array.attributes.find("Name");
            if (array.section == section && found != array.attributes.end() && found->second == name) return &array;
        }
        return nullptr;
    }

    PolygonMesh build_mesh() {
        const std::uint64_t point_count = piece_count("NumberOfPoints"), poly_count = piece_count("NumberOfPolys");
        if (piece_count("NumberOfStrips") > 0) xml_.fail("triangle strips are not supported (triangulate the mesh first)");
        if (point_count > max_vertex_count) xml_.fail("too many vertices for 32-bit face indices");

        const Array* points = nullptr;
        for (const Array& array : arrays_)
            if (array.section == "Points") points = &array;
        if (points == nullptr) xml_.fail("no Points array");
        const std::vector<double> coordinates = values(*points);
        if (coordinates.size() != 3 * point_count) xml_.fail("the Points array does not hold 3 coordinates per point");
        for (const double x : coordinates)
            if (!std::isfinite(x)) xml_.fail("vertex has a non-finite coordinate");

        FaceList faces(false);
        std::vector<double> normals;
        const Array* connectivity = find("Polys", "connectivity");
        const Array* offsets = find("Polys", "offsets");
        if (poly_count > 0 && (connectivity == nullptr || offsets == nullptr)) xml_.fail("Polys without connectivity and offsets");
        std::vector<double> indices, ends;
        if (poly_count > 0) {
            indices = values(*connectivity);
            ends = values(*offsets);
            if (ends.size() != poly_count) xml_.fail("the offsets array does not hold one offset per polygon");
        }
        const Array* normal_array = nullptr;
        for (const Array& array : arrays_) {
            if (array.section != "CellData") continue;
            const auto name = array.attributes.find("Name");
            if (name != array.attributes.end() && (name->second == cell_normals_ || name->second == "u")) normal_array = &array;
        }
        if (normal_array != nullptr) {
            normals = values(*normal_array);
            if (normals.size() != 3 * poly_count) normals.clear();
        }
        FaceList list(!normals.empty());
        list.reserve(static_cast<std::size_t>(poly_count));
        double begin = 0;
        for (std::size_t f = 0; f < ends.size(); ++f) {
            const double end = ends[f];
            if (!(end >= begin && end <= double(indices.size())) || end != std::floor(end)) xml_.fail("polygon offsets out of range");
            const auto size = static_cast<std::size_t>(end - begin);
            if (size != 3 && size != 4) xml_.fail(unsupported_face_size(static_cast<std::int64_t>(size)));
            std::int32_t face[4];
            for (std::size_t k = 0; k < size; ++k) {
                const double index = indices[static_cast<std::size_t>(begin) + k];
                if (!(index >= 0 && index < double(point_count)) || index != std::floor(index))
                    xml_.fail(face_index_out_of_range(static_cast<std::int64_t>(index), static_cast<std::int64_t>(point_count)));
                face[k] = static_cast<std::int32_t>(index);
            }
            list.add(face, static_cast<int>(size), normals.empty() ? nullptr : normals.data() + 3 * f);
            begin = end;
        }
        PolygonMesh mesh = make_mesh(to_point_matrix(coordinates), list);
        for (const Array& array : arrays_) {
            if (array.section != "PointData") continue;
            const auto name = array.attributes.find("Name");
            const auto components = array.attributes.find("NumberOfComponents");
            if (name == array.attributes.end() || (components != array.attributes.end() && components->second != "1")) continue;
            const std::vector<double> scalar = values(array);
            if (scalar.size() != point_count) continue;
            mesh.vertex_scalars.emplace_back(name->second, Eigen::Map<const Eigen::VectorXd>(scalar.data(), Eigen::Index(point_count)));
        }
        for (const Array& array : arrays_) {
            if (array.section != "CellData" || &array == normal_array || !is_integer_array(array)) continue;
            const std::vector<double> integers = values(array);
            if (integers.size() != poly_count) continue;
            Eigen::VectorXi face_values(static_cast<Eigen::Index>(poly_count));
            for (std::size_t f = 0; f < integers.size(); ++f) {
                if (!(integers[f] >= INT32_MIN && integers[f] <= INT32_MAX)) xml_.fail("a CellData integer does not fit 32 bits");
                face_values[static_cast<Eigen::Index>(f)] = static_cast<int>(integers[f]);
            }
            mesh.face_integers.emplace_back(array.attributes.at("Name"), std::move(face_values));
        }
        if (const Array* space = find("FieldData", "SPACE")) {
            std::string text;
            for (const double code : values(*space)) {
                if (code == 0) break;
                if (code > 0 && code < 128) text.push_back(static_cast<char>(code));
            }
            // Slicer's rule: "RAS" anywhere in the value, else "LPS".
            mesh.coordinate_system = text.find("RAS") != std::string::npos ? "RAS" : text.find("LPS") != std::string::npos ? "LPS" : "";
        }
        return mesh;
    }

    XmlScanner xml_;
    std::string_view content_;
    ArrayFormat format_;
    std::map<std::string, std::string> piece_;
    std::vector<Array> arrays_;
    std::size_t scan_end_ = std::string_view::npos;
    std::size_t appended_start_ = std::string_view::npos;
    bool appended_raw_ = false;
    std::string cell_normals_ = "Normals";  ///< the CellData element's Normals attribute
};

}  // namespace

void write_vtp(const std::string& path, const PolygonMesh& mesh) {
    write_file_atomically(path, [&](std::ostream& out) {
        OutputBuffer buffer(out);
        write_vtp_polydata(buffer, mesh);
        buffer.flush();
    });
}

PolygonMesh read_vtp(const std::string& path, std::string_view content) { return VtpParser(path, content).parse(); }

}  // namespace dsreg::mesh_format
