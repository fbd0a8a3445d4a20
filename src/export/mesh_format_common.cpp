// dsreg — helpers shared by the mesh format readers and writers (see mesh_format.hpp).
#include <algorithm>
#include <charconv>
#include <cmath>

#include "dsreg/error.hpp"
#include "mesh_format.hpp"

namespace dsreg::mesh_format {

// ---- mesh checks ------------------------------------------------------------------------------

std::string unsupported_face_size(std::int64_t size) {
    const std::string count = std::to_string(size) + (size == 1 ? " vertex" : " vertices");
    if (size < 3) return "face has " + count + "; a face needs at least 3";
    return "face has " + count + "; only triangles and quads are supported";
}

std::string face_index_out_of_range(std::int64_t index, std::int64_t vertex_count) {
    const std::string defined = std::to_string(vertex_count) + (vertex_count == 1 ? " vertex is" : " vertices are");
    return "face refers to vertex " + std::to_string(index) + " but only " + defined + " defined";
}

namespace {

void check_face_indices(const std::string& context, const FaceMatrix& faces, Eigen::Index vertex_count) {
    for (Eigen::Index f = 0; f < faces.rows(); ++f) {
        for (Eigen::Index k = 0; k < faces.cols(); ++k) {
            const std::int32_t index = faces(f, k);
            if (index < 0 || index >= vertex_count) {
                throw Error(context + ": face " + std::to_string(f) + " refers to vertex " + std::to_string(index) +
                            " but the mesh has " + std::to_string(vertex_count) + " vertices");
            }
        }
    }
}

void check_vertices_finite(const std::string& context, const PointMatrix& vertices) {
    for (Eigen::Index v = 0; v < vertices.rows(); ++v) {
        if (!vertices.row(v).allFinite()) {
            throw Error(context + ": vertex " + std::to_string(v) + " has a non-finite coordinate");
        }
    }
}

void check_vertex_scalars(const std::string& context, const PolygonMesh& mesh) {
    for (const auto& [name, values] : mesh.vertex_scalars) {
        if (values.size() != mesh.vertices.rows()) {
            throw Error(context + ": vertex scalar '" + name + "' has " + std::to_string(values.size()) +
                        " values for " + std::to_string(mesh.vertices.rows()) + " vertices");
        }
    }
}

}  // namespace

void check_faces(const std::string& context, const PolygonMesh& mesh) {
    const FaceMatrix& faces = mesh.faces;
    if (faces.rows() > 0 && faces.cols() != 3 && faces.cols() != 4) {
        throw Error(context + ": faces have " + std::to_string(faces.cols()) +
                    " vertices each; only triangles and quads are supported");
    }
    if (mesh.vertices.rows() > static_cast<Eigen::Index>(max_vertex_count)) {
        throw Error(context + ": too many vertices for 32-bit face indices");
    }
    check_face_indices(context, faces, mesh.vertices.rows());
    if (mesh.face_normals.rows() != 0 && mesh.face_normals.rows() != faces.rows()) {
        throw Error(context + ": " + std::to_string(mesh.face_normals.rows()) + " face normals for " +
                    std::to_string(faces.rows()) + " faces");
    }
    for (const auto& [name, values] : mesh.face_integers) {
        if (values.size() != faces.rows()) {
            throw Error(context + ": face integer '" + name + "' has " + std::to_string(values.size()) + " values for " +
                        std::to_string(faces.rows()) + " faces");
        }
    }
}

void check_mesh_for_writing(const std::string& path, const PolygonMesh& mesh) {
    check_faces(path, mesh);
    check_vertices_finite(path, mesh.vertices);
    check_vertex_scalars(path, mesh);
}

// ---- coordinate system ---------------------------------------------------------------------------

std::string coordinate_system_tag(const PolygonMesh& mesh) {
    return mesh.coordinate_system.empty() ? "" : "SPACE=" + mesh.coordinate_system;
}

std::string coordinate_system_in(std::string_view header) {
    if (header.find("SPACE=RAS") != std::string_view::npos) return "RAS";
    if (header.find("SPACE=LPS") != std::string_view::npos) return "LPS";
    return "";
}

// ---- quads and mixed faces -----------------------------------------------------------------

std::array<Triangle, 2> split_quad(const PointMatrix& vertices, const std::int32_t* quad) {
    const std::int32_t a = quad[0], b = quad[1], c = quad[2], d = quad[3];
    const double ac = (vertices.row(c) - vertices.row(a)).squaredNorm();
    const double bd = (vertices.row(d) - vertices.row(b)).squaredNorm();
    if (ac <= bd) return {Triangle{a, b, c}, Triangle{a, c, d}};
    return {Triangle{a, b, d}, Triangle{b, c, d}};
}

void FaceList::reserve(std::size_t face_count) {
    sizes_.reserve(face_count);
    indices_.reserve(face_count * 4);
    if (with_normals_) normals_.reserve(face_count * 3);
}

void FaceList::add(const std::int32_t* indices, int size, const double* normal) {
    sizes_.push_back(static_cast<std::uint8_t>(size));
    indices_.insert(indices_.end(), indices, indices + size);
    if (size == 3) ++triangle_count_;
    if (with_normals_) normals_.insert(normals_.end(), normal, normal + 3);
}

namespace {

/// All faces of `faces` have `size` vertices: copy them as they are.
void copy_uniform_faces(const FaceList& faces, int size, PolygonMesh& mesh) {
    const auto rows = static_cast<Eigen::Index>(faces.face_count());
    mesh.faces = Eigen::Map<const FaceMatrix>(faces.indices().data(), rows, size);
    if (faces.with_normals()) mesh.face_normals = Eigen::Map<const PointMatrix>(faces.normals().data(), rows, 3);
}

/// Triangles are copied, quads are split in two; face order is kept.
void copy_triangulating_quads(const FaceList& faces, PolygonMesh& mesh) {
    const std::size_t triangle_count = faces.triangle_count() + 2 * faces.quad_count();
    mesh.faces.resize(static_cast<Eigen::Index>(triangle_count), 3);
    if (faces.with_normals()) mesh.face_normals.resize(static_cast<Eigen::Index>(triangle_count), 3);
    const std::int32_t* indices = faces.indices().data();
    Eigen::Index row = 0;
    for (std::size_t f = 0; f < faces.face_count(); ++f) {
        const int size = faces.sizes()[f];
        const Eigen::Index first_row = row;
        if (size == 3) {
            mesh.faces.row(row++) << indices[0], indices[1], indices[2];
        } else {
            for (const Triangle& t : split_quad(mesh.vertices, indices)) mesh.faces.row(row++) << t[0], t[1], t[2];
        }
        if (faces.with_normals()) {
            const double* n = faces.normals().data() + 3 * f;
            for (Eigen::Index r = first_row; r < row; ++r) mesh.face_normals.row(r) << n[0], n[1], n[2];
        }
        indices += size;
    }
}

}  // namespace

PolygonMesh make_mesh(PointMatrix vertices, const FaceList& faces) {
    PolygonMesh mesh;
    mesh.vertices = std::move(vertices);
    if (faces.face_count() == 0) {
        mesh.faces.resize(0, 3);
    } else if (faces.quad_count() == 0) {
        copy_uniform_faces(faces, 3, mesh);
    } else if (faces.triangle_count() == 0) {
        copy_uniform_faces(faces, 4, mesh);
    } else {
        copy_triangulating_quads(faces, mesh);
    }
    return mesh;
}

PointMatrix to_point_matrix(const std::vector<double>& coordinates) {
    const auto rows = static_cast<Eigen::Index>(coordinates.size() / 3);
    return Eigen::Map<const PointMatrix>(coordinates.data(), rows, 3);
}

// ---- reading text ------------------------------------------------------------------------------

std::string at_line(const std::string& path, std::size_t line) { return path + ":" + std::to_string(line); }

bool LineReader::next(std::string_view& line) {
    if (position_ >= text_.size()) return false;
    std::size_t end = text_.find('\n', position_);
    const std::size_t next_position = (end == std::string_view::npos) ? text_.size() : end + 1;
    if (end == std::string_view::npos) end = text_.size();
    line = text_.substr(position_, end - position_);
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    position_ = next_position;
    ++line_number_;
    return true;
}

bool is_space(char c) { return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\v' || c == '\f'; }

std::string_view TokenScanner::next() {
    while (position_ < text_.size() && is_space(text_[position_])) {
        if (text_[position_] == '\n') ++line_;
        ++position_;
    }
    const std::size_t start = position_;
    while (position_ < text_.size() && !is_space(text_[position_])) ++position_;
    return text_.substr(start, position_ - start);
}

void TokenScanner::skip_rest_of_line() {
    const std::size_t end = text_.find('\n', position_);
    if (end == std::string_view::npos) {
        position_ = text_.size();
    } else {
        position_ = end + 1;
        ++line_;
    }
}

void split_words(std::string_view line, std::vector<std::string_view>& words) {
    words.clear();
    std::size_t position = 0;
    while (true) {
        while (position < line.size() && is_space(line[position])) ++position;
        if (position == line.size()) return;
        const std::size_t start = position;
        while (position < line.size() && !is_space(line[position])) ++position;
        words.push_back(line.substr(start, position - start));
    }
}

std::string_view strip_comment(std::string_view line) {
    const std::size_t hash = line.find('#');
    return hash == std::string_view::npos ? line : line.substr(0, hash);
}

bool equals_keyword(std::string_view word, std::string_view lower_case_keyword) {
    if (word.size() != lower_case_keyword.size()) return false;
    for (std::size_t i = 0; i < word.size(); ++i) {
        const char c = (word[i] >= 'A' && word[i] <= 'Z') ? static_cast<char>(word[i] - 'A' + 'a') : word[i];
        if (c != lower_case_keyword[i]) return false;
    }
    return true;
}

namespace {

/// Drops one leading '+' (std::from_chars does not accept it), unless a sign follows.
std::string_view without_plus_sign(std::string_view token) {
    if (token.size() > 1 && token[0] == '+' && token[1] != '+' && token[1] != '-') token.remove_prefix(1);
    return token;
}

template <class T>
bool parse_whole_token(std::string_view token, T& value) {
    token = without_plus_sign(token);
    if (token.empty()) return false;
    const char* end = token.data() + token.size();
    const auto [stop, error] = std::from_chars(token.data(), end, value);
    return error == std::errc() && stop == end;
}

}  // namespace

bool parse_double(std::string_view token, double& value) { return parse_whole_token(token, value); }
bool parse_integer(std::string_view token, std::int64_t& value) { return parse_whole_token(token, value); }
bool parse_unsigned(std::string_view token, std::uint64_t& value) { return parse_whole_token(token, value); }

void check_count_fits(const std::string& where, const std::string& what, std::uint64_t count,
                      std::uint64_t min_bytes_each, std::uint64_t available_bytes) {
    if (min_bytes_each == 0 || count <= available_bytes / min_bytes_each) return;
    throw Error(where + ": the file claims " + std::to_string(count) + " " + what + ", but the " +
                std::to_string(available_bytes) +
                " bytes that follow cannot hold that many (truncated or corrupt file?)");
}

// ---- writing -----------------------------------------------------------------------------------

bool host_is_little_endian() {
    const std::uint16_t probe = 1;
    unsigned char first_byte = 0;
    std::memcpy(&first_byte, &probe, 1);
    return first_byte == 1;
}

OutputBuffer::OutputBuffer(std::ostream& out, std::size_t capacity)
    : out_(out), data_(std::max<std::size_t>(capacity, 64)), little_endian_host_(host_is_little_endian()) {}

void OutputBuffer::append(std::string_view text) {
    if (text.size() > data_.size() - used_) flush();
    if (text.size() > data_.size()) {
        out_.write(text.data(), static_cast<std::streamsize>(text.size()));
        return;
    }
    std::memcpy(data_.data() + used_, text.data(), text.size());
    used_ += text.size();
}

void OutputBuffer::append_decimal(double value) {
    constexpr std::size_t longest_double = 32;  // e.g. "-2.2250738585072014e-308" has 24
    make_room(longest_double);
    char* begin = data_.data() + used_;
    const auto result = std::to_chars(begin, begin + longest_double, value);
    used_ += static_cast<std::size_t>(result.ptr - begin);
}

void OutputBuffer::append_integer(std::int64_t value) {
    constexpr std::size_t longest_integer = 24;  // "-9223372036854775808" has 20
    make_room(longest_integer);
    char* begin = data_.data() + used_;
    const auto result = std::to_chars(begin, begin + longest_integer, value);
    used_ += static_cast<std::size_t>(result.ptr - begin);
}

void OutputBuffer::flush() {
    if (used_ > 0) out_.write(data_.data(), static_cast<std::streamsize>(used_));
    used_ = 0;
}

void OutputBuffer::reverse_bytes(char* bytes, std::size_t count) { std::reverse(bytes, bytes + count); }

}  // namespace dsreg::mesh_format
