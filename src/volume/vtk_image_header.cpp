// dsreg — the header of a legacy VTK image (DATASET STRUCTURED_POINTS), checked before ITK reads it.
//
// ITK's reader (5.2) scans each header line as a C string: a line cut by a NUL byte
// ("SPACING 7.5\0...") or a keyword run into its first number ("SPACINGz7.5 ...") left spacings
// unset, taken from uninitialized memory, so two reads of one file gave two grids (both found by
// fuzzing). So the header lines (all but the title) must be text, and a line ITK takes for
// DIMENSIONS, SPACING (or ASPECT_RATIO) or ORIGIN must give three numbers after its first word;
// POINT_DATA must count the voxels, and a binary payload must hold them (check_payload) from
// where ITK's header ends (check_after_scalars).
#include <cmath>
#include <optional>
#include <string>
#include <vector>

#include "dsreg/text.hpp"

#include "text_header.hpp"
#include "volume_io_internal.hpp"

namespace dsreg::volume_io_detail {

namespace {

constexpr std::uint64_t kMaxHeaderBytes = 1 << 16;

bool is_text(const std::string& line) {
    for (const char c : line)
        if (static_cast<unsigned char>(c) < 0x20 && c != '\t') return false;
    return true;
}

/// The geometry keyword ITK finds in a header line: it looks for each anywhere in the line (in
/// this order), then reads the three numbers after the line's first word.
const char* geometry_keyword(const std::string& lower_line) {
    for (const char* keyword : {"dimensions", "spacing", "aspect_ratio", "origin"})
        if (lower_line.find(keyword) != std::string::npos) return keyword;
    return nullptr;
}

/// DIMENSIONS: three positive integers; SPACING, ASPECT_RATIO, ORIGIN: three finite numbers.
void check_geometry_line(const InputFile& file, std::int64_t number, const std::string& keyword,
                         const std::vector<std::string>& words) {
    const std::string where = "header line " + std::to_string(number) + " ('" + words[0] + "', read as " + keyword + ")";
    if (words.size() != 4) file.fail(where + " gives " + std::to_string(words.size() - 1) + " values, not 3");
    for (std::size_t w = 1; w < 4; ++w) {
        std::int64_t size = 0;
        const std::optional<double> value = parse_whole_number(words[w]);
        if (keyword == "dimensions" ? !parse_integer(words[w], size) || size < 1
                                    : !value || !std::isfinite(*value) || std::abs(*value) > 1e10)
            file.fail(where + ": '" + words[w] + "' is not a " + (keyword == "dimensions" ? "positive integer" : "plausible finite number"));
    }
}

/// What the header says of the voxels that follow it.
struct VtkImageHeader {
    bool binary = false;
    std::int64_t voxels = 0;      ///< DIMENSIONS' product, 0 before that line
    std::int64_t point_data = 0;  ///< POINT_DATA's count, 0 before that line
    int value_bytes = 0;          ///< of the SCALARS type, 0 if unknown
    std::int64_t components = 1;
};

/// Bytes of a VTK scalar type name, or 0.
int vtk_type_bytes(const std::string& type) {
    if (type == "char" || type == "unsigned_char") return 1;
    if (type == "short" || type == "unsigned_short") return 2;
    if (type == "int" || type == "unsigned_int" || type == "float") return 4;
    if (type == "long" || type == "unsigned_long" || type == "double") return 8;
    return 0;
}

/// What ITK takes from a header line: it looks for each keyword anywhere in the (lower-case)
/// line, and reads the words after the first ("SCAM-*ARS scalars short 1" has short scalars).
void note_line(const std::string& lower_line, const std::vector<std::string>& words, VtkImageHeader& header) {
    const auto has = [&](const char* keyword) { return lower_line.find(keyword) != std::string::npos; };
    std::int64_t value = 0;
    if (has("dimensions") && header.voxels == 0) {  // ITK reads the first (line 5), no later one
        header.voxels = 1;
        for (std::size_t w = 1; w < 4; ++w)
            header.voxels = parse_integer(words[w], value) && value < (1 << 20) ? header.voxels * value : -1;
    } else if (has("point_data") && words.size() == 2 && parse_integer(words[1], value)) {
        header.point_data = value;
    } else if (has("scalars") && words.size() >= 3) {
        header.value_bytes = vtk_type_bytes(to_lower(words[2]));
        if (words.size() >= 4 && parse_integer(words[3], value)) header.components = value;
    }
}

/// POINT_DATA counts the voxels, and a binary payload holds them all: ITK's reader took a
/// short one without a word, leaving the last voxels unset (found by fuzzing).
void check_payload(const InputFile& file, const VtkImageHeader& header) {
    if (header.voxels > 0 && header.point_data != header.voxels)
        file.fail("POINT_DATA " + std::to_string(header.point_data) + " differs from the " + std::to_string(header.voxels) +
                  " voxels of DIMENSIONS");
    if (!header.binary || header.value_bytes == 0 || header.voxels <= 0 || header.components < 1 || header.components > 4) return;
    const std::uint64_t needed = static_cast<std::uint64_t>(header.voxels * header.components * header.value_bytes);
    if (file.remaining() < needed)
        file.fail("truncated payload: the header says " + std::to_string(header.voxels) + " voxels of " +
                  std::to_string(header.components * header.value_bytes) + " bytes = " + std::to_string(needed) +
                  " bytes, the file holds " + std::to_string(file.remaining()) + " after the header");
}

/// Reads the next line (at most 1 KiB of it): whether it holds LOOKUP_TABLE, as ITK looks for it.
bool next_line_is_lookup_table(InputFile& file) {
    std::string next;
    for (int c = file.get(); c != -1 && c != '\n' && next.size() < 1024; c = file.get()) next.push_back(static_cast<char>(c));
    return to_lower(next).find("lookup_table") != std::string::npos;
}

/// Where ITK's header ends: after the SCALARS line, or after the next one if it holds
/// LOOKUP_TABLE (ITK reads that line, and steps back unless it does: a garbled one found by
/// fuzzing was payload). Then checks the payload from there.
void check_after_scalars(InputFile& file, const VtkImageHeader& header) {
    const std::uint64_t payload = file.position();
    if (!next_line_is_lookup_table(file)) file.seek(payload);
    check_payload(file, header);
}

/// COLOR_SCALARS: unsigned bytes in a binary file, as many per voxel as the line's third word
/// says (1 if none), right after the line. ITK's whole read took a short payload without a word
/// (found by fuzzing), and does not skip a LOOKUP_TABLE line there where its streaming read does
/// (a box would not be the crop of the whole): such a line is refused.
void check_after_color_scalars(InputFile& file, VtkImageHeader header, const std::vector<std::string>& words) {
    std::int64_t components = 1;
    header.value_bytes = 1;
    header.components = words.size() >= 3 && parse_integer(words[2], components) ? components : 1;
    const std::uint64_t payload = file.position();
    if (next_line_is_lookup_table(file))
        file.fail("a LOOKUP_TABLE line after COLOR_SCALARS (ITK's reader takes it for voxels or skips it, depending on the read)");
    file.seek(payload);
    check_payload(file, header);
}

}  // namespace

void check_vtk_image_header(const std::string& path) {
    InputFile file(path);
    VtkImageHeader header;
    std::string line;
    // ITK skips empty lines (no byte before the newline) and counts the others: `itk_line` is the
    // line as ITK numbers it (a blank line before BINARY made ITK read a binary payload that
    // this walk took for ASCII, unchecked; found by fuzzing), `number` the line in the file.
    std::int64_t itk_line = 0;
    for (std::int64_t number = 1;; ++number) {
        const std::uint64_t start = file.position();
        if (!read_header_line(file, line, kMaxHeaderBytes)) break;
        if (file.position() == start + 1 && line.empty()) continue;
        if (++itk_line == 2) continue;  // the title: free text
        if (!is_text(line)) file.fail("header line " + std::to_string(number) + " holds control characters (a NUL byte?)");
        const std::vector<std::string> words = split_words(line);
        if (words.empty()) continue;
        const std::string lower_line = to_lower(line);
        header.binary = itk_line == 3 ? lower_line.find("ascii") == std::string::npos && lower_line.find("binary") != std::string::npos
                                      : header.binary;
        if (itk_line < 5) continue;  // the version, the file type and the data set line: ITK reads no keyword there
        if (const char* geometry = geometry_keyword(lower_line)) {
            check_geometry_line(file, number, geometry, words);
        } else if (lower_line.find("vector") != std::string::npos) {
            return;  // VECTORS (ITK looks for this first): 3 components, which dsreg refuses after the header
        } else if (lower_line.find("color_scalars") != std::string::npos) {
            return check_after_color_scalars(file, header, words);
        }
        note_line(lower_line, words, header);
        if (lower_line.find("scalars") != std::string::npos) return check_after_scalars(file, header);
    }
}

}  // namespace dsreg::volume_io_detail
