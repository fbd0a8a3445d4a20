// dsreg — VTK legacy PolyData (.vtk), as 3D Slicer writes and reads its models.
//
// Written: "# vtk DataFile Version 4.2" (the version Slicer writes, for the widest
// compatibility), the header line "dsreg output. SPACE=LPS" (Slicer's vtkMRMLModelStorageNode
// looks for "SPACE=RAS" / "SPACE=LPS" in this line), BINARY (big-endian), POINTS as double,
// POLYGONS as counts and indices; CELL_DATA NORMALS "u" when the mesh has face normals, the face
// integers (a label complex's inner_label/outer_label) as int arrays of a CELL_DATA FIELD, and one
// POINT_DATA SCALARS array per vertex scalar.
// Read: ASCII or BINARY, POINTS of any numeric type, POLYGONS in the 4.2 layout (count then
// indices per cell) and the 5.1 layout (OFFSETS and CONNECTIVITY arrays), VERTICES and LINES
// skipped, CELL_DATA NORMALS as face normals, integer CELL_DATA FIELD arrays of one component as
// face integers, POINT_DATA SCALARS of one component as vertex scalars; other attribute arrays (VECTORS, TEXTURE_COORDINATES, FIELD, ...) are skipped. Every
// count is checked against the size of the file before memory is allocated for it.
#include <cmath>
#include <cstdint>
#include <cstring>

#include "dsreg/atomic_file.hpp"
#include "dsreg/error.hpp"
#include "dsreg/text.hpp"
#include "mesh_format.hpp"

namespace dsreg::mesh_format {

namespace {

// ---- writing ----------------------------------------------------------------------------------

template <class T>
void append_big_endian(OutputBuffer& buffer, T value) {
    unsigned char bytes[sizeof(T)];
    std::memcpy(bytes, &value, sizeof(T));
    if (host_is_little_endian())
        for (std::size_t i = 0; i < sizeof(T) / 2; ++i) std::swap(bytes[i], bytes[sizeof(T) - 1 - i]);
    buffer.append(std::string_view(reinterpret_cast<const char*>(bytes), sizeof(T)));
}

void write_vtk_polydata(OutputBuffer& buffer, const PolygonMesh& mesh) {
    const std::string space = mesh.coordinate_system.empty() ? "" : " SPACE=" + mesh.coordinate_system;
    buffer.append("# vtk DataFile Version 4.2\ndsreg output." + space + "\nBINARY\nDATASET POLYDATA\nPOINTS ");
    buffer.append_integer(mesh.vertices.rows());
    buffer.append(" double\n");
    for (Eigen::Index v = 0; v < mesh.vertices.rows(); ++v)
        for (int a = 0; a < 3; ++a) append_big_endian(buffer, mesh.vertices(v, a));
    buffer.append("\nPOLYGONS ");
    buffer.append_integer(mesh.faces.rows());
    buffer.append(' ');
    buffer.append_integer(mesh.faces.rows() * (mesh.faces.cols() + 1));
    buffer.append('\n');
    for (Eigen::Index f = 0; f < mesh.faces.rows(); ++f) {
        append_big_endian(buffer, static_cast<std::int32_t>(mesh.faces.cols()));
        for (Eigen::Index k = 0; k < mesh.faces.cols(); ++k) append_big_endian(buffer, mesh.faces(f, k));
    }
    buffer.append('\n');
    if (mesh.face_normals.rows() > 0 || !mesh.face_integers.empty()) {
        buffer.append("CELL_DATA ");
        buffer.append_integer(mesh.faces.rows());
        buffer.append('\n');
    }
    if (mesh.face_normals.rows() > 0) {
        buffer.append("NORMALS u double\n");
        for (Eigen::Index f = 0; f < mesh.face_normals.rows(); ++f)
            for (int a = 0; a < 3; ++a) append_big_endian(buffer, mesh.face_normals(f, a));
        buffer.append('\n');
    }
    if (!mesh.face_integers.empty()) {
        // A FIELD block: VTK's legacy reader keeps every array of it (of several SCALARS it keeps
        // only the first unless asked), so 3D Slicer shows each as a cell scalar.
        buffer.append("FIELD FieldData ");
        buffer.append_integer(static_cast<std::int64_t>(mesh.face_integers.size()));
        buffer.append('\n');
        for (const auto& [name, values] : mesh.face_integers) {
            buffer.append(name + " 1 ");
            buffer.append_integer(values.size());
            buffer.append(" int\n");
            for (Eigen::Index f = 0; f < values.size(); ++f) append_big_endian(buffer, static_cast<std::int32_t>(values[f]));
            buffer.append('\n');
        }
    }
    if (!mesh.vertex_scalars.empty()) {
        buffer.append("POINT_DATA ");
        buffer.append_integer(mesh.vertices.rows());
        buffer.append('\n');
        for (const auto& [name, values] : mesh.vertex_scalars) {
            buffer.append("SCALARS " + name + " double 1\nLOOKUP_TABLE default\n");
            for (Eigen::Index v = 0; v < values.size(); ++v) append_big_endian(buffer, values[v]);
            buffer.append('\n');
        }
    }
}

// ---- reading ----------------------------------------------------------------------------------

/// The bytes of one value of a VTK legacy data type, or 0 for an unknown type.
std::size_t type_bytes(std::string_view type) {
    static const std::pair<std::string_view, std::size_t> types[] = {
        {"bit", 0},   {"unsigned_char", 1}, {"char", 1},          {"unsigned_short", 2}, {"short", 2},
        {"unsigned_int", 4}, {"int", 4},     {"unsigned_long", 8}, {"long", 8},           {"float", 4},
        {"double", 8}, {"vtkidtype", 8},     {"vtktypeint64", 8},  {"vtktypeuint64", 8},  {"vtktypeint32", 4},
        {"vtktypeuint32", 4},
    };
    std::string lower(type);
    for (char& c : lower) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    for (const auto& [name, bytes] : types)
        if (lower == name) return bytes;
    return 0;
}

bool is_float_type(std::string_view type) { return equals_keyword(type, "float") || equals_keyword(type, "double"); }
bool is_unsigned_type(std::string_view type) {
    std::string lower(type);
    for (char& c : lower) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    return lower.rfind("unsigned", 0) == 0 || lower == "vtktypeuint64" || lower == "vtktypeuint32";
}

/// Reads the sections of a legacy file: keyword lines, and values (ASCII tokens or big-endian
/// binary) in between.
class VtkParser {
public:
    VtkParser(const std::string& path, std::string_view content) : path_(path), content_(content) {}

    PolygonMesh parse() {
        const std::string_view magic = line();
        if (magic.rfind("# vtk DataFile Version", 0) != 0) fail("not a VTK legacy file (no '# vtk DataFile Version' line)");
        header_ = std::string(line());
        const std::string_view mode = trimmed(line());
        if (equals_keyword(mode, "binary"))
            binary_ = true;
        else if (!equals_keyword(mode, "ascii"))
            fail("the third line must be ASCII or BINARY, not '" + std::string(mode.substr(0, 40)) + "'");
        std::vector<std::string_view> words = keyword_line();
        if (words.size() != 2 || !equals_keyword(words[0], "dataset"))
            fail("expected 'DATASET POLYDATA'");
        if (!equals_keyword(words[1], "polydata"))
            fail("the dataset is " + std::string(words[1]) + ", not POLYDATA (a mesh)");
        while (true) {
            words = keyword_line();
            if (words.empty()) break;
            section(words);
        }
        if (!has_points_) fail("no POINTS section");
        PolygonMesh mesh = make_mesh(to_point_matrix(coordinates_), faces_);
        mesh.vertex_scalars = std::move(scalars_);
        mesh.face_integers = std::move(face_integers_);
        return mesh;
    }

    const std::string& header() const { return header_; }

private:
    [[noreturn]] void fail(const std::string& problem) const { throw Error(path_ + ": " + problem); }

    /// Next line (without '\n' or '\r'); empty at the end.
    std::string_view line() {
        if (position_ >= content_.size()) return {};
        const std::size_t end = content_.find('\n', position_);
        const std::size_t stop = end == std::string_view::npos ? content_.size() : end;
        std::string_view text = content_.substr(position_, stop - position_);
        position_ = stop == content_.size() ? stop : stop + 1;
        if (!text.empty() && text.back() == '\r') text.remove_suffix(1);
        return text;
    }

    static std::string_view trimmed(std::string_view text) {
        while (!text.empty() && is_space(text.front())) text.remove_prefix(1);
        while (!text.empty() && is_space(text.back())) text.remove_suffix(1);
        return text;
    }

    /// The words of the next non-blank line; empty at the end of the file.
    std::vector<std::string_view> keyword_line() {
        std::vector<std::string_view> words;
        while (words.empty() && position_ < content_.size()) split_words(line(), words);
        return words;
    }

    std::uint64_t count_word(const std::vector<std::string_view>& words, std::size_t index, const char* what) const {
        std::uint64_t value = 0;
        if (index >= words.size() || !parse_unsigned(words[index], value)) fail(std::string("expected ") + what);
        return value;
    }

    /// Reads `count` values of `type` as doubles (ASCII tokens, or binary big-endian).
    void read_values(std::uint64_t count, std::string_view type, std::vector<double>& out) {
        const std::size_t bytes = type_bytes(type);
        if (bytes == 0) fail("unsupported data type '" + std::string(type.substr(0, 40)) + "'");
        const std::uint64_t available = content_.size() - position_;
        check_count_fits(path_, "values", count, binary_ ? bytes : 2, available + 1);
        out.resize(static_cast<std::size_t>(count));
        if (binary_) {
            const bool floating = is_float_type(type), is_unsigned = is_unsigned_type(type);
            for (std::uint64_t i = 0; i < count; ++i) {
                unsigned char raw[8];
                std::memcpy(raw, content_.data() + position_, bytes);
                position_ += bytes;
                std::uint64_t bits = 0;
                for (std::size_t b = 0; b < bytes; ++b) bits = (bits << 8) | raw[b];
                out[i] = decode(bits, bytes, floating, is_unsigned);
            }
            return;
        }
        TokenScanner tokens(content_.substr(position_), 1);
        std::size_t consumed = 0;
        for (std::uint64_t i = 0; i < count; ++i) {
            const std::string_view token = tokens.next();
            if (token.empty()) fail("the file ends inside a list of " + std::to_string(count) + " values");
            if (!parse_double(token, out[i])) fail("'" + std::string(token.substr(0, 40)) + "' is not a number");
            consumed = static_cast<std::size_t>(token.data() + token.size() - content_.data()) - position_;
        }
        position_ += consumed;
    }

    static double decode(std::uint64_t bits, std::size_t bytes, bool floating, bool is_unsigned) {
        if (floating) {
            if (bytes == 4) {
                const auto narrow = static_cast<std::uint32_t>(bits);
                float value;
                std::memcpy(&value, &narrow, 4);
                return value;
            }
            double value;
            std::memcpy(&value, &bits, 8);
            return value;
        }
        if (is_unsigned || bytes == 8) {
            if (!is_unsigned) {
                std::int64_t value;
                std::memcpy(&value, &bits, 8);
                return static_cast<double>(value);
            }
            return static_cast<double>(bits);
        }
        const std::uint64_t sign = std::uint64_t(1) << (8 * bytes - 1);
        return static_cast<double>(static_cast<std::int64_t>(bits ^ sign) - static_cast<std::int64_t>(sign));
    }

    void section(const std::vector<std::string_view>& words) {
        const std::string_view keyword = words[0];
        if (equals_keyword(keyword, "points")) return points(words);
        if (equals_keyword(keyword, "polygons")) return polygons(words);
        if (equals_keyword(keyword, "vertices") || equals_keyword(keyword, "lines")) return skip_cells(words);
        if (equals_keyword(keyword, "triangle_strips")) fail("triangle strips are not supported (triangulate the mesh first)");
        if (equals_keyword(keyword, "cell_data")) return attribute_block(count_word(words, 1, "a cell count"), true);
        if (equals_keyword(keyword, "point_data")) {
            const std::uint64_t count = count_word(words, 1, "a point count");
            if (!has_points_) fail("POINT_DATA before POINTS is not supported");
            if (count != coordinates_.size() / 3) fail("POINT_DATA count differs from the number of points");
            return attribute_block(count, false);
        }
        if (equals_keyword(keyword, "metadata")) return skip_metadata();
        if (equals_keyword(keyword, "field")) return skip_field(words);
        fail("unexpected section '" + std::string(keyword.substr(0, 40)) + "'");
    }

    void points(const std::vector<std::string_view>& words) {
        if (has_points_) fail("two POINTS sections");
        const std::uint64_t count = count_word(words, 1, "a point count after POINTS");
        if (words.size() < 3) fail("POINTS needs a data type");
        if (count > max_vertex_count) fail("too many vertices for 32-bit face indices");
        read_values(3 * count, words[2], coordinates_);
        for (const double x : coordinates_)
            if (!std::isfinite(x)) fail("vertex has a non-finite coordinate");
        has_points_ = true;
    }

    /// 4.2 layout "POLYGONS n size" then n × (k, i1..ik); 5.1 layout "POLYGONS n+1 m" then the
    /// OFFSETS and CONNECTIVITY arrays.
    void polygons(const std::vector<std::string_view>& words) {
        const std::uint64_t first = count_word(words, 1, "a cell count after POLYGONS");
        const std::uint64_t second = count_word(words, 2, "a size after POLYGONS");
        const std::size_t save = position_;
        std::vector<std::string_view> next = keyword_line();
        if (!next.empty() && equals_keyword(next[0], "offsets")) {
            if (next.size() < 2) fail("OFFSETS needs a data type");
            std::vector<double> offsets, connectivity;
            read_values(first, next[1], offsets);
            next = keyword_line();
            if (next.size() < 2 || !equals_keyword(next[0], "connectivity")) fail("expected CONNECTIVITY after OFFSETS");
            read_values(second, next[1], connectivity);
            for (std::size_t c = 0; c + 1 < offsets.size(); ++c) {
                const double begin = offsets[c], end = offsets[c + 1];
                if (!(begin >= 0 && end >= begin && end <= double(connectivity.size())))
                    fail("cell offsets out of range");
                add_face(connectivity.data() + static_cast<std::size_t>(begin), static_cast<std::size_t>(end - begin));
            }
            return;
        }
        position_ = save;
        std::vector<double> cells;
        read_values(second, "int", cells);
        std::size_t at = 0;
        for (std::uint64_t c = 0; c < first; ++c) {
            if (at >= cells.size()) fail("POLYGONS holds fewer cells than announced");
            const double size = cells[at++];
            // Compared as a double first: a size beyond any integer made the cast undefined (found by fuzzing).
            if (!(size >= 0) || size > double(cells.size() - at)) fail("polygon size out of range");
            add_face(cells.data() + at, static_cast<std::size_t>(size));
            at += static_cast<std::size_t>(size);
        }
        if (at != cells.size()) fail("POLYGONS size does not match its cells");
    }

    void add_face(const double* indices, std::size_t size) {
        // Checked first: once normals are read, the faces carry them and a face without one
        // cannot be added (a second POLYGONS after CELL_DATA, found by fuzzing).
        if (face_normal_count_ > 0) fail("CELL_DATA before POLYGONS is not supported");
        if (size != 3 && size != 4) fail(unsupported_face_size(static_cast<std::int64_t>(size)));
        std::int32_t face[4];
        const auto vertex_count = static_cast<std::int64_t>(coordinates_.size() / 3);
        for (std::size_t k = 0; k < size; ++k) {
            const double index = indices[k];
            if (!(index >= 0 && index < double(vertex_count)) || index != std::floor(index)) {
                // Doubles beyond the 64-bit integers (or NaN) cannot be converted: named as read.
                if (!(std::abs(index) < 9e18)) fail("face refers to vertex " + format("%g", index) + ", not a vertex index");
                fail(face_index_out_of_range(static_cast<std::int64_t>(index), vertex_count));
            }
            face[k] = static_cast<std::int32_t>(index);
        }
        faces_.add(face, static_cast<int>(size));
    }

    void skip_cells(const std::vector<std::string_view>& words) {
        const std::uint64_t first = count_word(words, 1, "a cell count");
        const std::uint64_t second = count_word(words, 2, "a size");
        const std::size_t save = position_;
        std::vector<double> scratch;
        std::vector<std::string_view> next = keyword_line();
        if (!next.empty() && equals_keyword(next[0], "offsets") && next.size() >= 2) {
            read_values(first, next[1], scratch);
            next = keyword_line();
            if (next.size() < 2) fail("expected CONNECTIVITY after OFFSETS");
            read_values(second, next[1], scratch);
            return;
        }
        position_ = save;
        read_values(second, "int", scratch);
    }

    /// CELL_DATA or POINT_DATA: attribute arrays until the next section keyword.
    void attribute_block(std::uint64_t count, bool cells) {
        while (true) {
            const std::size_t save = position_;
            const std::vector<std::string_view> words = keyword_line();
            if (words.empty()) return;
            const std::string_view keyword = words[0];
            std::vector<double> values;
            if (equals_keyword(keyword, "scalars")) {
                if (words.size() < 3) fail("SCALARS needs a name and a data type");
                const std::uint64_t components = words.size() >= 4 ? count_word(words, 3, "a component count") : 1;
                const std::vector<std::string_view> table = keyword_line();
                if (table.empty() || !equals_keyword(table[0], "lookup_table")) fail("expected LOOKUP_TABLE after SCALARS");
                read_values(count * components, words[2], values);
                if (!cells && components == 1) {
                    Eigen::VectorXd scalar(static_cast<Eigen::Index>(count));
                    for (std::uint64_t i = 0; i < count; ++i) scalar[static_cast<Eigen::Index>(i)] = values[i];
                    scalars_.emplace_back(std::string(words[1]), scalar);
                }
            } else if (equals_keyword(keyword, "normals")) {
                if (words.size() < 3) fail("NORMALS needs a name and a data type");
                read_values(3 * count, words[2], values);
                if (cells) {
                    if (count != faces_.face_count()) fail("CELL_DATA count differs from the number of polygons");
                    rebuild_faces_with_normals(values);
                }
            } else if (equals_keyword(keyword, "vectors")) {
                if (words.size() < 3) fail("VECTORS needs a name and a data type");
                read_values(3 * count, words[2], values);
            } else if (equals_keyword(keyword, "tensors")) {
                if (words.size() < 3) fail("TENSORS needs a name and a data type");
                read_values(9 * count, words[2], values);
            } else if (equals_keyword(keyword, "texture_coordinates")) {
                if (words.size() < 4) fail("TEXTURE_COORDINATES needs a name, a dimension and a data type");
                read_values(count * count_word(words, 2, "a dimension"), words[3], values);
            } else if (equals_keyword(keyword, "field")) {
                read_field(words, cells ? count : 0);
            } else if (equals_keyword(keyword, "metadata")) {
                skip_metadata();
            } else {
                position_ = save;  // the next section
                return;
            }
        }
    }

    void rebuild_faces_with_normals(const std::vector<double>& normals) {
        FaceList with_normals(true);
        with_normals.reserve(faces_.face_count());
        std::size_t at = 0;
        for (std::size_t f = 0; f < faces_.face_count(); ++f) {
            const int size = faces_.sizes()[f];
            with_normals.add(faces_.indices().data() + at, size, normals.data() + 3 * f);
            at += static_cast<std::size_t>(size);
        }
        faces_ = std::move(with_normals);
        face_normal_count_ = faces_.face_count();
    }

    void skip_field(const std::vector<std::string_view>& words) { read_field(words, 0); }

    /// A FIELD block; in CELL_DATA (`face_count` > 0) its integer arrays of one component and one
    /// tuple per face become face integers (e.g. the labels of a label complex), the rest is skipped.
    void read_field(const std::vector<std::string_view>& words, std::uint64_t face_count) {
        const std::uint64_t arrays = count_word(words, 2, "an array count after FIELD");
        for (std::uint64_t a = 0; a < arrays; ++a) {
            const std::vector<std::string_view> array = keyword_line();
            if (array.size() < 4) fail("FIELD array needs a name, components, tuples and a data type");
            const std::uint64_t components = count_word(array, 1, "a component count");
            const std::uint64_t tuples = count_word(array, 2, "a tuple count");
            if (components != 0 && tuples > std::numeric_limits<std::uint64_t>::max() / components) fail("FIELD array too large");
            if (equals_keyword(array[3], "string")) fail("string arrays in FIELD data are not supported");
            std::vector<double> values;
            read_values(components * tuples, array[3], values);
            if (face_count == 0 || components != 1 || tuples != face_count || is_float_type(array[3])) continue;
            if (face_count != faces_.face_count()) fail("CELL_DATA count differs from the number of polygons");
            face_integers_.emplace_back(std::string(array[0]), integer_vector(values));
        }
    }

    Eigen::VectorXi integer_vector(const std::vector<double>& values) const {
        Eigen::VectorXi out(static_cast<Eigen::Index>(values.size()));
        for (std::size_t i = 0; i < values.size(); ++i) {
            if (!(values[i] >= INT32_MIN && values[i] <= INT32_MAX)) fail("a cell integer does not fit 32 bits");
            out[static_cast<Eigen::Index>(i)] = static_cast<int>(values[i]);
        }
        return out;
    }

    void skip_metadata() {
        // METADATA ... ends at a blank line.
        while (position_ < content_.size() && !trimmed(line()).empty()) {
        }
    }

    const std::string& path_;
    std::string_view content_;
    std::size_t position_ = 0;
    bool binary_ = false;
    std::string header_;
    bool has_points_ = false;
    std::vector<double> coordinates_;
    FaceList faces_{false};
    std::size_t face_normal_count_ = 0;
    std::vector<std::pair<std::string, Eigen::VectorXd>> scalars_;
    std::vector<std::pair<std::string, Eigen::VectorXi>> face_integers_;
};

}  // namespace

void write_vtk(const std::string& path, const PolygonMesh& mesh) {
    for (const auto& scalar : mesh.vertex_scalars)
        if (scalar.first.empty() || scalar.first.find_first_of(" \t\r\n") != std::string::npos)
            throw Error(path + ": vertex scalar name '" + scalar.first + "' must be a single word");
    for (const auto& integers : mesh.face_integers)
        if (integers.first.empty() || integers.first.find_first_of(" \t\r\n") != std::string::npos)
            throw Error(path + ": face property name '" + integers.first + "' must be a single word");
    write_file_atomically(path, [&](std::ostream& out) {
        OutputBuffer buffer(out);
        write_vtk_polydata(buffer, mesh);
        buffer.flush();
    });
}

PolygonMesh read_vtk(const std::string& path, std::string_view content) {
    VtkParser parser(path, content);
    PolygonMesh mesh = parser.parse();
    mesh.coordinate_system = coordinate_system_in(parser.header());
    return mesh;
}

}  // namespace dsreg::mesh_format
