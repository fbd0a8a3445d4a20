// dsreg — Stanford PLY.
//
// Writing: binary_little_endian 1.0; element vertex with double x y z plus one float property
// per vertex scalar; element face with "list uchar int vertex_indices" plus float nx ny nz when
// the mesh has face normals, then one int property per face integer.
//
// Reading: ascii, binary_little_endian and binary_big_endian. Element "vertex" needs scalar
// properties x, y, z (any numeric type); its other scalar properties become vertex scalars of
// the same name, its list properties are skipped. Element "face" needs a list property
// "vertex_indices" (or "vertex_index") with integer count and index types, each face with 3 or 4
// indices; scalar properties nx, ny, nz (all three) become face_normals; other integer scalar
// properties become face integers; other properties are skipped. Other elements are skipped. The counts of the header are checked against the size of
// the file before anything is allocated. Bytes after the last element of a binary file are
// ignored; anything but white space after the last element of an ASCII file is an error.
#include <algorithm>
#include <array>
#include <cmath>

#include "dsreg/atomic_file.hpp"
#include "dsreg/error.hpp"
#include "mesh_format.hpp"

namespace dsreg::mesh_format {

namespace {

// ---- writing -----------------------------------------------------------------------------------

/// PLY names are single words: reject names the header could not hold or that clash with the
/// element's other properties (`names`: the reserved ones, x y z or nx ny nz vertex_indices).
template <class Named>
void check_property_names(const std::string& path, const char* what, const Named& properties, std::vector<std::string> names) {
    const std::string reserved = names.size() == 3 ? "x, y and z are the coordinates" : "nx, ny, nz and vertex_indices are taken";
    for (const auto& property : properties) {
        const std::string& name = property.first;
        const bool printable = std::all_of(name.begin(), name.end(), [](char c) { return c > ' ' && c < 127; });
        if (name.empty() || !printable) {
            throw Error(path + ": " + what + " name '" + name +
                        "' cannot be a PLY property name (it must be one word of printable ASCII)");
        }
        if (std::find(names.begin(), names.end(), name) != names.end()) {
            throw Error(path + ": " + what + " name '" + name + "' is used twice (" + reserved + ")");
        }
        names.push_back(name);
    }
}

void check_vertex_scalar_names(const std::string& path, const PolygonMesh& mesh) {
    check_property_names(path, "vertex scalar", mesh.vertex_scalars, {"x", "y", "z"});
    check_property_names(path, "face integer", mesh.face_integers, {"nx", "ny", "nz", "vertex_indices"});
}

void write_ply_header(OutputBuffer& buffer, const PolygonMesh& mesh) {
    buffer.append("ply\nformat binary_little_endian 1.0\ncomment written by dsreg\n");
    // 3D Slicer reads the coordinate system from the comments (vtkPLYReader::GetComments).
    if (!mesh.coordinate_system.empty()) buffer.append("comment " + coordinate_system_tag(mesh) + "\n");
    buffer.append("element vertex ");
    buffer.append_integer(mesh.vertices.rows());
    buffer.append("\nproperty double x\nproperty double y\nproperty double z\n");
    for (const auto& scalar : mesh.vertex_scalars) {
        buffer.append("property float ");
        buffer.append(scalar.first);
        buffer.append('\n');
    }
    buffer.append("element face ");
    buffer.append_integer(mesh.faces.rows());
    buffer.append("\nproperty list uchar int vertex_indices\n");
    if (mesh.face_normals.rows() > 0) buffer.append("property float nx\nproperty float ny\nproperty float nz\n");
    for (const auto& integer : mesh.face_integers) {
        buffer.append("property int ");
        buffer.append(integer.first);
        buffer.append('\n');
    }
    buffer.append("end_header\n");
}

void write_ply_vertices(OutputBuffer& buffer, const PolygonMesh& mesh) {
    for (Eigen::Index v = 0; v < mesh.vertices.rows(); ++v) {
        for (Eigen::Index c = 0; c < 3; ++c) buffer.append_little_endian(mesh.vertices(v, c));
        for (const auto& scalar : mesh.vertex_scalars)
            buffer.append_little_endian(static_cast<float>(scalar.second(v)));
    }
}

void write_ply_faces(OutputBuffer& buffer, const PolygonMesh& mesh) {
    const FaceMatrix& faces = mesh.faces;
    const bool with_normals = mesh.face_normals.rows() > 0;
    for (Eigen::Index f = 0; f < faces.rows(); ++f) {
        buffer.append_little_endian(static_cast<std::uint8_t>(faces.cols()));
        for (Eigen::Index k = 0; k < faces.cols(); ++k) buffer.append_little_endian(faces(f, k));
        if (with_normals)
            for (Eigen::Index c = 0; c < 3; ++c) buffer.append_little_endian(static_cast<float>(mesh.face_normals(f, c)));
        for (const auto& integer : mesh.face_integers) buffer.append_little_endian(static_cast<std::int32_t>(integer.second[f]));
    }
}

// ---- header ------------------------------------------------------------------------------------

enum class PlyEncoding { Ascii, BinaryLittleEndian, BinaryBigEndian };
enum class PlyType { Int8, UInt8, Int16, UInt16, Int32, UInt32, Float32, Float64 };

struct PlyProperty {
    std::string name;
    bool is_list = false;
    PlyType count_type = PlyType::UInt8;  ///< lists only
    PlyType value_type = PlyType::Float32;
};

struct PlyElement {
    std::string name;
    std::uint64_t count = 0;
    std::vector<PlyProperty> properties;
};

struct PlyHeader {
    PlyEncoding encoding = PlyEncoding::Ascii;
    std::vector<PlyElement> elements;
    std::size_t data_offset = 0;      ///< first byte after the end_header line
    std::size_t data_first_line = 0;  ///< line number of the first byte of data (ASCII)
};

std::size_t size_of(PlyType type) {
    switch (type) {
        case PlyType::Int8:
        case PlyType::UInt8:
            return 1;
        case PlyType::Int16:
        case PlyType::UInt16:
            return 2;
        case PlyType::Int32:
        case PlyType::UInt32:
        case PlyType::Float32:
            return 4;
        case PlyType::Float64:
            return 8;
    }
    return 0;
}

bool is_integer_type(PlyType type) { return type != PlyType::Float32 && type != PlyType::Float64; }

bool parse_ply_type(std::string_view name, PlyType& type) {
    struct NamedType {
        std::string_view name;
        PlyType type;
    };
    static constexpr std::array<NamedType, 16> names = {{
        {"char", PlyType::Int8},
        {"int8", PlyType::Int8},
        {"uchar", PlyType::UInt8},
        {"uint8", PlyType::UInt8},
        {"short", PlyType::Int16},
        {"int16", PlyType::Int16},
        {"ushort", PlyType::UInt16},
        {"uint16", PlyType::UInt16},
        {"int", PlyType::Int32},
        {"int32", PlyType::Int32},
        {"uint", PlyType::UInt32},
        {"uint32", PlyType::UInt32},
        {"float", PlyType::Float32},
        {"float32", PlyType::Float32},
        {"double", PlyType::Float64},
        {"float64", PlyType::Float64},
    }};
    for (const NamedType& entry : names) {
        if (entry.name == name) {
            type = entry.type;
            return true;
        }
    }
    return false;
}

/// Parses the header lines, from "ply" to "end_header".
class PlyHeaderParser {
public:
    PlyHeaderParser(const std::string& path, std::string_view content) : path_(path), lines_(content) {}

    PlyHeader parse() {
        std::string_view line;
        if (!lines_.next(line) || line != "ply") throw Error(path_ + ": not a PLY file (it does not start with 'ply')");
        bool has_format = false;
        while (true) {
            if (!lines_.next(line)) throw Error(path_ + ": the PLY header has no end_header line");
            split_words(line, words_);
            if (words_.empty() || words_[0] == "comment" || words_[0] == "obj_info") continue;
            if (words_[0] == "end_header" && words_.size() == 1) break;
            if (words_[0] == "format") {
                parse_format();
                has_format = true;
            } else if (words_[0] == "element") {
                parse_element();
            } else if (words_[0] == "property") {
                parse_property();
            } else {
                throw Error(here() + ": unexpected PLY header line '" + std::string(line) + "'");
            }
        }
        if (!has_format) throw Error(path_ + ": the PLY header has no format line");
        header_.data_offset = lines_.offset();
        header_.data_first_line = lines_.line_number() + 1;
        return std::move(header_);
    }

private:
    std::string here() const { return at_line(path_, lines_.line_number()); }

    void parse_format() {
        if (words_.size() != 3 || words_[2] != "1.0") throw Error(here() + ": expected 'format <encoding> 1.0'");
        if (words_[1] == "ascii") {
            header_.encoding = PlyEncoding::Ascii;
        } else if (words_[1] == "binary_little_endian") {
            header_.encoding = PlyEncoding::BinaryLittleEndian;
        } else if (words_[1] == "binary_big_endian") {
            header_.encoding = PlyEncoding::BinaryBigEndian;
        } else {
            throw Error(here() + ": unknown PLY encoding '" + std::string(words_[1]) + "'");
        }
    }

    void parse_element() {
        PlyElement element;
        if (words_.size() != 3 || !parse_unsigned(words_[2], element.count)) {
            throw Error(here() + ": expected 'element <name> <count>'");
        }
        element.name = checked_name("element", words_[1]);
        for (const PlyElement& other : header_.elements) {
            if (other.name == element.name) throw Error(here() + ": element '" + element.name + "' is declared twice");
        }
        header_.elements.push_back(std::move(element));
    }

    /// Element and property names are words of printable ASCII (so that a vertex scalar read
    /// from a PLY file can always be written to one again).
    std::string checked_name(const char* what, std::string_view name) const {
        if (std::all_of(name.begin(), name.end(), [](char c) { return c > ' ' && c < 127; })) return std::string(name);
        std::string shown;
        for (std::size_t i = 0; i < name.size() && i < 40; ++i) shown += (name[i] > ' ' && name[i] < 127) ? name[i] : '?';
        throw Error(here() + ": " + what + " name '" + shown + "' is not printable ASCII");
    }

    void parse_property() {
        if (header_.elements.empty()) throw Error(here() + ": property declared before any element");
        PlyProperty property;
        const bool is_list = words_.size() == 5 && words_[1] == "list";
        if (is_list) {
            property.is_list = true;
            property.count_type = parse_type(words_[2]);
            property.value_type = parse_type(words_[3]);
            if (!is_integer_type(property.count_type))
                throw Error(here() + ": the count of a list must have an integer type");
        } else if (words_.size() == 3) {
            property.value_type = parse_type(words_[1]);
        } else {
            throw Error(here() + ": expected 'property <type> <name>' or 'property list <type> <type> <name>'");
        }
        property.name = checked_name("property", words_.back());
        std::vector<PlyProperty>& properties = header_.elements.back().properties;
        for (const PlyProperty& other : properties) {
            if (other.name == property.name)
                throw Error(here() + ": property '" + property.name + "' is declared twice");
        }
        properties.push_back(std::move(property));
    }

    PlyType parse_type(std::string_view name) const {
        PlyType type = PlyType::UInt8;
        if (!parse_ply_type(name, type)) throw Error(here() + ": unknown PLY type '" + std::string(name) + "'");
        return type;
    }

    const std::string& path_;
    LineReader lines_;
    std::vector<std::string_view> words_;
    PlyHeader header_;
};

/// Fewest bytes one element can take: binary, its scalars and list counts (empty lists);
/// ASCII, one character per property.
std::uint64_t min_element_bytes(const PlyElement& element, PlyEncoding encoding) {
    if (encoding == PlyEncoding::Ascii) return element.properties.size();
    std::uint64_t bytes = 0;
    for (const PlyProperty& property : element.properties) {
        bytes += size_of(property.is_list ? property.count_type : property.value_type);
    }
    return bytes;
}

/// Rejects headers whose element counts cannot fit in the data that follows.
void check_counts_against_size(const std::string& path, const PlyHeader& header, std::uint64_t data_bytes) {
    std::uint64_t used = 0;
    for (const PlyElement& element : header.elements) {
        const std::uint64_t each = min_element_bytes(element, header.encoding);
        if (each == 0 && element.count > 0) throw Error(path + ": element '" + element.name + "' has no properties");
        check_count_fits(path, "'" + element.name + "' elements", element.count, each, data_bytes - used);
        used += element.count * each;
    }
}

// ---- what the reader takes from the elements ---------------------------------------------------

/// Role of each property of element "vertex": coordinate 0..2, vertex scalar, or skipped list.
struct VertexLayout {
    static constexpr int skipped = -1;
    static constexpr int first_scalar = 3;
    std::vector<int> roles;
    std::vector<std::string> scalar_names;
};

VertexLayout vertex_layout(const std::string& path, const PlyElement& element) {
    VertexLayout layout;
    std::array<bool, 3> found{false, false, false};
    for (const PlyProperty& property : element.properties) {
        const int axis = property.name == "x" ? 0 : property.name == "y" ? 1 : property.name == "z" ? 2 : -1;
        if (axis >= 0 && property.is_list) throw Error(path + ": vertex property '" + property.name + "' is a list");
        if (axis >= 0) {
            found[static_cast<std::size_t>(axis)] = true;
            layout.roles.push_back(axis);
        } else if (property.is_list) {
            layout.roles.push_back(VertexLayout::skipped);
        } else {
            layout.roles.push_back(VertexLayout::first_scalar + static_cast<int>(layout.scalar_names.size()));
            layout.scalar_names.push_back(property.name);
        }
    }
    for (int axis = 0; axis < 3; ++axis) {
        if (!found[static_cast<std::size_t>(axis)]) {
            throw Error(path + ": element 'vertex' has no property '" + std::string(1, char('x' + axis)) + "'");
        }
    }
    return layout;
}

/// Role of each property of element "face": the index list, a normal component, or skipped.
struct FaceLayout {
    static constexpr int skipped = -1;
    static constexpr int indices = 3;
    static constexpr int first_integer = 4;  ///< roles from here on: face integer (role − first_integer)
    std::vector<int> roles;  ///< 0..2 for nx, ny, nz
    bool with_normals = false;
    std::vector<std::string> integer_names;
};

FaceLayout face_layout(const std::string& path, const PlyElement& element) {
    FaceLayout layout;
    std::array<bool, 3> has_normal{false, false, false};
    bool has_indices = false;
    for (const PlyProperty& property : element.properties) {
        const std::string& name = property.name;
        const int axis = property.is_list ? -1 : name == "nx" ? 0 : name == "ny" ? 1 : name == "nz" ? 2 : -1;
        if (axis >= 0) has_normal[static_cast<std::size_t>(axis)] = true;
        const bool is_index_list =
            property.is_list && !has_indices && (name == "vertex_indices" || name == "vertex_index");
        if (is_index_list && !is_integer_type(property.value_type)) {
            throw Error(path + ": face property '" + name + "' must hold integers");
        }
        has_indices = has_indices || is_index_list;
        const bool index_name = name == "vertex_indices" || name == "vertex_index";
        if (!is_index_list && !index_name && axis < 0 && !property.is_list && is_integer_type(property.value_type)) {
            layout.roles.push_back(FaceLayout::first_integer + int(layout.integer_names.size()));
            layout.integer_names.push_back(name);
            continue;
        }
        layout.roles.push_back(is_index_list ? FaceLayout::indices : axis >= 0 ? axis : FaceLayout::skipped);
    }
    if (!has_indices) throw Error(path + ": element 'face' has no list property 'vertex_indices' or 'vertex_index'");
    layout.with_normals = has_normal[0] && has_normal[1] && has_normal[2];
    if (!layout.with_normals) {  // an incomplete normal is skipped like any other property
        const auto is_normal_component = [](int role) { return role >= 0 && role < 3; };
        std::replace_if(layout.roles.begin(), layout.roles.end(), is_normal_component, FaceLayout::skipped);
    }
    return layout;
}

// ---- data sources ------------------------------------------------------------------------------

/// Which element is being read, for messages.
struct DataPosition {
    const PlyElement* element = nullptr;
    std::uint64_t index = 0;

    std::string describe() const {
        if (element == nullptr) return "";
        return "element '" + element->name + "' " + std::to_string(index) + " (of " + std::to_string(element->count) +
               ")";
    }
};

/// Values of a binary PLY body, in either byte order, with bounds checks.
class BinarySource {
public:
    BinarySource(const std::string& path, std::string_view data, bool big_endian)
        : path_(path), data_(data), swap_(big_endian == host_is_little_endian()) {}

    DataPosition position;

    std::string where() const { return path_ + ": " + position.describe(); }

    double read_number(PlyType type) {
        switch (type) {
            case PlyType::Int8:
                return read<std::int8_t>();
            case PlyType::UInt8:
                return read<std::uint8_t>();
            case PlyType::Int16:
                return read<std::int16_t>();
            case PlyType::UInt16:
                return read<std::uint16_t>();
            case PlyType::Int32:
                return read<std::int32_t>();
            case PlyType::UInt32:
                return read<std::uint32_t>();
            case PlyType::Float32:
                return read<float>();
            case PlyType::Float64:
                return read<double>();
        }
        return 0.0;
    }

    /// `type` must be an integer type (checked by the header parser and the layouts).
    std::int64_t read_integer(PlyType type) {
        switch (type) {
            case PlyType::Int8:
                return read<std::int8_t>();
            case PlyType::UInt8:
                return read<std::uint8_t>();
            case PlyType::Int16:
                return read<std::int16_t>();
            case PlyType::UInt16:
                return read<std::uint16_t>();
            case PlyType::Int32:
                return read<std::int32_t>();
            case PlyType::UInt32:
                return read<std::uint32_t>();
            case PlyType::Float32:
            case PlyType::Float64:
                break;
        }
        throw Error(where() + ": expected an integer type");
    }

    void skip(PlyType type, std::uint64_t count) {
        const std::uint64_t bytes = count * size_of(type);  // count < 2^32, no overflow
        require(bytes);
        offset_ += static_cast<std::size_t>(bytes);
    }

    void check_end() const {}  // trailing bytes of a binary body are ignored

private:
    template <class T>
    T read() {
        require(sizeof(T));
        std::array<char, sizeof(T)> bytes;
        std::memcpy(bytes.data(), data_.data() + offset_, sizeof(T));
        if (swap_) std::reverse(bytes.begin(), bytes.end());
        offset_ += sizeof(T);
        T value;
        std::memcpy(&value, bytes.data(), sizeof(T));
        return value;
    }

    void require(std::uint64_t bytes) const {
        if (bytes <= data_.size() - offset_) return;
        throw Error(where() + ": the file is truncated (binary data ends in the middle of this element)");
    }

    const std::string& path_;
    std::string_view data_;
    std::size_t offset_ = 0;
    bool swap_;
};

/// Values of an ASCII PLY body: whitespace-separated numbers.
class AsciiSource {
public:
    AsciiSource(const std::string& path, std::string_view data, std::size_t first_line)
        : path_(path), tokens_(data, first_line) {}

    DataPosition position;

    std::string where() const { return at_line(path_, tokens_.line()) + ": " + position.describe(); }

    double read_number(PlyType) {
        const std::string_view token = next_token();
        double value = 0.0;
        if (!parse_double(token, value)) throw Error(where() + ": '" + std::string(token) + "' is not a number");
        return value;
    }

    std::int64_t read_integer(PlyType) {
        const std::string_view token = next_token();
        std::int64_t value = 0;
        if (!parse_integer(token, value)) throw Error(where() + ": '" + std::string(token) + "' is not an integer");
        return value;
    }

    void skip(PlyType type, std::uint64_t count) {
        for (std::uint64_t i = 0; i < count; ++i) read_number(type);
    }

    void check_end() {
        const std::string_view token = tokens_.next();
        if (!token.empty())
            throw Error(at_line(path_, tokens_.line()) + ": unexpected '" + std::string(token) +
                        "' after the last element");
    }

private:
    std::string_view next_token() {
        const std::string_view token = tokens_.next();
        if (token.empty()) throw Error(where() + ": the file ends in the middle of this element");
        return token;
    }

    const std::string& path_;
    TokenScanner tokens_;
};

// ---- body --------------------------------------------------------------------------------------

/// Reads the elements of a PLY body from a BinarySource or an AsciiSource.
template <class Source>
class PlyBodyReader {
public:
    PlyBodyReader(const std::string& path, const PlyHeader& header, Source& source)
        : path_(path), header_(header), source_(source) {}

    PolygonMesh read() {
        const PlyElement* vertex_element = find_element("vertex");
        if (vertex_element == nullptr) throw Error(path_ + ": the PLY file has no 'vertex' element");
        if (vertex_element->count > max_vertex_count)
            throw Error(path_ + ": too many vertices for 32-bit face indices");
        vertex_count_ = static_cast<std::int64_t>(vertex_element->count);
        const VertexLayout vertex_roles = vertex_layout(path_, *vertex_element);
        const PlyElement* face_element = find_element("face");
        const FaceLayout face_roles = face_element ? face_layout(path_, *face_element) : FaceLayout{};
        FaceList faces(face_roles.with_normals);

        for (const PlyElement& element : header_.elements) {
            if (&element == vertex_element) {
                read_vertices(element, vertex_roles);
            } else if (&element == face_element) {
                read_faces(element, face_roles, faces);
            } else {
                skip_element(element);
            }
        }
        source_.position = DataPosition{};
        source_.check_end();
        PolygonMesh mesh = make_mesh(std::move(vertices_), faces);
        mesh.vertex_scalars = std::move(scalars_);
        attach_face_integers(face_roles, faces, mesh);
        return mesh;
    }

private:
    const PlyElement* find_element(const std::string& name) const {
        for (const PlyElement& element : header_.elements) {
            if (element.name == name) return &element;
        }
        return nullptr;
    }

    void read_vertices(const PlyElement& element, const VertexLayout& layout) {
        vertices_.resize(vertex_count_, 3);
        for (const std::string& name : layout.scalar_names) scalars_.emplace_back(name, Eigen::VectorXd(vertex_count_));
        for (std::int64_t v = 0; v < vertex_count_; ++v) {
            source_.position = DataPosition{&element, static_cast<std::uint64_t>(v)};
            read_vertex(element, layout, v);
        }
    }

    void read_vertex(const PlyElement& element, const VertexLayout& layout, std::int64_t v) {
        for (std::size_t p = 0; p < element.properties.size(); ++p) {
            const PlyProperty& property = element.properties[p];
            const int role = layout.roles[p];
            if (role == VertexLayout::skipped) {
                skip_property(property);
            } else if (role < VertexLayout::first_scalar) {
                vertices_(v, role) = source_.read_number(property.value_type);
            } else {
                scalars_[static_cast<std::size_t>(role - VertexLayout::first_scalar)].second(v) =
                    source_.read_number(property.value_type);
            }
        }
        if (!vertices_.row(v).allFinite()) throw Error(source_.where() + ": vertex has a non-finite coordinate");
    }

    /// The face integers of the file, one row per mesh face (a split quad gives its value to
    /// both its triangles).
    void attach_face_integers(const FaceLayout& layout, const FaceList& faces, PolygonMesh& mesh) const {
        const std::size_t count = layout.integer_names.size();
        if (count == 0) return;
        const bool split = faces.triangle_count() > 0 && faces.quad_count() > 0;
        for (std::size_t i = 0; i < count; ++i) {
            Eigen::VectorXi values(mesh.faces.rows());
            Eigen::Index row = 0;
            for (std::size_t f = 0; f < faces.face_count(); ++f) {
                const int copies = split && faces.sizes()[f] == 4 ? 2 : 1;
                for (int c = 0; c < copies; ++c) values[row++] = integers_[f * count + i];
            }
            mesh.face_integers.emplace_back(layout.integer_names[i], std::move(values));
        }
    }

    void read_faces(const PlyElement& element, const FaceLayout& layout, FaceList& faces) {
        faces.reserve(static_cast<std::size_t>(element.count));
        integers_.reserve(static_cast<std::size_t>(element.count) * layout.integer_names.size());
        for (std::uint64_t f = 0; f < element.count; ++f) {
            source_.position = DataPosition{&element, f};
            read_face(element, layout, faces);
        }
    }

    void read_face(const PlyElement& element, const FaceLayout& layout, FaceList& faces) {
        std::array<std::int32_t, 4> indices{};
        std::array<double, 3> normal{};
        int size = 0;
        for (std::size_t p = 0; p < element.properties.size(); ++p) {
            const PlyProperty& property = element.properties[p];
            const int role = layout.roles[p];
            if (role == FaceLayout::indices) {
                size = read_index_list(property, indices);
            } else if (role == FaceLayout::skipped) {
                skip_property(property);
            } else if (role >= FaceLayout::first_integer) {
                const std::int64_t value = source_.read_integer(property.value_type);
                if (value < INT32_MIN || value > INT32_MAX)
                    throw Error(source_.where() + ": face property '" + property.name + "' does not fit a 32-bit integer");
                integers_.push_back(static_cast<std::int32_t>(value));
            } else {
                normal[static_cast<std::size_t>(role)] = source_.read_number(property.value_type);
            }
        }
        faces.add(indices.data(), size, normal.data());
    }

    /// Reads a face's index list into `indices`; returns its size (3 or 4).
    int read_index_list(const PlyProperty& property, std::array<std::int32_t, 4>& indices) {
        const std::int64_t size = source_.read_integer(property.count_type);
        if (size < 3 || size > 4) throw Error(source_.where() + ": " + unsupported_face_size(size));
        for (std::int64_t k = 0; k < size; ++k) {
            const std::int64_t index = source_.read_integer(property.value_type);
            if (index < 0 || index >= vertex_count_) {
                throw Error(source_.where() + ": " + face_index_out_of_range(index, vertex_count_));
            }
            indices[static_cast<std::size_t>(k)] = static_cast<std::int32_t>(index);
        }
        return static_cast<int>(size);
    }

    void skip_element(const PlyElement& element) {
        for (std::uint64_t i = 0; i < element.count; ++i) {
            source_.position = DataPosition{&element, i};
            for (const PlyProperty& property : element.properties) skip_property(property);
        }
    }

    void skip_property(const PlyProperty& property) {
        if (!property.is_list) return source_.skip(property.value_type, 1);
        const std::int64_t count = source_.read_integer(property.count_type);
        if (count < 0) throw Error(source_.where() + ": list property '" + property.name + "' has a negative length");
        source_.skip(property.value_type, static_cast<std::uint64_t>(count));
    }

    const std::string& path_;
    const PlyHeader& header_;
    Source& source_;
    std::int64_t vertex_count_ = 0;
    PointMatrix vertices_;
    std::vector<std::pair<std::string, Eigen::VectorXd>> scalars_;
    std::vector<std::int32_t> integers_;  ///< face integers, face-major
};

template <class Source>
PolygonMesh read_ply_body(const std::string& path, const PlyHeader& header, Source&& source) {
    return PlyBodyReader<std::remove_reference_t<Source>>(path, header, source).read();
}

}  // namespace

void write_ply(const std::string& path, const PolygonMesh& mesh) {
    check_vertex_scalar_names(path, mesh);
    write_file_atomically(path, [&](std::ostream& out) {
        OutputBuffer buffer(out);
        write_ply_header(buffer, mesh);
        write_ply_vertices(buffer, mesh);
        write_ply_faces(buffer, mesh);
        buffer.flush();
    });
}

PolygonMesh read_ply(const std::string& path, std::string_view content) {
    const PlyHeader header = PlyHeaderParser(path, content).parse();
    const std::string_view data = content.substr(header.data_offset);
    check_counts_against_size(path, header, data.size());
    switch (header.encoding) {
        case PlyEncoding::Ascii:
            return read_ply_body(path, header, AsciiSource(path, data, header.data_first_line));
        case PlyEncoding::BinaryLittleEndian:
            return read_ply_body(path, header, BinarySource(path, data, false));
        case PlyEncoding::BinaryBigEndian:
            return read_ply_body(path, header, BinarySource(path, data, true));
    }
    throw Error(path + ": unknown PLY encoding");  // not reached
}

}  // namespace dsreg::mesh_format
