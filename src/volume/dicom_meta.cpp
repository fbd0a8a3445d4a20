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
#include <optional>
#include <string>

#include "dsreg/text.hpp"
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

/// A UID as stored: without its padding (a NUL or a space to an even length).
std::string trimmed_uid(std::string uid) {
    while (!uid.empty() && (uid.back() == '\0' || uid.back() == ' ')) uid.pop_back();
    return uid;
}

/// The little- or big-endian unsigned integer of 2 or 4 bytes at `first` in `bytes`.
std::uint64_t unsigned_at(const std::string& bytes, std::size_t first, std::size_t count, bool big_endian) {
    return unsigned_integer(reinterpret_cast<const std::uint8_t*>(bytes.data()) + first, count, big_endian);
}

/// The image pixel module of the data set's top level, as far as the walk has read it.
struct PixelModule {
    std::uint64_t rows = 0, columns = 0, frames = 1, samples = 1, bits = 0, bits_stored = 0, pixel_representation = 0;
    std::uint64_t pixel_bytes = 0;  ///< the length of a native Pixel Data element
    bool native_pixels = false;
};

std::string value_at(InputFile& file, std::uint64_t at, std::uint64_t length) {
    std::string value(static_cast<std::size_t>(length), '\0');
    file.seek(at);
    if (file.read(reinterpret_cast<std::uint8_t*>(value.data()), value.size()) != value.size()) value.clear();
    return value;
}

/// Notes the pixel module's elements (top level: an icon sequence has its own). GDCM asserts on
/// Samples per Pixel other than 1, 3 or 4 (an abort, found by fuzzing).
void note_element(InputFile& file, std::uint64_t tag, std::uint64_t at, std::uint64_t length, bool big_endian,
                  PixelModule& pixels) {
    if (tag == 0x7fe00010) {
        pixels.native_pixels = true;
        pixels.pixel_bytes = length;
    }
    if (tag == 0x00080010) {  // Recognition Code (ACR-NEMA): GDCM asserts on any other value (found by fuzzing)
        const std::string code = value_at(file, at, std::min<std::uint64_t>(length, 8));
        if (code.rfind("ACR-NEMA", 0) != 0 && code.rfind("ACRNEMA", 0) != 0 && code.rfind("MIPS 2.0", 0) != 0)
            file.fail("Recognition Code (0008,0010) is neither ACR-NEMA nor MIPS 2.0");
    }
    if (tag == 0x00280008 && length <= 12) {  // Number of Frames, a decimal string
        const std::optional<double> frames = parse_whole_number(trimmed_uid(value_at(file, at, length)));
        if (frames && *frames >= 1 && *frames < 1e9) pixels.frames = static_cast<std::uint64_t>(*frames);
    }
    if (tag != 0x00280002 && tag != 0x00280010 && tag != 0x00280011 && tag != 0x00280100 && tag != 0x00280101 && tag != 0x00280103)
        return;
    if (length != 2)  // one US value; GDCM read 2 of the 12 bytes of one as Samples per Pixel and asserted (fuzzing)
        file.fail("pixel module element (0028," + hex4(tag & 0xffff) + ") holds " + std::to_string(length) +
                  " bytes, not one 2-byte value");
    const std::string value = value_at(file, at, 2);
    if (value.size() != 2) return;
    const std::uint64_t number = unsigned_at(value, 0, 2, big_endian);
    if (tag == 0x00280002 && number != 1 && number != 3 && number != 4)
        file.fail("Samples per Pixel (0028,0002) is " + std::to_string(number) + " (DICOM allows 1, 3 or 4)");
    if (tag == 0x00280002) pixels.samples = number;
    if (tag == 0x00280010) pixels.rows = number;
    if (tag == 0x00280011) pixels.columns = number;
    if (tag == 0x00280100) pixels.bits = number;
    if (tag == 0x00280101) pixels.bits_stored = number;
    if (tag == 0x00280103) pixels.pixel_representation = number;
}

/// GDCM asserts on a pixel format it has no scalar type for: Bits Allocated other than 1, 8, 12,
/// 16, 32 or 64 with signed values, or signed single bits (found by fuzzing); Bits Stored above
/// Bits Allocated makes it throw what ITK does not catch. PS3.3 C.7.6.3.1
/// allows Pixel Representation 0 (unsigned) or 1 (two's complement) only.
void check_pixel_format(const InputFile& file, const PixelModule& pixels) {
    if (pixels.pixel_representation > 1)
        file.fail("Pixel Representation (0028,0103) is " + std::to_string(pixels.pixel_representation) +
                  " (DICOM allows 0 or 1)");
    if (pixels.bits == 0) return;
    const bool known = pixels.bits == 1 || pixels.bits == 8 || pixels.bits == 12 || pixels.bits == 16 || pixels.bits == 32 ||
                       pixels.bits == 64;
    if (!known) file.fail("Bits Allocated (0028,0100) is " + std::to_string(pixels.bits) + " (1, 8, 12, 16, 32 or 64 here)");
    if (pixels.bits == 1 && pixels.pixel_representation == 1)
        file.fail("Bits Allocated (0028,0100) is 1 with signed values (Pixel Representation (0028,0103) 1)");
    if (pixels.bits_stored > pixels.bits)
        file.fail("Bits Stored (0028,0101) is " + std::to_string(pixels.bits_stored) + ", more than Bits Allocated (0028,0100) " +
                  std::to_string(pixels.bits));
}

/// Native (not encapsulated) pixel data must hold what the pixel module says: GDCM and ITK read
/// a short one without a word, the missing voxels from memory never written (two reads of one
/// file differed; found by fuzzing).
void check_pixel_bytes(const InputFile& file, const PixelModule& pixels) {
    if (!pixels.native_pixels || pixels.bits == 0 || pixels.bits % 8 != 0) return;
    const double needed = double(pixels.rows) * double(pixels.columns) * double(pixels.frames) * double(pixels.samples) *
                          double(pixels.bits / 8);
    if (needed > double(pixels.pixel_bytes))
        file.fail("Pixel Data (7FE0,0010) holds " + std::to_string(pixels.pixel_bytes) + " bytes, but " +
                  std::to_string(pixels.rows) + " rows x " + std::to_string(pixels.columns) + " columns x " +
                  std::to_string(pixels.frames) + " frames x " + std::to_string(pixels.samples) + " samples of " +
                  std::to_string(pixels.bits) + " bits need " + format("%.0f", needed));
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
    PixelModule pixels;
    int depth = 0;  // of the sequences and items of undefined length open
    bool in_fragments = false;  // inside encapsulated Pixel Data (of undefined length, PS3.5 A.4)
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
        const std::uint64_t tag = group << 16 | element;
        if (in_fragments) {
            // Encapsulated pixel data is a sequence of fragments, items of defined length, closed
            // by a sequence delimiter: GDCM asserted on anything else in their place (found by fuzzing).
            if (tag == 0xfffee0dd) in_fragments = false;
            else if (tag != 0xfffee000 || length == 0xffffffffu)
                file.fail("encapsulated Pixel Data (7FE0,0010) holds (" + hex4(group) + "," + hex4(element) +
                          ") where an item of defined length (FFFE,E000) or the sequence delimiter must be");
        } else if (tag == 0xfffee00d || tag == 0xfffee0dd) {
            depth -= depth > 0 ? 1 : 0;  // an item's or a sequence's end
        }
        if (depth == 0 && tag == 0x7fe00010 && length == 0xffffffffu) {
            in_fragments = true;
            continue;
        }
        if (length == 0xffffffffu) {  // undefined length: its elements follow
            depth += 1;
            continue;
        }
        if (length > size - std::min(at, size))
            file.fail("data element (" + hex4(group) + "," + hex4(element) + ") announces " + std::to_string(length) +
                      " bytes, but the file holds " + std::to_string(size - std::min(at, size)) + " after it");
        if (depth == 0) note_element(file, tag, at, length, big_endian, pixels);
        at += length;
    }
    check_pixel_format(file, pixels);
    check_pixel_bytes(file, pixels);
    if (in_fragments) file.fail("the file ends inside encapsulated Pixel Data (7FE0,0010), before its sequence delimiter");
    if (at < size)  // GDCM asserted on an element cut inside its tag or length (found by fuzzing)
        file.fail("the file ends inside a data element's header (" + std::to_string(size - at) + " bytes after the last element)");
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
        return unsigned_at(b, first, count, false);  // group 0002 is always little endian
    };
    std::string transfer_syntax;
    for (int element = 0;; ++element) {
        if (at == size) file.fail("the file holds DICOM meta information and no data set");
        const std::string tag = bytes_at(at, 4, "an element's tag");
        if (little(tag, 0, 2) != 0x0002) {
            // Without the group, or its transfer syntax, GDCM guesses how the data set is encoded,
            // which the walk cannot follow: a group 0003 in its place made GDCM read lengths of
            // the wrong size and allocate 0.7 GB (found by fuzzing). PS3.10 requires both.
            if (element == 0) file.fail("the DICM preamble is not followed by DICOM meta information (group 0002)");
            if (transfer_syntax.empty()) file.fail("the DICOM meta information gives no Transfer Syntax UID (0002,0010)");
            return check_data_set_lengths(file, at, transfer_syntax);
        }
        if (element > 10000) file.fail("more than 10000 elements of DICOM meta information");
        const std::string vr = bytes_at(at + 4, 2, "an element's value representation");
        if (!is_value_representation(vr))
            file.fail("DICOM meta information element " + element_name(little(tag, 2, 2)) +
                      " has no explicit value representation");
        if (vr == "SQ")  // PS3.10 7.1 has none; GDCM asserts on one (found by fuzzing)
            file.fail("DICOM meta information element " + element_name(little(tag, 2, 2)) + " is a sequence");
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
