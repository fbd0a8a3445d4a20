// dsreg — Object File Format (OFF): "OFF", "nv nf ne", nv lines "x y z", nf lines "n i j k ...".
//
// Reading: '#' starts a comment; the counts may follow "OFF" on the same line. Header keywords
// with the C, N, ST prefixes (COFF, NOFF, STOFF, ...) are accepted and the extra numbers of
// their vertex lines are ignored, as are face colours after the indices. 4OFF, nOFF and binary
// OFF are rejected. Each vertex and each face is on its own line; faces have 3 or 4 vertices.
#include <array>
#include <cmath>

#include "dsreg/atomic_file.hpp"
#include "dsreg/error.hpp"
#include "mesh_format.hpp"

namespace dsreg::mesh_format {

namespace {

// Smallest possible vertex line "0 0 0\n" and face line "3 0 1 2\n", to bound the counts.
constexpr std::uint64_t min_vertex_line_bytes = 6;
constexpr std::uint64_t min_face_line_bytes = 8;

void write_off_header(OutputBuffer& buffer, const PolygonMesh& mesh) {
    buffer.append("OFF\n");
    if (!mesh.coordinate_system.empty()) buffer.append("# " + coordinate_system_tag(mesh) + "\n");
    buffer.append_integer(mesh.vertices.rows());
    buffer.append(' ');
    buffer.append_integer(mesh.faces.rows());
    buffer.append(" 0\n");
}

void write_off_vertices(OutputBuffer& buffer, const PointMatrix& vertices) {
    for (Eigen::Index v = 0; v < vertices.rows(); ++v) {
        buffer.append_decimal(vertices(v, 0));
        buffer.append(' ');
        buffer.append_decimal(vertices(v, 1));
        buffer.append(' ');
        buffer.append_decimal(vertices(v, 2));
        buffer.append('\n');
    }
}

void write_off_faces(OutputBuffer& buffer, const FaceMatrix& faces) {
    for (Eigen::Index f = 0; f < faces.rows(); ++f) {
        buffer.append_integer(faces.cols());
        for (Eigen::Index k = 0; k < faces.cols(); ++k) {
            buffer.append(' ');
            buffer.append_integer(faces(f, k));
        }
        buffer.append('\n');
    }
}

/// "OFF" with optional prefixes ST, C, N (the prefixes only add numbers to vertex lines).
bool is_supported_off_keyword(std::string_view word) {
    constexpr std::string_view suffix = "OFF";
    if (word.size() < suffix.size() || word.substr(word.size() - suffix.size()) != suffix) return false;
    const std::string_view prefix = word.substr(0, word.size() - suffix.size());
    return prefix.find_first_not_of("STCN") == std::string_view::npos;
}

/// Parses an OFF text line by line (comments and blank lines skipped).
class OffParser {
public:
    OffParser(const std::string& path, std::string_view content) : path_(path), content_(content), lines_(content) {}

    PolygonMesh parse() {
        parse_header();
        parse_vertices();
        parse_faces();
        if (next_content_line()) throw Error(here() + ": unexpected content after the last face");
        return make_mesh(std::move(vertices_), faces_);
    }

private:
    std::string here() const { return at_line(path_, lines_.line_number()); }

    /// Moves to the next line holding something other than a comment; false at the end.
    bool next_content_line() {
        std::string_view line;
        while (lines_.next(line)) {
            split_words(strip_comment(line), words_);
            if (!words_.empty()) return true;
        }
        return false;
    }

    void parse_header() {
        if (!next_content_line()) throw Error(path_ + ": empty file, not an OFF mesh");
        if (!is_supported_off_keyword(words_[0])) {
            throw Error(here() + ": not an OFF file or an unsupported OFF variant (header '" + std::string(words_[0]) +
                        "')");
        }
        std::size_t first_count = 1;
        if (words_.size() == 1) {
            if (!next_content_line()) throw Error(path_ + ": file ends before the vertex and face counts");
            first_count = 0;
        }
        if (words_[first_count] == "BINARY") throw Error(here() + ": binary OFF is not supported");
        parse_counts(first_count);
    }

    /// "nv nf [ne]" from words_[first], then checks them against the size of the file.
    void parse_counts(std::size_t first) {
        const std::size_t count_words = words_.size() - first;
        if ((count_words != 2 && count_words != 3) || !parse_unsigned(words_[first], vertex_count_) ||
            !parse_unsigned(words_[first + 1], face_count_) ||
            (count_words == 3 && !parse_unsigned(words_[first + 2], edge_count_))) {
            throw Error(here() + ": expected the vertex, face and edge counts");
        }
        if (vertex_count_ > max_vertex_count) throw Error(here() + ": too many vertices for 32-bit face indices");
        const std::uint64_t available = content_.size() - lines_.offset() + 1;  // last line may lack '\n'
        check_count_fits(here(), "vertices", vertex_count_, min_vertex_line_bytes, available);
        check_count_fits(here(), "faces", face_count_, min_face_line_bytes,
                         available - vertex_count_ * min_vertex_line_bytes);
    }

    void parse_vertices() {
        vertices_.resize(static_cast<Eigen::Index>(vertex_count_), 3);
        for (Eigen::Index v = 0; v < vertices_.rows(); ++v) {
            if (!next_content_line()) {
                throw Error(path_ + ": file ends after " + std::to_string(v) + " of " + std::to_string(vertex_count_) +
                            " vertices");
            }
            parse_vertex_line(v);
        }
    }

    /// "x y z" possibly followed by more numbers (normal, colour, texture coordinates).
    void parse_vertex_line(Eigen::Index v) {
        if (words_.size() < 3) throw Error(here() + ": vertex needs 3 coordinates");
        for (std::size_t i = 0; i < words_.size(); ++i) {
            double value = 0.0;
            if (!parse_double(words_[i], value))
                throw Error(here() + ": '" + std::string(words_[i]) + "' is not a number");
            if (i < 3) vertices_(v, static_cast<Eigen::Index>(i)) = value;
        }
        if (!vertices_.row(v).allFinite()) throw Error(here() + ": vertex has a non-finite coordinate");
    }

    void parse_faces() {
        faces_.reserve(static_cast<std::size_t>(face_count_));
        for (std::uint64_t f = 0; f < face_count_; ++f) {
            if (!next_content_line()) {
                throw Error(path_ + ": file ends after " + std::to_string(f) + " of " + std::to_string(face_count_) +
                            " faces");
            }
            parse_face_line();
        }
    }

    /// "n i1 ... in" possibly followed by a colour.
    void parse_face_line() {
        std::int64_t size = 0;
        if (!parse_integer(words_[0], size))
            throw Error(here() + ": '" + std::string(words_[0]) + "' is not a vertex count");
        if (size < 3 || size > 4) throw Error(here() + ": " + unsupported_face_size(size));
        if (words_.size() < static_cast<std::size_t>(size) + 1) {
            throw Error(here() + ": face lists " + std::to_string(words_.size() - 1) + " of its " +
                        std::to_string(size) + " vertices");
        }
        std::array<std::int32_t, 4> indices{};
        for (std::size_t k = 0; k < static_cast<std::size_t>(size); ++k) indices[k] = parse_vertex_index(words_[k + 1]);
        for (std::size_t i = static_cast<std::size_t>(size) + 1; i < words_.size(); ++i) {
            double ignored = 0.0;
            if (!parse_double(words_[i], ignored))
                throw Error(here() + ": '" + std::string(words_[i]) + "' is not a number");
        }
        faces_.add(indices.data(), static_cast<int>(size));
    }

    std::int32_t parse_vertex_index(std::string_view word) const {
        std::int64_t index = 0;
        if (!parse_integer(word, index)) throw Error(here() + ": '" + std::string(word) + "' is not a vertex index");
        const auto count = static_cast<std::int64_t>(vertex_count_);
        if (index < 0 || index >= count) throw Error(here() + ": " + face_index_out_of_range(index, count));
        return static_cast<std::int32_t>(index);
    }

    const std::string& path_;
    std::string_view content_;
    LineReader lines_;
    std::vector<std::string_view> words_;
    std::uint64_t vertex_count_ = 0;
    std::uint64_t face_count_ = 0;
    std::uint64_t edge_count_ = 0;
    PointMatrix vertices_;
    FaceList faces_{false};
};

}  // namespace

void write_off(const std::string& path, const PolygonMesh& mesh) {
    write_file_atomically(path, [&](std::ostream& out) {
        OutputBuffer buffer(out);
        write_off_header(buffer, mesh);
        write_off_vertices(buffer, mesh.vertices);
        write_off_faces(buffer, mesh.faces);
        buffer.flush();
    });
}

PolygonMesh read_off(const std::string& path, std::string_view content) { return OffParser(path, content).parse(); }

}  // namespace dsreg::mesh_format
