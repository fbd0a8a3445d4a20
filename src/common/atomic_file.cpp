#include "dsreg/atomic_file.hpp"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>

#include "dsreg/error.hpp"

namespace dsreg {

namespace {

std::string temporary_sibling(const std::string& path) {
    std::random_device rd;
    const std::filesystem::path p(path);
    const std::string name = "." + p.filename().string() + ".tmp" + std::to_string(rd() % 1000000);
    return (p.parent_path() / name).string();
}

}  // namespace

void write_file_atomically(const std::string& path, const std::function<void(std::ostream&)>& write) {
    const std::string tmp = temporary_sibling(path);
    try {
        {
            errno = 0;
            std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
            if (!out) throw FileError(path + ": cannot create file for writing", errno);
            write(out);
            out.flush();
            if (!out) throw FileError(path + ": write failed (disk full?)", errno);
        }
        std::error_code ec;
        std::filesystem::rename(tmp, path, ec);
        if (ec) throw FileError(path + ": cannot rename temporary file into place: " + ec.message(), ec.value());
    } catch (...) {
        std::error_code ignored;
        std::filesystem::remove(tmp, ignored);
        throw;
    }
}

std::string file_extension(const std::string& path) {
    std::string ext = std::filesystem::path(path).extension().string();
    if (!ext.empty() && ext[0] == '.') ext.erase(0, 1);
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    return ext;
}

}  // namespace dsreg
