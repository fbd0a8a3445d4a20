// Normal vector fields in a text file (format in normals_file.hpp).
#include "dsreg/normals_file.hpp"

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <fstream>
#include <string_view>
#include <vector>

#include "dsreg/atomic_file.hpp"
#include "dsreg/error.hpp"

namespace dsreg {

namespace {

constexpr std::size_t kMaxLineLength = 1024;

/// 6·(voxel linear index) + 2·axis + (sign > 0): one key per possible voxel face.
std::int64_t surfel_key(const VoxelGrid& grid, std::int64_t i, std::int64_t j, std::int64_t k, int axis, int sign) {
    return 6 * grid.linear_index(i, j, k) + 2 * axis + (sign > 0 ? 1 : 0);
}

/// Face index of each surfel, looked up by key.
class SurfelLookup {
public:
    explicit SurfelLookup(const DigitalSurface& surface) {
        entries_.reserve(surface.surfels.size());
        for (std::size_t f = 0; f < surface.surfels.size(); ++f) {
            const Surfel& s = surface.surfels[f];
            entries_.emplace_back(surfel_key(surface.grid, s.voxel[0], s.voxel[1], s.voxel[2], s.axis, s.sign),
                                  std::int32_t(f));
        }
        std::sort(entries_.begin(), entries_.end());
    }
    /// −1 when the key is not a surfel.
    std::int32_t find(std::int64_t key) const {
        const auto it = std::lower_bound(entries_.begin(), entries_.end(), std::make_pair(key, std::int32_t(-1)));
        return it != entries_.end() && it->first == key ? it->second : -1;
    }

private:
    std::vector<std::pair<std::int64_t, std::int32_t>> entries_;
};

/// A token quoted for a message: printable characters only, at most 40 of them.
std::string quoted(std::string_view token) {
    std::string text = "'";
    for (std::size_t q = 0; q < token.size() && q < 40; ++q)
        text += (token[q] >= 0x20 && token[q] < 0x7f) ? token[q] : '?';
    return text + (token.size() > 40 ? "…'" : "'");
}

/// Splits at spaces, tabs and carriage returns, up to the first '#'.
std::vector<std::string_view> split_fields(std::string_view line) {
    line = line.substr(0, line.find('#'));
    std::vector<std::string_view> fields;
    std::size_t q = 0;
    while (q < line.size()) {
        while (q < line.size() && (line[q] == ' ' || line[q] == '\t' || line[q] == '\r')) ++q;
        const std::size_t start = q;
        while (q < line.size() && line[q] != ' ' && line[q] != '\t' && line[q] != '\r') ++q;
        if (q > start) fields.push_back(line.substr(start, q - start));
    }
    return fields;
}

bool parse_integer(std::string_view token, std::int64_t& value) {
    if (!token.empty() && token[0] == '+') token.remove_prefix(1);
    const auto [end, error] = std::from_chars(token.data(), token.data() + token.size(), value);
    return error == std::errc() && end == token.data() + token.size();
}

bool parse_real(std::string_view token, double& value) {
    if (!token.empty() && token[0] == '+') token.remove_prefix(1);
    const auto [end, error] = std::from_chars(token.data(), token.data() + token.size(), value);
    return error == std::errc() && end == token.data() + token.size();
}

/// "+x" → (0, +1), …; false for anything else.
bool parse_direction(std::string_view token, int& axis, int& sign) {
    if (token.size() != 2 || (token[0] != '+' && token[0] != '-')) return false;
    const char letter = char(token[1] | 0x20);  // lower case
    if (letter < 'x' || letter > 'z') return false;
    axis = letter - 'x';
    sign = token[0] == '+' ? 1 : -1;
    return true;
}

/// Reads lines of at most kMaxLineLength characters.
class LineReader {
public:
    LineReader(std::istream& in, const std::string& name) : in_(in), name_(name) {}

    bool next(std::string_view& line) {
        if (in_.eof()) return false;
        in_.getline(buffer_, sizeof buffer_);
        if (in_.bad()) throw Error(name_ + ": read error after line " + std::to_string(number_));
        const std::streamsize extracted = in_.gcount();
        if (in_.fail()) {
            if (in_.eof() && extracted == 0) return false;
            throw Error(where(number_ + 1) + ": line longer than " + std::to_string(kMaxLineLength) + " characters");
        }
        ++number_;
        const std::size_t length = std::size_t(extracted) - (in_.eof() ? 0 : 1);  // without the '\n'
        line = std::string_view(buffer_, length);
        if (number_ == 1 && line.substr(0, 3) == "\xEF\xBB\xBF") line.remove_prefix(3);  // UTF-8 byte order mark
        return true;
    }

    std::int64_t number() const { return number_; }
    std::string where(std::int64_t line) const { return name_ + ":" + std::to_string(line); }
    std::string here() const { return where(number_); }

private:
    std::istream& in_;
    const std::string& name_;
    char buffer_[kMaxLineLength + 1];
    std::int64_t number_ = 0;
};

/// One parsed data line.
struct NormalLine {
    std::int64_t voxel[3];
    int axis, sign;
    Eigen::RowVector3d normal;
};

NormalLine parse_normal_line(const std::vector<std::string_view>& fields, const LineReader& reader) {
    if (fields.size() != 7)
        throw Error(reader.here() + ": expected 7 fields 'i j k direction nx ny nz', found " + std::to_string(fields.size()));
    NormalLine parsed{};
    for (int d = 0; d < 3; ++d)
        if (!parse_integer(fields[std::size_t(d)], parsed.voxel[d]))
            throw Error(reader.here() + ": voxel index " + quoted(fields[std::size_t(d)]) + " is not an integer");
    if (!parse_direction(fields[3], parsed.axis, parsed.sign))
        throw Error(reader.here() + ": direction " + quoted(fields[3]) + " is not one of +x -x +y -y +z -z");
    for (int d = 0; d < 3; ++d) {
        double value = 0;
        if (!parse_real(fields[std::size_t(4 + d)], value))
            throw Error(reader.here() + ": normal component " + quoted(fields[std::size_t(4 + d)]) + " is not a number");
        parsed.normal[d] = value;
    }
    if (!parsed.normal.allFinite()) throw Error(reader.here() + ": the normal is not finite (NaN or infinity)");
    const double largest = parsed.normal.cwiseAbs().maxCoeff();
    if (!(largest > 0)) throw Error(reader.here() + ": the normal is zero");
    double length = parsed.normal.norm();
    if (!(length > 0) || !std::isfinite(length)) {
        // |n|² under- or overflows (components near 1e-160 or 1e160): scale by the largest first.
        parsed.normal /= largest;
        length = parsed.normal.norm();
    }
    if (std::abs(length - 1) > 1e-12) parsed.normal /= length;
    return parsed;
}

std::string surfel_text(const std::int64_t voxel[3], const Surfel& direction) {
    return "voxel " + std::to_string(voxel[0]) + " " + std::to_string(voxel[1]) + " " + std::to_string(voxel[2]) +
           " direction " + surfel_direction_name(direction);
}

void write_number(std::ostream& out, double x) {
    char text[32];
    const auto end = std::to_chars(text, text + sizeof text, x).ptr;  // shortest form that reads back exactly
    out.write(text, end - text);
}

}  // namespace

std::string surfel_direction_name(const Surfel& surfel) {
    return std::string(1, surfel.sign > 0 ? '+' : '-') + char('x' + surfel.axis);
}

PointMatrix read_normals(std::istream& in, const std::string& name, const DigitalSurface& surface) {
    const SurfelLookup lookup(surface);
    const VoxelGrid& grid = surface.grid;
    const std::int64_t m = surface.face_count();
    PointMatrix normals(m, 3);
    std::vector<std::int64_t> line_of_face(std::size_t(m), 0);  // 0 = not given yet
    LineReader reader(in, name);
    std::string_view line;
    while (reader.next(line)) {
        const std::vector<std::string_view> fields = split_fields(line);
        if (fields.empty()) continue;
        const NormalLine parsed = parse_normal_line(fields, reader);
        const Surfel direction{{0, 0, 0}, std::int8_t(parsed.axis), std::int8_t(parsed.sign)};
        const std::int64_t* v = parsed.voxel;
        if (!grid.contains(v[0], v[1], v[2]))
            throw Error(reader.here() + ": voxel " + std::to_string(v[0]) + " " + std::to_string(v[1]) + " " +
                        std::to_string(v[2]) + " is outside the grid of " + std::to_string(grid.dims[0]) + "x" +
                        std::to_string(grid.dims[1]) + "x" + std::to_string(grid.dims[2]) + " voxels");
        const std::int32_t f = lookup.find(surfel_key(grid, v[0], v[1], v[2], parsed.axis, parsed.sign));
        if (f < 0)
            throw Error(reader.here() + ": " + surfel_text(v, direction) +
                        " is not a surfel of the surface (not an object voxel with background on that side)");
        std::int64_t& given = line_of_face[std::size_t(f)];
        if (given != 0)
            throw Error(reader.here() + ": " + surfel_text(v, direction) + " was already given on line " +
                        std::to_string(given));
        given = reader.number();
        normals.row(f) = parsed.normal;
    }
    const auto missing = std::find(line_of_face.begin(), line_of_face.end(), 0);
    if (missing != line_of_face.end()) {
        const std::int64_t count = std::count(line_of_face.begin(), line_of_face.end(), 0);
        const Surfel& s = surface.surfels[std::size_t(missing - line_of_face.begin())];
        const std::int64_t voxel[3] = {s.voxel[0], s.voxel[1], s.voxel[2]};
        throw Error(name + ": no normal for " + std::to_string(count) + " of the " + std::to_string(m) +
                    " surfels, e.g. " + surfel_text(voxel, s) + " (the file needs one line per surfel)");
    }
    return normals;
}

PointMatrix read_normals_file(const std::string& path, const DigitalSurface& surface) {
    errno = 0;
    std::ifstream in(path, std::ios::binary);
    if (!in) throw FileError(path + ": cannot open the normals file", errno);
    return read_normals(in, path, surface);
}

void write_normals_file(const std::string& path, const DigitalSurface& surface, const PointMatrix& normals,
                        const std::string& description) {
    if (normals.rows() != surface.face_count())
        throw Error(path + ": " + std::to_string(normals.rows()) + " normals for " + std::to_string(surface.face_count()) +
                    " surfels");
    const VoxelGrid& g = surface.grid;
    write_file_atomically(path, [&](std::ostream& out) {
        out << "# dsreg normals: one line per surfel: i j k direction nx ny nz\n"
            << "#   i j k: 0-based object voxel in the grid of " << g.dims[0] << "x" << g.dims[1] << "x" << g.dims[2]
            << " voxels (voxel (0,0,0) centred at " << g.origin.x() << " " << g.origin.y() << " " << g.origin.z()
            << ", spacing " << g.spacing.x() << " " << g.spacing.y() << " " << g.spacing.z() << ")\n"
            << "#   direction: the face's side of the voxel (+x -x +y -y +z -z; that neighbour is background)\n"
            << "#   nx ny nz: unit outward normal, physical coordinates\n";
        std::string field = description;
        std::replace(field.begin(), field.end(), '\n', ' ');
        if (!field.empty()) out << "# field: " << field << "\n";
        for (std::int64_t f = 0; f < surface.face_count(); ++f) {
            const Surfel& s = surface.surfels[std::size_t(f)];
            out << s.voxel[0] << ' ' << s.voxel[1] << ' ' << s.voxel[2] << ' ' << surfel_direction_name(s);
            for (int d = 0; d < 3; ++d) out << ' ', write_number(out, normals(f, d));
            out << '\n';
        }
    });
}

}  // namespace dsreg
