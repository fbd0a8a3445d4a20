// dsreg — STL, a list of independent triangles.
//
// Writing: binary STL; quads are split along their shorter diagonal; each facet normal is the
// unit geometric normal of its triangle, or 0 for a degenerate triangle.
//
// Reading: binary when the size of the file is exactly 84 + 50 × (the triangle count of the
// header), or when the file does not start with "solid" and is at least that long; ASCII
// ("solid ... facet normal ... outer loop vertex ×3 endloop endfacet ... endsolid", keywords in
// any case, several solids allowed) when it starts with "solid". Identical vertex positions are
// merged so the mesh is indexed. Facet normals of the file are not kept.
#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <unordered_map>

#include "dsreg/atomic_file.hpp"
#include "dsreg/error.hpp"
#include "mesh_format.hpp"

namespace dsreg::mesh_format {

namespace {

constexpr std::size_t stl_header_bytes = 80;
constexpr std::size_t stl_facet_bytes = 50;  // normal, 3 vertices (12 floats), attribute (uint16)

// ---- writing -----------------------------------------------------------------------------------

/// Unit normal of triangle (a, b, c) by the right-hand rule; 0 if it is degenerate.
Eigen::Vector3d triangle_normal(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
    const Eigen::Vector3d normal = (b - a).cross(c - a);
    const double length = normal.norm();
    if (!(length > 0.0) || !std::isfinite(length)) return Eigen::Vector3d::Zero();
    return normal / length;
}

void write_stl_facet(OutputBuffer& buffer, const PointMatrix& vertices, const Triangle& triangle) {
    const Eigen::Vector3d a = vertices.row(triangle[0]).transpose();
    const Eigen::Vector3d b = vertices.row(triangle[1]).transpose();
    const Eigen::Vector3d c = vertices.row(triangle[2]).transpose();
    for (const Eigen::Vector3d& point : {triangle_normal(a, b, c), a, b, c}) {
        for (int axis = 0; axis < 3; ++axis) buffer.append_little_endian(static_cast<float>(point[axis]));
    }
    buffer.append_little_endian(std::uint16_t{0});
}

void write_stl_facets(OutputBuffer& buffer, const PolygonMesh& mesh) {
    const FaceMatrix& faces = mesh.faces;
    for (Eigen::Index f = 0; f < faces.rows(); ++f) {
        const std::int32_t* face = faces.row(f).data();
        if (faces.cols() == 3) {
            write_stl_facet(buffer, mesh.vertices, Triangle{face[0], face[1], face[2]});
        } else {
            for (const Triangle& triangle : split_quad(mesh.vertices, face))
                write_stl_facet(buffer, mesh.vertices, triangle);
        }
    }
}

// ---- reading: shared -------------------------------------------------------------------------

/// Gives each distinct position one vertex index (-0 and +0 are the same position).
class VertexMerger {
public:
    explicit VertexMerger(const std::string& path) : path_(path) {}

    void reserve(std::size_t positions) { index_of_.reserve(positions); }

    std::int32_t index_of(double x, double y, double z) {
        const Position position{x + 0.0, y + 0.0, z + 0.0};  // + 0.0 turns -0 into +0
        const auto [entry, inserted] =
            index_of_.try_emplace(position, static_cast<std::int32_t>(coordinates_.size() / 3));
        if (inserted) {
            if (coordinates_.size() / 3 >= max_vertex_count)
                throw Error(path_ + ": too many vertices for 32-bit face indices");
            coordinates_.insert(coordinates_.end(), position.begin(), position.end());
        }
        return entry->second;
    }

    PointMatrix vertices() const { return to_point_matrix(coordinates_); }

private:
    using Position = std::array<double, 3>;

    struct PositionHash {
        std::size_t operator()(const Position& position) const {
            std::uint64_t hash = 0x9e3779b97f4a7c15ULL;
            for (double coordinate : position) {
                std::uint64_t bits = 0;
                std::memcpy(&bits, &coordinate, sizeof bits);
                hash ^= bits + 0x9e3779b97f4a7c15ULL + (hash << 6) + (hash >> 2);
            }
            return static_cast<std::size_t>(hash);
        }
    };

    const std::string& path_;
    std::unordered_map<Position, std::int32_t, PositionHash> index_of_;
    std::vector<double> coordinates_;
};

bool starts_with_solid(std::string_view content) {
    std::size_t start = 0;
    while (start < content.size() && is_space(content[start])) ++start;
    return equals_keyword(content.substr(start, 5), "solid");
}

// ---- reading: binary -------------------------------------------------------------------------

std::uint32_t binary_triangle_count(std::string_view content) {
    std::uint32_t count = 0;
    for (int byte = 3; byte >= 0; --byte) {
        count = (count << 8) | static_cast<unsigned char>(content[stl_header_bytes + static_cast<std::size_t>(byte)]);
    }
    return count;
}

float read_little_endian_float(const char* bytes) {
    std::array<char, 4> ordered;
    std::memcpy(ordered.data(), bytes, 4);
    if (!host_is_little_endian()) std::reverse(ordered.begin(), ordered.end());
    float value = 0.0f;
    std::memcpy(&value, ordered.data(), 4);
    return value;
}

PolygonMesh read_binary_stl(const std::string& path, std::string_view content) {
    const std::uint32_t triangle_count = binary_triangle_count(content);
    VertexMerger merger(path);
    merger.reserve(triangle_count);
    FaceList faces(false);
    faces.reserve(triangle_count);
    for (std::uint32_t t = 0; t < triangle_count; ++t) {
        const char* facet = content.data() + stl_header_bytes + 4 + std::size_t(t) * stl_facet_bytes;
        std::array<std::int32_t, 3> triangle{};
        for (std::size_t corner = 0; corner < 3; ++corner) {
            const char* position = facet + 12 * (corner + 1);  // after the facet normal
            const double x = read_little_endian_float(position);
            const double y = read_little_endian_float(position + 4);
            const double z = read_little_endian_float(position + 8);
            if (!std::isfinite(x) || !std::isfinite(y) || !std::isfinite(z)) {
                throw Error(path + ": triangle " + std::to_string(t) + " has a non-finite coordinate");
            }
            triangle[corner] = merger.index_of(x, y, z);
        }
        faces.add(triangle.data(), 3);
    }
    return make_mesh(merger.vertices(), faces);
}

// ---- reading: ASCII --------------------------------------------------------------------------

/// Parses "solid name / facet ... / endsolid name" blocks.
class AsciiStlParser {
public:
    AsciiStlParser(const std::string& path, std::string_view content)
        : path_(path), tokens_(content, 1), merger_(path) {}

    PolygonMesh parse() {
        expect("solid");
        tokens_.skip_rest_of_line();  // the name of the solid
        while (true) {
            const std::string_view word = tokens_.next();
            if (equals_keyword(word, "facet")) {
                parse_facet();
            } else if (equals_keyword(word, "endsolid")) {
                tokens_.skip_rest_of_line();
                if (!next_solid()) break;
            } else {
                throw unexpected(word, "'facet' or 'endsolid'");
            }
        }
        return make_mesh(merger_.vertices(), faces_);
    }

private:
    std::string here() const { return at_line(path_, tokens_.line()); }

    Error unexpected(std::string_view word, const std::string& expected) const {
        if (word.empty()) return Error(here() + ": the file ends where " + expected + " was expected");
        return Error(here() + ": expected " + expected + " but found '" + std::string(word) + "'");
    }

    void expect(std::string_view keyword) {
        const std::string_view word = tokens_.next();
        if (!equals_keyword(word, keyword)) throw unexpected(word, "'" + std::string(keyword) + "'");
    }

    /// After "endsolid": true if another "solid" follows, false at the end of the file.
    bool next_solid() {
        const std::string_view word = tokens_.next();
        if (word.empty()) return false;
        if (!equals_keyword(word, "solid")) throw unexpected(word, "'solid' or the end of the file");
        tokens_.skip_rest_of_line();
        return true;
    }

    double number() {
        const std::string_view word = tokens_.next();
        double value = 0.0;
        if (!parse_double(word, value)) throw unexpected(word, "a number");
        return value;
    }

    void parse_facet() {
        expect("normal");
        for (int i = 0; i < 3; ++i) number();  // the stored normal is not kept
        expect("outer");
        expect("loop");
        std::array<std::int32_t, 3> triangle{};
        for (std::int32_t& corner : triangle) {
            expect("vertex");
            const double x = number(), y = number(), z = number();
            if (!std::isfinite(x) || !std::isfinite(y) || !std::isfinite(z)) {
                throw Error(here() + ": vertex has a non-finite coordinate");
            }
            corner = merger_.index_of(x, y, z);
        }
        expect("endloop");
        expect("endfacet");
        faces_.add(triangle.data(), 3);
    }

    const std::string& path_;
    TokenScanner tokens_;
    VertexMerger merger_;
    FaceList faces_{false};
};

}  // namespace

void write_stl(const std::string& path, const PolygonMesh& mesh) {
    const std::uint64_t triangles_per_face = mesh.faces.cols() == 4 ? 2 : 1;
    const std::uint64_t triangle_count = triangles_per_face * static_cast<std::uint64_t>(mesh.faces.rows());
    if (triangle_count > std::numeric_limits<std::uint32_t>::max()) {
        throw Error(path + ": " + std::to_string(triangle_count) + " triangles do not fit in a binary STL file");
    }
    write_file_atomically(path, [&](std::ostream& out) {
        OutputBuffer buffer(out);
        // Must not start with "solid"; 3D Slicer reads the coordinate system from it (vtkSTLReader::GetHeader).
        std::string header = "binary STL written by dsreg";
        if (!mesh.coordinate_system.empty()) header += " " + coordinate_system_tag(mesh);
        header.resize(stl_header_bytes, ' ');
        buffer.append(header);
        buffer.append_little_endian(static_cast<std::uint32_t>(triangle_count));
        write_stl_facets(buffer, mesh);
        buffer.flush();
    });
}

PolygonMesh read_stl(const std::string& path, std::string_view content) {
    const bool solid = starts_with_solid(content);
    if (content.size() >= stl_header_bytes + 4) {
        const std::uint64_t expected =
            stl_header_bytes + 4 + std::uint64_t(binary_triangle_count(content)) * stl_facet_bytes;
        if (content.size() == expected || (!solid && content.size() > expected)) return read_binary_stl(path, content);
        if (!solid) {
            throw Error(path + ": truncated binary STL: the header announces " +
                        std::to_string(binary_triangle_count(content)) + " triangles (" + std::to_string(expected) +
                        " bytes) but the file has " + std::to_string(content.size()) + " bytes");
        }
    }
    if (!solid) throw Error(path + ": not an STL file (too short for binary STL and does not start with 'solid')");
    return AsciiStlParser(path, content).parse();
}

}  // namespace dsreg::mesh_format
