// dsreg — Wavefront OBJ: "v x y z" and "f i j k [l]" statements (1-based indices).
//
// Reading: faces may reference vertices as i, i/t, i/t/n or i//n, with negative indices counting
// back from the last vertex defined. Texture coordinates, normals, groups, materials, smoothing
// groups, lines, points and free-form geometry statements are ignored; any other statement is an
// error. A face must have 3 or 4 vertices and may only use vertices defined before it.
#include <algorithm>
#include <array>
#include <cmath>

#include "dsreg/atomic_file.hpp"
#include "dsreg/error.hpp"
#include "mesh_format.hpp"

namespace dsreg::mesh_format {

namespace {

// ---- writing -----------------------------------------------------------------------------------

void write_obj_vertices(OutputBuffer& buffer, const PointMatrix& vertices) {
    for (Eigen::Index v = 0; v < vertices.rows(); ++v) {
        buffer.append("v ");
        buffer.append_decimal(vertices(v, 0));
        buffer.append(' ');
        buffer.append_decimal(vertices(v, 1));
        buffer.append(' ');
        buffer.append_decimal(vertices(v, 2));
        buffer.append('\n');
    }
}

void write_obj_faces(OutputBuffer& buffer, const FaceMatrix& faces) {
    for (Eigen::Index f = 0; f < faces.rows(); ++f) {
        buffer.append('f');
        for (Eigen::Index k = 0; k < faces.cols(); ++k) {
            buffer.append(' ');
            buffer.append_integer(std::int64_t(faces(f, k)) + 1);
        }
        buffer.append('\n');
    }
}

// ---- reading -----------------------------------------------------------------------------------

enum class ObjStatement { Vertex, Face, Ignored, Unknown };

ObjStatement classify_statement(std::string_view keyword) {
    if (keyword == "v") return ObjStatement::Vertex;
    if (keyword == "f") return ObjStatement::Face;
    static constexpr std::array<std::string_view, 35> ignored = {
        // texture coordinates, vertex normals, parameter-space vertices
        "vt", "vn", "vp",
        // grouping, display and material attributes
        "g", "o", "s", "mg", "usemtl", "mtllib", "maplib", "usemap", "lod", "shadow_obj", "trace_obj", "bevel",
        "c_interp", "d_interp", "ctech", "stech",
        // lines, points, free-form curves and surfaces
        "l", "p", "cstype", "deg", "bmat", "step", "curv", "curv2", "surf", "parm", "trim", "hole", "scrv", "sp", "end",
        "con"};
    if (std::find(ignored.begin(), ignored.end(), keyword) != ignored.end()) return ObjStatement::Ignored;
    return ObjStatement::Unknown;
}

/// Parses the statements of an OBJ text one line at a time.
class ObjParser {
public:
    ObjParser(const std::string& path, std::string_view content) : path_(path), lines_(content) {}

    PolygonMesh parse() {
        std::string_view line;
        while (lines_.next(line)) parse_line(strip_comment(line));
        return make_mesh(to_point_matrix(coordinates_), faces_);
    }

private:
    std::string here() const { return at_line(path_, lines_.line_number()); }
    std::int64_t vertex_count() const { return static_cast<std::int64_t>(coordinates_.size() / 3); }

    void parse_line(std::string_view line) {
        split_words(line, words_);
        if (words_.empty()) return;
        switch (classify_statement(words_[0])) {
            case ObjStatement::Vertex:
                return parse_vertex();
            case ObjStatement::Face:
                return parse_face();
            case ObjStatement::Ignored:
                return;
            case ObjStatement::Unknown:
                throw Error(here() + ": unknown OBJ statement '" + std::string(words_[0]) + "'");
        }
    }

    /// "v x y z [w]" or "v x y z r g b": every value must be a number; x y z are kept.
    void parse_vertex() {
        if (words_.size() < 4) throw Error(here() + ": vertex needs 3 coordinates");
        std::array<double, 3> position{};
        for (std::size_t i = 1; i < words_.size(); ++i) {
            double value = 0.0;
            if (!parse_double(words_[i], value)) {
                throw Error(here() + ": '" + std::string(words_[i]) + "' is not a number");
            }
            if (i <= 3) position[i - 1] = value;
        }
        if (!std::isfinite(position[0]) || !std::isfinite(position[1]) || !std::isfinite(position[2])) {
            throw Error(here() + ": vertex has a non-finite coordinate");
        }
        if (static_cast<std::uint64_t>(vertex_count()) >= max_vertex_count) {
            throw Error(here() + ": too many vertices for 32-bit face indices");
        }
        coordinates_.insert(coordinates_.end(), position.begin(), position.end());
    }

    void parse_face() {
        const std::size_t size = words_.size() - 1;
        if (size < 3 || size > 4) throw Error(here() + ": " + unsupported_face_size(static_cast<std::int64_t>(size)));
        std::array<std::int32_t, 4> indices{};
        for (std::size_t k = 0; k < size; ++k) indices[k] = resolve_vertex_reference(words_[k + 1]);
        faces_.add(indices.data(), static_cast<int>(size));
    }

    /// 0-based vertex index of a reference "i", "i/t", "i/t/n" or "i//n".
    std::int32_t resolve_vertex_reference(std::string_view reference) const {
        std::int64_t index = 0;
        if (!is_valid_reference(reference, index)) {
            throw Error(here() + ": '" + std::string(reference) +
                        "' is not a valid face vertex (i, i/t, i/t/n or i//n)");
        }
        const std::int64_t resolved = index > 0 ? index - 1 : vertex_count() + index;
        if (resolved < 0 || resolved >= vertex_count()) {
            throw Error(here() + ": " + face_index_out_of_range(index, vertex_count()));
        }
        return static_cast<std::int32_t>(resolved);
    }

    /// Whether `reference` has the form i, i/t, i/t/n or i//n with nonzero integers; `index`
    /// gets i as written.
    static bool is_valid_reference(std::string_view reference, std::int64_t& index) {
        std::array<std::string_view, 3> parts;
        std::size_t part_count = 0;
        while (true) {
            if (part_count == parts.size()) return false;
            const std::size_t slash = reference.find('/');
            parts[part_count++] = reference.substr(0, slash);
            if (slash == std::string_view::npos) break;
            reference.remove_prefix(slash + 1);
        }
        std::int64_t ignored = 0;
        const bool texture_ok =
            part_count < 2 || (parts[1].empty() ? part_count == 3 : parse_integer(parts[1], ignored));
        const bool normal_ok = part_count < 3 || parse_integer(parts[2], ignored);
        return parse_integer(parts[0], index) && index != 0 && texture_ok && normal_ok;
    }

    const std::string& path_;
    LineReader lines_;
    std::vector<std::string_view> words_;
    std::vector<double> coordinates_;
    FaceList faces_{false};
};

}  // namespace

void write_obj(const std::string& path, const PolygonMesh& mesh) {
    write_file_atomically(path, [&](std::ostream& out) {
        OutputBuffer buffer(out);
        buffer.append("# dsreg mesh: ");
        buffer.append_integer(mesh.vertices.rows());
        buffer.append(" vertices, ");
        buffer.append_integer(mesh.faces.rows());
        buffer.append(" faces");
        // 3D Slicer reads the coordinate system from the leading comment lines (vtkOBJReader).
        if (!mesh.coordinate_system.empty()) buffer.append(" " + coordinate_system_tag(mesh));
        buffer.append('\n');
        write_obj_vertices(buffer, mesh.vertices);
        write_obj_faces(buffer, mesh.faces);
        buffer.flush();
    });
}

PolygonMesh read_obj(const std::string& path, std::string_view content) { return ObjParser(path, content).parse(); }

}  // namespace dsreg::mesh_format
