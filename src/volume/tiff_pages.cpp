// dsreg — the pages of a multi-page TIFF, checked with libtiff before ITK reads them.
//
// ITK's TIFF reader (5.2) takes the size and the value type of the whole stack from the first
// page and the number of slices from the directories' subfile types, then decodes every
// directory as it comes: a stack whose second directory lost its "page" subfile type (one
// mutated byte) had one slice less allocated than written, a heap overflow that aborted at exit
// (found by mutating a small stack). So every directory must be a page described like the first,
// and hold no tag that ITK copies unsafely (check_page_tags).
#include <tiffio.h>

#include <cstdint>
#include <cstring>
#include <memory>
#include <mutex>
#include <string>

#include "volume_io_internal.hpp"

namespace dsreg::volume_io_detail {

namespace {

/// How a page stores its pixels (what ITK assumes the same for every page).
struct TiffPage {
    std::uint32_t width = 0, height = 0;
    std::uint16_t bits_per_sample = 0, samples_per_pixel = 0, sample_format = 0, planar_config = 0;
    std::uint32_t subfile_type = 0;

    bool operator==(const TiffPage& o) const {
        return width == o.width && height == o.height && bits_per_sample == o.bits_per_sample &&
               samples_per_pixel == o.samples_per_pixel && sample_format == o.sample_format &&
               planar_config == o.planar_config && subfile_type == o.subfile_type;
    }
    std::string text() const {
        return std::to_string(width) + "x" + std::to_string(height) + ", " + std::to_string(samples_per_pixel) + " x " +
               std::to_string(bits_per_sample) + " bits per pixel, sample format " + std::to_string(sample_format) +
               ", planar configuration " + std::to_string(planar_config) + ", subfile type " + std::to_string(subfile_type);
    }
};

TiffPage current_page(TIFF* tiff) {
    TiffPage page;
    TIFFGetField(tiff, TIFFTAG_IMAGEWIDTH, &page.width);
    TIFFGetField(tiff, TIFFTAG_IMAGELENGTH, &page.height);
    TIFFGetFieldDefaulted(tiff, TIFFTAG_BITSPERSAMPLE, &page.bits_per_sample);
    TIFFGetFieldDefaulted(tiff, TIFFTAG_SAMPLESPERPIXEL, &page.samples_per_pixel);
    TIFFGetFieldDefaulted(tiff, TIFFTAG_SAMPLEFORMAT, &page.sample_format);
    TIFFGetFieldDefaulted(tiff, TIFFTAG_PLANARCONFIG, &page.planar_config);
    TIFFGetField(tiff, TIFFTAG_SUBFILETYPE, &page.subfile_type);
    return page;
}

/// ITK's reader copies the 20 bytes a DateTime tag is defined to hold ("YYYY:MM:DD HH:MM:SS" and
/// its NUL) whatever the file stores: a shorter one was read past its end (heap overflow).
void check_date_time(const std::string& path, TIFF* tiff, std::int64_t index) {
    const char* text = nullptr;
    if (!TIFFGetField(tiff, TIFFTAG_DATETIME, &text) || text == nullptr) return;
    const std::size_t length = std::strlen(text);
    if (length != 19)
        fail(path, "page " + std::to_string(index) + " has a DateTime tag of " + std::to_string(length) +
                       " characters, not the 19 of 'YYYY:MM:DD HH:MM:SS' (ITK's TIFF reader reads 20 bytes)");
}

/// ITK's reader reads a one-byte text tag as a C string: the byte of a tag libtiff does not
/// know, kept without a NUL after it, was read past its end (heap overflow). This libtiff puts a
/// NUL in place of that byte, so any one-byte text of an unknown tag is refused.
void check_one_byte_text(const std::string& path, TIFF* tiff, std::uint32_t tag, std::int64_t index) {
    const TIFFField* field = TIFFFieldWithTag(tiff, tag);
    if (field == nullptr || TIFFFieldDataType(field) != TIFF_ASCII || !TIFFFieldPassCount(field) ||
        TIFFFieldReadCount(field) != TIFF_VARIABLE2)
        return;
    std::uint32_t count = 0;
    const char* text = nullptr;
    if (TIFFGetField(tiff, tag, &count, &text) && count == 1)
        fail(path, "page " + std::to_string(index) + " has an unknown text tag " + std::to_string(tag) +
                       " of one byte (ITK's TIFF reader reads it as a C string, past its end)");
}

/// The tags ITK's reader copies into its metadata unsafely (all found by fuzzing): a DateTime
/// of another length, DotRange, which it asks of its libtiff with one pointer where two are
/// written (a write to a stray address: the process crashed), one-byte texts of unknown tags.
void check_page_tags(const std::string& path, TIFF* tiff, std::int64_t index) {
    const int count = TIFFGetTagListCount(tiff);
    for (int i = 0; i < count; ++i) {
        const auto tag = static_cast<std::uint32_t>(TIFFGetTagListEntry(tiff, i));
        if (tag == TIFFTAG_DOTRANGE)
            fail(path, "page " + std::to_string(index) + " has a DotRange tag, which ITK's TIFF reader cannot read");
        check_one_byte_text(path, tiff, tag, index);
    }
    check_date_time(path, tiff, index);
}

struct TiffCloser {
    void operator()(TIFF* tiff) const { TIFFClose(tiff); }
};

}  // namespace

void check_tiff_pages(const std::string& path) {
    static std::once_flag quiet;  // libtiff prints its errors and warnings by default; ours name the file
    std::call_once(quiet, [] {
        TIFFSetErrorHandler(nullptr);
        TIFFSetWarningHandler(nullptr);
    });
    const std::unique_ptr<TIFF, TiffCloser> tiff(TIFFOpen(path.c_str(), "rm"));
    if (!tiff) fail(path, "not a TIFF file that libtiff can open");
    const TiffPage first = current_page(tiff.get());
    check_page_tags(path, tiff.get(), 1);
    // ITK's libtiff (4.0.3) counts the directories without noticing a loop in their chain: a
    // directory that named itself as the next one hung the reader (found by fuzzing). This one
    // refuses to read a directory twice, as it refuses a damaged one.
    for (std::int64_t index = 2; !TIFFLastDirectory(tiff.get()); ++index) {
        if (!TIFFReadDirectory(tiff.get()))
            fail(path, "directory " + std::to_string(index) +
                           " cannot be read (a loop in the chain of directories, or a damaged directory)");
        check_page_tags(path, tiff.get(), index);
        const TiffPage page = current_page(tiff.get());
        if (!(page == first))
            fail(path, "page " + std::to_string(index) + " is " + page.text() + ", page 1 " + first.text() +
                           " (dsreg reads stacks whose directories are all pages alike)");
    }
}

}  // namespace dsreg::volume_io_detail
