// dsreg — internals of the mesh I/O module, shared by the per-format source files of
// src/export/ (not part of the public API).
//
// mesh_io.cpp picks the format from the file extension, checks a mesh before it is written and
// reads the file content; each <format>_format.cpp writes or parses one format with the helpers
// declared here.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <limits>
#include <ostream>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

#include "dsreg/mesh.hpp"

namespace dsreg::mesh_format {

// ---- per-format entry points -------------------------------------------------------------

// Writers get a mesh already accepted by check_mesh_for_writing() and write it through
// write_file_atomically(). They may check format-specific limits first.
void write_obj(const std::string& path, const PolygonMesh& mesh);
void write_off(const std::string& path, const PolygonMesh& mesh);
void write_ply(const std::string& path, const PolygonMesh& mesh);
void write_stl(const std::string& path, const PolygonMesh& mesh);
void write_vtk(const std::string& path, const PolygonMesh& mesh);
void write_vtp(const std::string& path, const PolygonMesh& mesh);

// Readers parse the whole content of the file; `path` is only used in error messages.
PolygonMesh read_obj(const std::string& path, std::string_view content);
PolygonMesh read_off(const std::string& path, std::string_view content);
PolygonMesh read_ply(const std::string& path, std::string_view content);
PolygonMesh read_stl(const std::string& path, std::string_view content);
PolygonMesh read_vtk(const std::string& path, std::string_view content);
PolygonMesh read_vtp(const std::string& path, std::string_view content);

// ---- coordinate system, as 3D Slicer records it ------------------------------------------------

/// "SPACE=LPS" / "SPACE=RAS" for a mesh with a coordinate system, else "".
std::string coordinate_system_tag(const PolygonMesh& mesh);

/// The coordinate system a header text records, by 3D Slicer's rule (vtkMRMLModelStorageNode::
/// GetCoordinateSystemFromFileHeader): "RAS" if it holds "SPACE=RAS", else "LPS" if it holds
/// "SPACE=LPS", else "".
std::string coordinate_system_in(std::string_view header);

// ---- mesh checks ------------------------------------------------------------------------------

/// Largest vertex count that 32-bit face indices can address.
constexpr std::uint64_t max_vertex_count = static_cast<std::uint64_t>(std::numeric_limits<std::int32_t>::max());

/// Checks that faces have 3 or 4 columns (unless there are none), that every index addresses a
/// vertex, and that face_normals is empty or has one row per face. `context` starts messages.
void check_faces(const std::string& context, const PolygonMesh& mesh);

/// check_faces() plus: finite vertex coordinates, one value per vertex in every vertex scalar.
void check_mesh_for_writing(const std::string& path, const PolygonMesh& mesh);

/// Message for a face of `size` vertices in a file ("face has 5 vertices; ...").
std::string unsupported_face_size(std::int64_t size);

/// Message for a face index outside [0, vertex_count): `index` is as written in the file.
std::string face_index_out_of_range(std::int64_t index, std::int64_t vertex_count);

// ---- quads and mixed faces -----------------------------------------------------------------

using Triangle = std::array<std::int32_t, 3>;

/// The two triangles of quad (a,b,c,d) cut along its shorter diagonal, with the orientation of
/// the quad: (a,b,c),(a,c,d) when |ac| <= |bd|, else (a,b,d),(b,c,d).
std::array<Triangle, 2> split_quad(const PointMatrix& vertices, const std::int32_t* quad);

/// Faces collected while reading a file, each a triangle or a quad, optionally with a normal.
class FaceList {
public:
    explicit FaceList(bool with_normals) : with_normals_(with_normals) {}

    void reserve(std::size_t face_count);
    /// Appends a face of `size` (3 or 4) indices; `normal` (3 values) is used iff with_normals.
    void add(const std::int32_t* indices, int size, const double* normal = nullptr);

    bool with_normals() const { return with_normals_; }
    std::size_t face_count() const { return sizes_.size(); }
    std::size_t triangle_count() const { return triangle_count_; }
    std::size_t quad_count() const { return sizes_.size() - triangle_count_; }
    const std::vector<std::uint8_t>& sizes() const { return sizes_; }
    const std::vector<std::int32_t>& indices() const { return indices_; }
    const std::vector<double>& normals() const { return normals_; }

private:
    bool with_normals_;
    std::size_t triangle_count_ = 0;
    std::vector<std::uint8_t> sizes_;
    std::vector<std::int32_t> indices_;
    std::vector<double> normals_;
};

/// A mesh from `vertices` and `faces`, every face of one size: when the list mixes triangles
/// and quads, the quads are split with split_quad() (normals duplicated). No faces → 0×3.
PolygonMesh make_mesh(PointMatrix vertices, const FaceList& faces);

/// Vertices from coordinates stored x0 y0 z0 x1 y1 z1 ...
PointMatrix to_point_matrix(const std::vector<double>& coordinates);

// ---- reading text ------------------------------------------------------------------------------

/// "path:line", the prefix of messages about a text file.
std::string at_line(const std::string& path, std::size_t line);

/// Walks the lines of a text; a line is returned without its '\n' nor a trailing '\r'.
class LineReader {
public:
    explicit LineReader(std::string_view text) : text_(text) {}
    /// Next line into `line`; false at the end of the text.
    bool next(std::string_view& line);
    /// 1-based number of the last line returned.
    std::size_t line_number() const { return line_number_; }
    /// Offset of the first byte after the last line returned (and its '\n').
    std::size_t offset() const { return position_; }

private:
    std::string_view text_;
    std::size_t position_ = 0;
    std::size_t line_number_ = 0;
};

/// Walks the whitespace-separated tokens of a text, counting lines.
class TokenScanner {
public:
    TokenScanner(std::string_view text, std::size_t first_line_number) : text_(text), line_(first_line_number) {}
    /// Next token; empty at the end of the text.
    std::string_view next();
    /// Line of the last token returned (or of the end of the text).
    std::size_t line() const { return line_; }
    /// Skips everything up to and including the next '\n'.
    void skip_rest_of_line();

private:
    std::string_view text_;
    std::size_t position_ = 0;
    std::size_t line_;
};

bool is_space(char c);

/// The whitespace-separated words of `line` (reusing the storage of `words`).
void split_words(std::string_view line, std::vector<std::string_view>& words);

/// `line` up to its first '#'.
std::string_view strip_comment(std::string_view line);

/// Case-insensitive comparison with a lower-case ASCII keyword.
bool equals_keyword(std::string_view word, std::string_view lower_case_keyword);

/// Whole-token parses (locale independent, an optional leading '+' accepted); false if the
/// token is not entirely a number of that kind or is out of range.
bool parse_double(std::string_view token, double& value);
bool parse_integer(std::string_view token, std::int64_t& value);
bool parse_unsigned(std::string_view token, std::uint64_t& value);

/// Throws dsreg::Error (starting with `where`) unless `count` items of at least
/// `min_bytes_each` bytes each fit in `available_bytes`. Run before allocating for `count`.
void check_count_fits(const std::string& where, const std::string& what, std::uint64_t count,
                      std::uint64_t min_bytes_each, std::uint64_t available_bytes);

// ---- writing -----------------------------------------------------------------------------------

bool host_is_little_endian();

/// Collects output bytes in a large buffer and hands them to the stream in big blocks. Numbers
/// are formatted with std::to_chars (shortest round-trip form for doubles, no locale).
class OutputBuffer {
public:
    explicit OutputBuffer(std::ostream& out, std::size_t capacity = std::size_t(1) << 20);
    OutputBuffer(const OutputBuffer&) = delete;
    OutputBuffer& operator=(const OutputBuffer&) = delete;

    void append(std::string_view text);
    void append(char c) {
        make_room(1);
        data_[used_++] = c;
    }
    void append_decimal(double value);
    void append_integer(std::int64_t value);

    /// The bytes of `value` in little-endian order.
    template <class T>
    void append_little_endian(T value) {
        static_assert(std::is_arithmetic<T>::value, "append_little_endian needs a number");
        make_room(sizeof(T));
        char* destination = data_.data() + used_;
        std::memcpy(destination, &value, sizeof(T));
        if (!little_endian_host_) reverse_bytes(destination, sizeof(T));
        used_ += sizeof(T);
    }

    /// Writes the buffered bytes to the stream (call once at the end).
    void flush();

private:
    void make_room(std::size_t bytes) {
        if (data_.size() - used_ < bytes) flush();
    }
    static void reverse_bytes(char* bytes, std::size_t count);

    std::ostream& out_;
    std::vector<char> data_;
    std::size_t used_ = 0;
    bool little_endian_host_;
};

}  // namespace dsreg::mesh_format
