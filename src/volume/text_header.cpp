#include "text_header.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <limits>

namespace dsreg::volume_io_detail {

std::string trim(const std::string& text) {
    const char* spaces = " \t\r";
    const std::size_t first = text.find_first_not_of(spaces);
    if (first == std::string::npos) return "";
    return text.substr(first, text.find_last_not_of(spaces) - first + 1);
}

std::string to_lower(std::string text) {
    std::transform(text.begin(), text.end(), text.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    return text;
}

bool read_header_line(InputFile& file, std::string& line, std::uint64_t max_header_bytes) {
    line.clear();
    bool any = false;
    for (int c = file.get(); c != -1; c = file.get()) {
        any = true;
        if (c == '\n') break;
        if (file.position() > max_header_bytes)
            file.fail("the header does not end within its first " + std::to_string(max_header_bytes) + " bytes");
        line.push_back(static_cast<char>(c));
    }
    if (!line.empty() && line.back() == '\r') line.pop_back();
    return any;
}

std::vector<std::string> split_words(const std::string& text) {
    std::vector<std::string> words;
    std::string word;
    for (const char c : text) {
        if (c == ' ' || c == '\t' || c == '\r' || c == '\n') {
            if (!word.empty()) words.push_back(word);
            word.clear();
        } else {
            word.push_back(c);
        }
    }
    if (!word.empty()) words.push_back(word);
    return words;
}

bool parse_integer(const std::string& text, std::int64_t& value) {
    std::size_t start = 0;
    bool negative = false;
    if (!text.empty() && (text[0] == '-' || text[0] == '+')) {
        negative = text[0] == '-';
        start = 1;
    }
    if (start >= text.size()) return false;
    std::int64_t result = 0;
    for (std::size_t i = start; i < text.size(); ++i) {
        const char c = text[i];
        if (c < '0' || c > '9') return false;
        const int digit = c - '0';
        if (result > (std::numeric_limits<std::int64_t>::max() - digit) / 10) return false;
        result = result * 10 + digit;
    }
    value = negative ? -result : result;
    return true;
}

void check_geometry_numbers(const InputFile& file, const std::string& field, const std::string& text) {
    std::string token;
    const auto check = [&] {
        if (token.empty() || to_lower(token) == "none") return;
        char* end = nullptr;
        const double value = std::strtod(token.c_str(), &end);
        if (end != token.c_str() + token.size() || !std::isfinite(value) || std::abs(value) > 1e10)
            file.fail(field + ": " + quote_excerpt(token) + " is not a plausible finite number");
        token.clear();
    };
    for (const char c : text) {
        if (c == ' ' || c == '\t' || c == ',' || c == '(' || c == ')') {
            check();
            token.clear();
        } else {
            token.push_back(c);
        }
    }
    check();
}

void skip_lines(InputFile& file, std::int64_t count, const std::string& field) {
    for (std::int64_t line = 0; line < count; ++line) {
        int c = file.get();
        while (c != -1 && c != '\n') c = file.get();
        if (c == -1)
            file.fail("the data ends before the " + std::to_string(count) + " lines that '" + field + "' says to skip");
    }
}

std::string path_beside(const std::string& header_path, const std::string& name) {
    const std::filesystem::path data(name);
    if (data.is_absolute()) return data.string();
    return (std::filesystem::path(header_path).parent_path() / data).string();
}

std::unique_ptr<InputFile> open_data_file(const std::string& header_path, const std::string& name, const std::string& field) {
    for (const char c : name)
        if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f)
            fail(header_path, field + " names a file with control characters: " + quote_excerpt(name));
    const std::string data_path = path_beside(header_path, name);
    std::error_code error;
    const auto status = std::filesystem::status(data_path, error);
    if (!std::filesystem::exists(status)) fail(header_path, "its data file " + data_path + " (" + field + ") does not exist");
    if (!std::filesystem::is_regular_file(status))
        fail(header_path, "its data file " + data_path + " (" + field + ") is not a regular file");
    std::unique_ptr<InputFile> file;
    naming_header(header_path, [&] { file = std::make_unique<InputFile>(data_path); });
    return file;
}

}  // namespace dsreg::volume_io_detail
