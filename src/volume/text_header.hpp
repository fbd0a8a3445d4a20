// dsreg — small helpers for the text headers of NRRD and MetaImage files (not public API).
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "dsreg/error.hpp"
#include "volume_io_internal.hpp"

namespace dsreg::volume_io_detail {

/// `text` without leading and trailing spaces, tabs and carriage returns.
std::string trim(const std::string& text);

/// Lower-case ASCII copy.
std::string to_lower(std::string text);

/// Reads one line (without its '\n' or a trailing '\r'). Returns false at the end of the file when
/// no character was read. Throws (naming the file) once the header passes `max_header_bytes`.
bool read_header_line(InputFile& file, std::string& line, std::uint64_t max_header_bytes);

/// The whitespace-separated words of `text`.
std::vector<std::string> split_words(const std::string& text);

/// Whole-string parse of a decimal integer with an optional sign. False otherwise or on overflow.
bool parse_integer(const std::string& text, std::int64_t& value);

/// Checks the numbers of a geometry field (origin, spacing, direction cosines: tokens separated
/// by spaces, commas or parentheses; "none" skipped) and throws, naming the file and `field`,
/// for one that is not a finite number of magnitude at most 1e10. ITK's readers must never see
/// such values (ITK 5.2 aborts the process on a NaN in a NIfTI sform).
void check_geometry_numbers(const InputFile& file, const std::string& field, const std::string& text);

/// Skips `count` lines of the file (up to and including their '\n'); throws if it ends before.
void skip_lines(InputFile& file, std::int64_t count, const std::string& field);

/// `name` as written in a header, resolved against the folder of the header file.
std::string path_beside(const std::string& header_path, const std::string& name);

/// Opens the data file that `field` of the header `header_path` names (relative to the header's
/// folder). Throws dsreg::Error starting with the header's path for a name with control
/// characters, a missing file, or anything but a regular file.
std::unique_ptr<InputFile> open_data_file(const std::string& header_path, const std::string& name, const std::string& field);

/// Runs `read`; an error about a detached data file (whose message starts with that file's path)
/// is given again starting with the header's path, so that every message names the file the
/// user gave.
template <typename Read>
void naming_header(const std::string& header_path, Read&& read) {
    try {
        read();
    } catch (const Error& error) {
        const std::string message = error.what();
        if (message.rfind(header_path + ": ", 0) == 0) throw;
        throw Error(header_path + ": in its data file, " + message);
    }
}

}  // namespace dsreg::volume_io_detail
