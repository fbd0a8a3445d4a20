// dsreg — the file meta information of a DICOM file (group 0002 after the "DICM" preamble),
// checked before GDCM reads it.
//
// Debian's GDCM is built with its assertions on, and its reader of the meta information asserts
// instead of failing where the file ends inside that group, or right after it (found by mutating
// a small file: 11 of 300 mutations aborted the process). The group is always explicit VR little
// endian (PS3.10 7.1), so it is simple to walk: every element must fit in the file, name a value
// representation, and a data set must follow.
#include <array>
#include <cstdint>
#include <string>

#include "volume_io_internal.hpp"

namespace dsreg::volume_io_detail {

namespace {

constexpr std::uint64_t kPreambleBytes = 128;

/// Value representations whose length takes 4 bytes after 2 reserved ones (PS3.5 7.1.2).
bool has_long_length(const std::string& vr) {
    static const std::array<const char*, 13> long_ones = {"OB", "OD", "OF", "OL", "OV", "OW", "SQ",
                                                          "SV", "UC", "UN", "UR", "UT", "UV"};
    for (const char* name : long_ones)
        if (vr == name) return true;
    return false;
}

bool is_value_representation(const std::string& vr) {
    static const std::array<const char*, 21> short_ones = {"AE", "AS", "AT", "CS", "DA", "DS", "DT", "FL", "FD", "IS", "LO",
                                                           "LT", "PN", "SH", "SL", "SS", "ST", "TM", "UI", "UL", "US"};
    if (has_long_length(vr)) return true;
    for (const char* name : short_ones)
        if (vr == name) return true;
    return false;
}

/// "(0002,xxxx)" in hexadecimal, as DICOM names its tags.
std::string element_name(std::uint64_t element) {
    static const char* digits = "0123456789ABCDEF";
    std::string name = "(0002,";
    for (int shift = 12; shift >= 0; shift -= 4) name += digits[(element >> shift) & 0xf];
    return name + ")";
}

}  // namespace

void check_dicom_meta(const std::string& path) {
    InputFile file(path);
    const std::uint64_t size = file.size();
    if (size < kPreambleBytes + 4) return;  // no preamble: GDCM's other paths
    const auto read_at = [&](std::uint64_t offset, std::size_t count) {
        std::string out(count, '\0');
        file.seek(offset);
        if (file.read(reinterpret_cast<std::uint8_t*>(out.data()), count) != count) file.fail("read error");
        return out;
    };
    if (read_at(kPreambleBytes, 4) != "DICM") return;
    std::uint64_t at = kPreambleBytes + 4;
    const auto bytes_at = [&](std::uint64_t offset, std::size_t count, const char* what) {
        if (offset + count > size) file.fail("the file ends inside its DICOM meta information (" + std::string(what) + ")");
        return read_at(offset, count);
    };
    const auto little = [](const std::string& b, std::size_t first, std::size_t count) {
        std::uint64_t value = 0;
        for (std::size_t k = count; k-- > 0;) value = value << 8 | std::uint8_t(b[first + k]);
        return value;
    };
    for (int element = 0;; ++element) {
        if (at == size) file.fail("the file holds DICOM meta information and no data set");
        const std::string tag = bytes_at(at, 4, "an element's tag");
        if (little(tag, 0, 2) != 0x0002) return;  // the data set begins
        if (element > 10000) file.fail("more than 10000 elements of DICOM meta information");
        const std::string vr = bytes_at(at + 4, 2, "an element's value representation");
        if (!is_value_representation(vr))
            file.fail("DICOM meta information element " + element_name(little(tag, 2, 2)) +
                      " has no explicit value representation");
        std::uint64_t length = 0, header = 8;
        if (has_long_length(vr)) {
            length = little(bytes_at(at + 8, 4, "an element's length"), 0, 4);
            header = 12;
            if (length == 0xffffffffu) file.fail("DICOM meta information with an element of undefined length");
        } else {
            length = little(bytes_at(at + 6, 2, "an element's length"), 0, 2);
        }
        if (at + header + length > size) file.fail("the file ends inside its DICOM meta information (an element's value)");
        at += header + length;
    }
}

}  // namespace dsreg::volume_io_detail
