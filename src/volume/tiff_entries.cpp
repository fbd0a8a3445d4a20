// dsreg — the directory entries of a TIFF file, checked against the file's size before libtiff or
// ITK reads them.
//
// ITK's libtiff (4.0.3) allocates a tag's values as its entry counts them before reading them:
// a Software tag of 1.8 billion characters in an 817-byte file made it allocate 1.8 GB (found by
// fuzzing; Debian's libtiff, which checks the pages first, drops such a tag and says nothing).
// So every entry whose values lie outside it must find them inside the file.
#include <cstdint>
#include <set>
#include <string>
#include <vector>

#include "volume_io_internal.hpp"

namespace dsreg::volume_io_detail {

namespace {

/// Bytes of one value of a TIFF field type (TIFF 6 and BigTIFF), 0 for an unknown type.
std::uint64_t tiff_type_bytes(std::uint64_t type) {
    switch (type) {
    case 1: case 2: case 6: case 7: return 1;              // BYTE ASCII SBYTE UNDEFINED
    case 3: case 8: return 2;                              // SHORT SSHORT
    case 4: case 9: case 11: case 13: return 4;            // LONG SLONG FLOAT IFD
    case 5: case 10: case 12: case 16: case 17: case 18: return 8;  // RATIONAL ... LONG8 SLONG8 IFD8
    default: return 0;
    }
}

/// The byte order and offset size of a TIFF or BigTIFF file, read from its 8- or 16-byte header.
struct TiffLayout {
    bool big_endian = false;
    bool big_tiff = false;
    std::uint64_t first_directory = 0;

    std::uint64_t number(const std::vector<std::uint8_t>& bytes, std::size_t at, std::size_t count) const {
        return unsigned_integer(bytes.data() + at, count, big_endian);
    }
    std::size_t offset_bytes() const { return big_tiff ? 8 : 4; }
    std::size_t count_bytes() const { return big_tiff ? 8 : 2; }     ///< of a directory's entry count
    std::size_t entry_bytes() const { return big_tiff ? 20 : 12; }
};

std::vector<std::uint8_t> bytes_at(InputFile& file, std::uint64_t offset, std::uint64_t count) {
    std::vector<std::uint8_t> bytes;
    if (offset > file.size() || count > file.size() - offset) return bytes;
    bytes.resize(static_cast<std::size_t>(count));
    file.seek(offset);
    if (file.read(bytes.data(), bytes.size()) != bytes.size()) bytes.clear();
    return bytes;
}

/// False for a file that is not a TIFF (libtiff says so).
bool read_layout(InputFile& file, TiffLayout& layout) {
    const std::vector<std::uint8_t> head = bytes_at(file, 0, 16);
    if (head.size() < 16 || head[0] != head[1] || (head[0] != 'I' && head[0] != 'M')) return false;
    layout.big_endian = head[0] == 'M';
    const std::uint64_t magic = layout.number(head, 2, 2);
    layout.big_tiff = magic == 43;
    if (magic != 42 && magic != 43) return false;
    layout.first_directory = layout.number(head, layout.big_tiff ? 8 : 4, layout.offset_bytes());
    return true;
}

/// Checks the entries of the directory at `offset`; returns the offset of the next one (0: none
/// or unreadable, left to libtiff).
std::uint64_t check_directory(InputFile& file, const TiffLayout& layout, std::uint64_t offset, std::int64_t index) {
    const std::vector<std::uint8_t> count_field = bytes_at(file, offset, layout.count_bytes());
    if (count_field.empty()) return 0;
    const std::uint64_t entries = layout.number(count_field, 0, layout.count_bytes());
    if (entries > (std::uint64_t(1) << 20)) return 0;
    // libtiff reads a directory whose entries are whole even when the file ends before the offset
    // of the next one (a truncated stack: it takes "no next directory"), so those are checked too.
    const std::uint64_t table_offset = offset + layout.count_bytes(), entry_bytes = entries * layout.entry_bytes();
    const std::vector<std::uint8_t> table = bytes_at(file, table_offset, entry_bytes);
    if (table.size() != entry_bytes || entries == 0) return 0;
    for (std::uint64_t e = 0; e < entries; ++e) {
        const std::size_t at = static_cast<std::size_t>(e * layout.entry_bytes());
        const std::uint64_t tag = layout.number(table, at, 2), type_bytes = tiff_type_bytes(layout.number(table, at + 2, 2));
        const std::uint64_t count = layout.number(table, at + 4, layout.offset_bytes());
        if (type_bytes == 0 || count <= layout.offset_bytes() / type_bytes) continue;  // unknown type, or values inline
        const std::uint64_t values = layout.number(table, at + 4 + layout.offset_bytes(), layout.offset_bytes());
        if (count > file.size() / type_bytes || values > file.size() - count * type_bytes)
            file.fail("directory " + std::to_string(index) + ": tag " + std::to_string(tag) + " claims " + std::to_string(count) +
                      " values, more than the file holds at their offset " + std::to_string(values));
    }
    const std::vector<std::uint8_t> next = bytes_at(file, table_offset + entry_bytes, layout.offset_bytes());
    return next.empty() ? 0 : layout.number(next, 0, layout.offset_bytes());
}

}  // namespace

void check_tiff_entries(const std::string& path) {
    InputFile file(path);
    TiffLayout layout;
    if (!read_layout(file, layout)) return;
    std::set<std::uint64_t> seen;  // a loop is refused by check_tiff_pages
    std::int64_t index = 1;
    for (std::uint64_t offset = layout.first_directory; offset != 0 && seen.insert(offset).second; ++index)
        offset = check_directory(file, layout, offset, index);
}

}  // namespace dsreg::volume_io_detail
