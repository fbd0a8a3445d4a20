// dsreg — the file meta information of a DICOM file (group 0002 after the "DICM" preamble),
// checked before GDCM reads it.
//
// Debian's GDCM is built with its assertions on, and its reader of the meta information asserts
// instead of failing where the file ends inside that group, or right after it (found by mutating
// a small file: 11 of 300 mutations aborted the process). The group is always explicit VR little
// endian (PS3.10 7.1), so it is simple to walk: every element must fit in the file, name a value
// representation, and a data set must follow. The data set is walked too, for the lengths of
// its elements (check_data_set_lengths).
#include <algorithm>
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

/// Four hexadecimal digits, as DICOM writes the halves of its tags.
std::string hex4(std::uint64_t number) {
    static const char* digits = "0123456789ABCDEF";
    std::string text;
    for (int shift = 12; shift >= 0; shift -= 4) text += digits[(number >> shift) & 0xf];
    return text;
}

/// "(0002,xxxx)", as DICOM names its tags.
std::string element_name(std::uint64_t element) { return "(0002," + hex4(element) + ")"; }

}  // namespace

/// A UID as stored: without its padding (a NUL or a space to an even length).
std::string trimmed_uid(std::string uid) {
    while (!uid.empty() && (uid.back() == '\0' || uid.back() == ' ')) uid.pop_back();
    return uid;
}

/// Reads little- or big-endian unsigned integers of 2 or 4 bytes out of `bytes`.
std::uint64_t unsigned_at(const std::string& bytes, std::size_t first, std::size_t count, bool big_endian) {
    std::uint64_t value = 0;
    for (std::size_t k = 0; k < count; ++k) {
        const std::size_t at = big_endian ? first + k : first + count - 1 - k;
        value = value << 8 | std::uint8_t(bytes[at]);
    }
    return value;
}

/// GDCM asserts on values it takes for impossible: Samples per Pixel (0028,0002) other than 1,
/// 3 or 4 aborted the process (found by fuzzing).
void check_element_value(InputFile& file, std::uint64_t group, std::uint64_t element, std::uint64_t at,
                         std::uint64_t length, bool big_endian) {
    if (group != 0x0028 || element != 0x0002 || length != 2) return;
    std::string value(2, '\0');
    file.seek(at);
    if (file.read(reinterpret_cast<std::uint8_t*>(value.data()), 2) != 2) return;
    const std::uint64_t samples = unsigned_at(value, 0, 2, big_endian);
    if (samples != 1 && samples != 3 && samples != 4)
        file.fail("Samples per Pixel (0028,0002) is " + std::to_string(samples) + " (DICOM allows 1, 3 or 4)");
}

/// The data set after the meta information, walked element by element in its transfer syntax
/// (top level, and inside sequences and items of undefined length): every value must fit in
/// the file. GDCM allocates what an element's length says before reading it (an element of
/// 1.9 GB in a 1 KB file, found by fuzzing). Values of defined length are skipped whole, so what
/// they nest is left to GDCM; so is a deflated data set. An element of an explicit VR syntax
/// without a VR is read as implicit, as GDCM reads it (an 0.8 GB one hung the fuzzer in GDCM).
void check_data_set_lengths(InputFile& file, std::uint64_t at, const std::string& transfer_syntax) {
    const bool implicit = transfer_syntax == "1.2.840.10008.1.2";
    const bool big_endian = transfer_syntax == "1.2.840.10008.1.2.2";
    if (transfer_syntax == "1.2.840.10008.1.2.1.99") return;  // deflated
    const std::uint64_t size = file.size();
    std::string head(12, '\0');
    while (at + 8 <= size) {
        file.seek(at);
        const std::size_t got = file.read(reinterpret_cast<std::uint8_t*>(head.data()), 12);
        const std::uint64_t group = unsigned_at(head, 0, 2, big_endian), element = unsigned_at(head, 2, 2, big_endian);
        const std::string vr = head.substr(4, 2);
        std::uint64_t length = 0, header = 8;
        if (implicit || group == 0xfffe || !is_value_representation(vr)) {  // no VR: GDCM reads it as implicit
            length = unsigned_at(head, 4, 4, big_endian);
        } else if (has_long_length(vr)) {
            if (got < 12) file.fail("the file ends inside a data element's header");
            length = unsigned_at(head, 8, 4, big_endian), header = 12;
        } else {
            length = unsigned_at(head, 6, 2, big_endian);
        }
        at += header;
        if (length == 0xffffffffu) continue;  // undefined length: its elements follow
        if (length > size - std::min(at, size))
            file.fail("data element (" + hex4(group) + "," + hex4(element) + ") announces " + std::to_string(length) +
                      " bytes, but the file holds " + std::to_string(size - std::min(at, size)) + " after it");
        check_element_value(file, group, element, at, length, big_endian);
        at += length;
    }
    if (at < size)  // GDCM asserted on an element cut inside its tag or length (found by fuzzing)
        file.fail("the file ends inside a data element's header (" + std::to_string(size - at) + " bytes after the last element)");
}

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
    std::string transfer_syntax;
    for (int element = 0;; ++element) {
        if (at == size) file.fail("the file holds DICOM meta information and no data set");
        const std::string tag = bytes_at(at, 4, "an element's tag");
        if (little(tag, 0, 2) != 0x0002) return check_data_set_lengths(file, at, transfer_syntax);
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
        if (little(tag, 2, 2) == 0x0010) transfer_syntax = trimmed_uid(read_at(at + header, static_cast<std::size_t>(length)));
        at += header + length;
    }
}

}  // namespace dsreg::volume_io_detail
