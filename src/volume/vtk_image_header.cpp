// dsreg — the header of a legacy VTK image (DATASET STRUCTURED_POINTS), checked before ITK reads it.
//
// ITK's reader (5.2) scans each header line as a C string: a line cut by a NUL byte
// ("SPACING 7.5\0...") left the other spacings unset, taken from uninitialized memory, so two
// reads of one file gave two grids (found by fuzzing). So the header lines (all but the title)
// must be text, and DIMENSIONS, SPACING (or ASPECT_RATIO) and ORIGIN must give three numbers.
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

/// DIMENSIONS: three positive integers; SPACING, ASPECT_RATIO, ORIGIN: three finite numbers.
void check_geometry_line(const InputFile& file, std::int64_t number, const std::string& keyword,
                         const std::vector<std::string>& words) {
    const std::string where = "header line " + std::to_string(number) + " ('" + words[0] + "')";
    if (words.size() != 4) file.fail(where + " gives " + std::to_string(words.size() - 1) + " values, not 3");
    for (std::size_t w = 1; w < 4; ++w) {
        std::int64_t size = 0;
        const std::optional<double> value = parse_whole_number(words[w]);
        if (keyword == "dimensions" ? !parse_integer(words[w], size) || size < 1
                                    : !value || !std::isfinite(*value) || std::abs(*value) > 1e10)
            file.fail(where + ": '" + words[w] + "' is not a " + (keyword == "dimensions" ? "positive integer" : "plausible finite number"));
    }
}

}  // namespace

void check_vtk_image_header(const std::string& path) {
    InputFile file(path);
    std::string line;
    for (std::int64_t number = 1; read_header_line(file, line, kMaxHeaderBytes); ++number) {
        if (number == 2) continue;  // the title: free text
        if (!is_text(line)) file.fail("header line " + std::to_string(number) + " holds control characters (a NUL byte?)");
        const std::vector<std::string> words = split_words(line);
        if (words.empty()) continue;
        const std::string keyword = to_lower(words[0]);
        if (keyword == "dimensions" || keyword == "spacing" || keyword == "aspect_ratio" || keyword == "origin")
            check_geometry_line(file, number, keyword, words);
        if (keyword == "lookup_table") return;  // the voxels follow
    }
}

}  // namespace dsreg::volume_io_detail
