// dsreg — shared machinery of the volume readers and writers (not part of the public API).
//
// Every reader follows the same plan:
//   1. open the file (InputFile) and parse its header;
//   2. validate the dimensions (checked_voxel_count) and check the payload size against the
//      real file size (require_exact_payload / require_plausible_zlib_payload) — all before
//      allocating anything proportional to the header's claims;
//   3. allocate the destination (VoxelDestination: a mask, or float values) and decode the
//      payload through a SampleWriter, which hands each value to the destination as soon as it
//      is decoded: a mask thresholds it at once, so no full-precision copy is ever kept.
// The format readers (read_*_voxels) are written once against VoxelDestination; the public
// read_* functions (masks) and read_volume_values (values) only choose the destination.
#pragma once

#include <cstddef>
#include <array>
#include <cstdint>
#include <fstream>
#include <ostream>
#include <memory>
#include <optional>
#include <string>
#include <unordered_map>
#include <vector>

#include <zlib.h>

#include "dsreg/value_histogram.hpp"
#include "dsreg/volume.hpp"
#include "dsreg/volume_io.hpp"
#include "itk_bridge.hpp"
#include "sample_format.hpp"

namespace dsreg::volume_io_detail {

/// Throws dsreg::Error("<path>: <problem>").
[[noreturn]] void fail(const std::string& path, const std::string& problem);

/// Printable, bounded excerpt of untrusted text for error messages.
std::string quote_excerpt(const std::string& text);

/// "5x4x3".
std::string format_dims(const Index3& dims);

/// Parses a whole string as a positive decimal integer (no sign, no trailing characters, no
/// overflow). Returns false otherwise.
bool parse_positive_integer(const std::string& text, std::int64_t& value);

/// Number of voxels of `dims`; throws (naming `path`) unless every dimension is positive and the
/// product is at most limits.max_voxels.
std::int64_t checked_voxel_count(const std::string& path, const Index3& dims, const VolumeLimits& limits);


/// The unsigned integer stored in the `count` (at most 8) bytes at `bytes`, in the given byte order
/// (the binary headers of TIFF and DICOM).
inline std::uint64_t unsigned_integer(const std::uint8_t* bytes, std::size_t count, bool big_endian) {
    std::uint64_t value = 0;
    for (std::size_t k = 0; k < count; ++k) value = value << 8 | bytes[big_endian ? k : count - 1 - k];
    return value;
}

/// A regular file opened for reading, with its size known up front and the read position tracked.
class InputFile {
public:
    explicit InputFile(const std::string& path);  ///< throws dsreg::Error naming the file

    const std::string& path() const { return path_; }
    std::uint64_t size() const { return size_; }
    std::uint64_t position() const { return position_; }
    std::uint64_t remaining() const { return position_ < size_ ? size_ - position_ : 0; }

    int get();   ///< next byte, or -1 at end of file
    int peek();  ///< next byte without consuming it, or -1
    /// Reads up to `count` bytes; fewer only at end of file (or on a read error).
    std::size_t read(std::uint8_t* destination, std::size_t count);
    void skip(std::uint64_t count);  ///< throws if the file is shorter
    void seek(std::uint64_t offset);  ///< absolute position; throws if beyond the end

    [[noreturn]] void fail(const std::string& problem) const { volume_io_detail::fail(path_, problem); }

private:
    std::string path_;
    std::filebuf buffer_;
    std::uint64_t size_ = 0;
    std::uint64_t position_ = 0;
};


/// Where a stream of voxels goes when only a box of the grid is kept: voxel (i,j,k) of the stream
/// (x fastest over `dims`) is stored at the box's own linear index if it lies in `box`, and
/// dropped otherwise.
struct StreamRegion {
    Index3 dims{0, 0, 0};
    VoxelBox box;

    /// Index in the box's storage of stream voxel `index`, or −1 outside the box.
    std::int64_t local_index(std::uint64_t index) const;
    /// The stream voxels [first_needed, end_needed) of the x-y slices the box spans: a box read
    /// decodes no others (stored payloads seek past the slices before, and stop after).
    std::uint64_t first_needed() const { return std::uint64_t(dims[0] * dims[1] * box.lo[2]); }
    std::uint64_t end_needed() const { return std::uint64_t(dims[0] * dims[1] * box.hi[2]); }
};

/// Label indices of the integer values of a label map, assigned as the values are decoded
/// (index 0 is the value 0, the background), then renumbered in increasing order of value.
/// The number of distinct labels is capped (VolumeLimits::max_labels) so that a hostile file of
/// distinct values cannot make the table grow without bound.
class LabelTable {
public:
    LabelTable(const std::string& path, std::int64_t max_labels);
    /// The index of `value` (the value of voxel #voxel). Throws, naming the file and the voxel,
    /// for a value that is not an integer of magnitude below 2^53, or one label too many.
    std::uint32_t index_of(double value, std::uint64_t voxel) {
        if (value == last_value_) return last_index_;
        return look_up(value, voxel);
    }
    /// Renumbers `labels` so that indices increase with the value (background first) and
    /// returns the value of each index.
    std::vector<std::int64_t> finish(std::vector<std::uint32_t>& labels) const;

private:
    std::uint32_t look_up(double value, std::uint64_t voxel);

    std::string path_;
    std::int64_t max_labels_;
    std::unordered_map<std::int64_t, std::uint32_t> index_;
    std::vector<std::int64_t> values_;  ///< by index of first appearance
    double last_value_ = 0;
    std::uint32_t last_index_ = 0;
};

/// Decodes a stream of encoded samples, in voxel order, into either mask bytes (1 = value in
/// `range`), float values, or label indices. Bytes may arrive in chunks of any size: a sample split between
/// chunks is completed by the next call. Optionally rejects values above a maximum (PGM's
/// maxval). The destination vector must already have one element per voxel (per voxel of the
/// box, with a region).
class SampleWriter {
public:
    /// Thresholding: mask[i] = range.contains(value of voxel i).
    SampleWriter(const std::string& path, SampleFormat format, const ValueRange& range, std::vector<std::uint8_t>& mask,
                 const StreamRegion* region = nullptr);
    /// Values: values[i] = value of voxel i, rounded to float.
    SampleWriter(const std::string& path, SampleFormat format, std::vector<float>& values,
                 const StreamRegion* region = nullptr);
    /// Labels: labels[i] = table.index_of(value of voxel i) (whole grids only).
    SampleWriter(const std::string& path, SampleFormat format, std::vector<std::uint32_t>& labels, LabelTable& table);
    /// Statistics: each of the `size` values is added to `histogram`, nothing is stored.
    SampleWriter(const std::string& path, SampleFormat format, ValueHistogram& histogram, std::uint64_t size);

    /// Values above `max_value` make consume() throw (naming the file and the voxel).
    void reject_values_above(double max_value, const std::string& limit_name);
    /// Every decoded value v becomes slope·v + intercept before it is thresholded or stored
    /// (NIfTI's scl_slope / scl_inter). Call before the first consume().
    void rescale(double slope, double intercept);

    void consume(const std::uint8_t* data, std::size_t count);

    /// With a region: the next sample consumed is that of stream voxel `index` (≥ the current
    /// one); the voxels skipped are outside the box. For payloads read by offsets.
    void skip_to(std::uint64_t index);
    const StreamRegion* region() const { return has_region_ ? &region_ : nullptr; }
    int sample_bytes() const { return format_.bytes; }

    std::uint64_t samples_written() const { return written_; }
    /// Bytes still to come before every voxel has its value.
    std::uint64_t bytes_missing() const {
        return (size_ - written_) * static_cast<std::uint64_t>(format_.bytes) - pending_size_;
    }
    bool complete() const { return written_ == size_ && pending_size_ == 0; }
    /// Bytes still to come before every voxel a box read needs (every voxel without a region)
    /// has its value.
    std::uint64_t bytes_needed() const {
        const std::uint64_t end = has_region_ ? region_.end_needed() : size_;
        return written_ >= end ? 0 : (end - written_) * static_cast<std::uint64_t>(format_.bytes) - pending_size_;
    }

private:
    SampleWriter(const std::string& path, SampleFormat format, std::uint64_t size, const StreamRegion* region = nullptr);
    void build_byte_tables();
    void emit(const std::uint8_t* sample);  ///< one value, with every check (PGM's maxval)
    /// `count` whole values, after the caller checked they fit: the fast path (with a region, the
    /// stretches of x-rows inside its box).
    void decode_run(const std::uint8_t* data, std::size_t count);
    /// `count` whole values stored from slot `slot` of the destination on.
    void decode_span(const std::uint8_t* data, std::size_t count, std::uint64_t slot);
    template <typename T>
    void decode_typed(const std::uint8_t* data, std::size_t count, std::uint64_t slot);

    std::string path_;
    SampleFormat format_;
    ValueRange range_;
    std::uint8_t* mask_ = nullptr;  ///< exactly one of mask_ / values_ / labels_ / histogram_ is set
    float* values_ = nullptr;
    std::uint32_t* labels_ = nullptr;
    LabelTable* label_table_ = nullptr;
    ValueHistogram* histogram_ = nullptr;
    std::uint64_t size_ = 0;        ///< voxels of the stream
    bool has_region_ = false;
    StreamRegion region_;
    bool use_byte_table_ = false;
    double byte_table_[256] = {};        ///< decoded value of each byte, for 1-byte samples
    std::uint8_t mask_table_[256] = {};  ///< its mask value (thresholding, 1-byte samples)
    bool rescaled_ = false;
    double slope_ = 1.0, intercept_ = 0.0;
    bool has_max_ = false;
    double max_value_ = 0.0;
    std::string max_name_;
    std::uint8_t pending_[8] = {};
    std::size_t pending_size_ = 0;
    std::uint64_t written_ = 0;
};

/// The name the thresholding decoder had before it could also keep values.
using MaskWriter = SampleWriter;

/// What a reader produces: a mask thresholded by a ValueRange (read_volume), the values
/// themselves as floats (read_volume_values) or label indices (read_label_volume), of the whole
/// grid or (mask and values) of a box of it, or only the dimensions (header_only). Readers call
/// allocate() once the header is checked and, if it returns true, feed the payload through
/// writer() (binary payloads) or set() (ASCII payloads).
class VoxelDestination {
public:
    static VoxelDestination mask(const ValueRange& range);
    static VoxelDestination values();
    static VoxelDestination labels(std::int64_t max_labels);
    /// Nothing stored per voxel: every value goes to `histogram` (read_value_histogram).
    static VoxelDestination statistics(ValueHistogram& histogram);
    /// Records the dimensions; allocate() returns false, so that no payload is read.
    static VoxelDestination header_only();

    /// Keeps only the voxels of `box` (call before allocate(), which checks that the box lies
    /// in the grid). Every reader honours it through writer() and set(); the ITK reader refuses
    /// it for the images ITK cannot read by slices (read_volume_box refuses DICOM series).
    void restrict_to(const VoxelBox& box);
    /// The region of restrict_to(), or null for the whole grid (valid after allocate()).
    const StreamRegion* region() const { return has_region_ ? &region_ : nullptr; }

    /// Storage for `dims` voxels (spacing 1, origin 0, identity direction), or for the box.
    /// Throws dsreg::Error naming `path` if the memory cannot be allocated or the box is not
    /// inside the grid. Returns whether the payload is wanted (false for header_only).
    bool allocate(const std::string& path, const Index3& dims);
    /// The grid's spacing, origin and direction (dims stay those of allocate()).
    void set_geometry(const VoxelGrid& geometry);
    /// Format, value type and notes, for read_volume's optional output.
    VolumeFileInfo& info() { return info_; }
    /// Voxels of the stream (the whole grid).
    std::uint64_t size() const { return static_cast<std::uint64_t>(dims_[0] * dims_[1] * dims_[2]); }
    const Index3& dims() const { return dims_; }
    /// Stores the value of voxel `index` of the grid (thresholded or rounded to float), if kept.
    void set(std::uint64_t index, double value) {
        std::int64_t slot = static_cast<std::int64_t>(index);
        if (has_region_ && (slot = region_.local_index(index)) < 0) return;
        switch (kind_) {
        case Kind::Values: values_[std::size_t(slot)] = static_cast<float>(value); break;
        case Kind::Mask: mask_[std::size_t(slot)] = range_.contains(value) ? 1 : 0; break;
        case Kind::Labels: labels_[std::size_t(slot)] = label_table_->index_of(value, index); break;
        case Kind::Statistics: histogram_->add(value); break;
        }
    }
    /// A decoder of encoded samples into this destination.
    SampleWriter writer(const std::string& path, SampleFormat format);

    /// An empty destination of the same kind (mask with the same range, values, labels, statistics).
    /// A label map's plane shares this destination's label table, so that its indices are this one's.
    VoxelDestination like() const {
        VoxelDestination plane(kind_, range_, histogram_, max_labels_);
        plane.label_table_ = label_table_;
        return plane;
    }
    /// False for statistics, which do not depend on the order of the voxels.
    bool keeps_voxel_order() const { return kind_ != Kind::Statistics; }
    /// Copies `plane` (allocated with dims (nz, ny, 1): k fastest, then j) into the voxels
    /// (i, j, k) of this destination, for all j, k: a transposed plane of a C-order array.
    void store_x_plane(std::int64_t i, const VoxelDestination& plane);

    BinaryVolume take_mask();
    ScalarVolume take_values();
    LabelVolume take_labels();

private:
    enum class Kind { Mask, Values, Labels, Statistics };
    VoxelDestination(Kind kind, const ValueRange& range, ValueHistogram* histogram = nullptr, std::int64_t max_labels = 0)
        : kind_(kind), range_(range), histogram_(histogram), max_labels_(max_labels) {}

    Kind kind_;
    bool header_only_ = false;
    ValueRange range_;
    ValueHistogram* histogram_;
    std::int64_t max_labels_;
    Index3 dims_{0, 0, 0};  ///< of the whole grid
    bool has_region_ = false;
    StreamRegion region_;
    VoxelGrid grid_;        ///< of what is kept
    VolumeFileInfo info_;
    std::vector<std::uint8_t> mask_;
    std::vector<float> values_;
    std::vector<std::uint32_t> labels_;
    std::shared_ptr<LabelTable> label_table_;  ///< created by allocate() (it names the file), shared by like()
};

// The format readers, each decoding one file into a destination (vol_format.cpp,
// pgm3d_format.cpp, raw_format.cpp), and the dispatch on the extension (volume_io.cpp).
void read_vol_voxels(const std::string& path, const VolumeLimits& limits, VoxelDestination& destination);
void read_longvol_voxels(const std::string& path, const VolumeLimits& limits, VoxelDestination& destination);
void read_pgm3d_voxels(const std::string& path, const VolumeLimits& limits, VoxelDestination& destination);
void read_raw_voxels(const std::string& path, const RawVolumeLayout& layout, const VolumeLimits& limits,
                     VoxelDestination& destination);
void read_volume_voxels(const std::string& path, const RawVolumeLayout* raw_layout, const VolumeLimits& limits,
                        VoxelDestination& destination);
// The medical and scientific formats (nifti_format.cpp, nrrd_format.cpp, metaimage_format.cpp,
// npy_format.cpp; itk_bridge.hpp for those ITK decodes).
void read_nifti_voxels(const std::string& path, const VolumeLimits& limits, VoxelDestination& destination);
void read_nrrd_voxels(const std::string& path, const VolumeLimits& limits, VoxelDestination& destination);
void read_metaimage_voxels(const std::string& path, const VolumeLimits& limits, VoxelDestination& destination);
void read_npy_voxels(const std::string& path, const VolumeLimits& limits, VoxelDestination& destination);
// Images ITK decodes (itk_volume_io.cpp): header checks, then the voxels in slabs of slices when
// ITK can stream the format, else in one piece; a DICOM series slab by slab.
void read_itk_voxels(const std::string& path, ItkFormat format, const VolumeLimits& limits, VoxelDestination& destination);
/// Throws (naming the file and the page) unless every directory of the TIFF stack `path` has the
/// size, the bits and samples per pixel, the sample format, the planar layout and the subfile
/// type of the first: ITK's reader assumes so (tiff_pages.cpp).
void check_tiff_pages(const std::string& path);
/// Throws (naming the file and the directory) where a TIFF directory entry counts more values than
/// the file holds at their offset: ITK's libtiff allocates them first (tiff_entries.cpp).
void check_tiff_entries(const std::string& path);
/// Throws (naming the file) where the DICOM file meta information (group 0002 after the "DICM"
/// preamble) ends before its elements do, names no value representation, or is all the file
/// holds: Debian's GDCM asserts on those instead of failing (dicom_meta.cpp); or where an element
/// of the data set announces more bytes than the file holds (GDCM allocates them). Files without
/// the preamble are left to GDCM.
void check_dicom_meta(const std::string& path);
/// Checks the header lines of a legacy VTK image before ITK reads it (vtk_image_header.cpp): text,
/// and three numbers on each geometry line. Throws naming the file and the line.
void check_vtk_image_header(const std::string& path);
/// Throws (naming the file) where the voxel data set of an HDF5 image as ITK writes it claims
/// more storage than the file holds, or chunks it could not hold compressed (HDF5 allocates
/// them), or a chunk that does not decode to a whole chunk (HDF5 copies past it), or uses a filter
/// other than deflate and shuffle (hdf5_storage.cpp). Files HDF5 cannot open are left to ITK's reader.
/// `slices`: the [first, end) z slices a box read needs (chunks elsewhere are not decoded); all
/// without it.
void check_hdf5_voxel_data(const std::string& path, std::optional<std::array<std::int64_t, 2>> slices = std::nullopt);
void read_dicom_series_voxels(const std::string& folder, const VolumeLimits& limits, VoxelDestination& destination);

/// Every format dsreg reads, told from the file name (compound extensions such as .nii.gz
/// included) or, for a folder, a DICOM series.
enum class VolumeFormat { Vol, Longvol, Pgm3d, Raw, Nifti, Nrrd, MetaImage, Npy, Tiff, Hdf5, VtkImage, DicomFile, DicomSeries };
/// Throws dsreg::Error naming `path` for an unknown or missing extension.
VolumeFormat volume_format(const std::string& path);

/// "5x4x3 = 60 voxels" or, for wider samples, "5x4x3 = 60 voxels x 8 bytes = 480 bytes".
std::string describe_payload(const Index3& dims, std::int64_t voxels, int bytes_per_value);

/// voxels × bytes_per_value, or throws (naming `path`) if it overflows.
std::uint64_t payload_bytes(const std::string& path, std::int64_t voxels, int bytes_per_value);

/// Throws unless the rest of the file holds exactly `expected_bytes` (truncated / trailing bytes).
void require_exact_payload(const InputFile& file, std::uint64_t expected_bytes, const std::string& description);

/// Throws if the rest of the file is too small to inflate to `expected_bytes`, given zlib's
/// maximum compression ratio (1032:1): a lying header must not make us allocate.
void require_plausible_zlib_payload(const InputFile& file, std::uint64_t expected_bytes, const std::string& description);

/// Feeds the rest of the file (exactly the expected size, already checked) to `sink`; with a
/// region, only the x-y slices its box spans, sought at their offset (StreamRegion::first_needed).
void decode_stored_payload(InputFile& file, SampleWriter& sink);
/// Feeds the next bytes of the file to `sink` until it is complete (with a region: until the
/// slices of its box are, seeking past those before); what follows is not read.
void decode_stored_prefix(InputFile& file, SampleWriter& sink);

/// Inflates the zlib stream filling the rest of the file into `sink`, with a hard cap at
/// `expected_bytes`: more output, less output, a corrupt stream or bytes after the end of the
/// stream all throw, naming the file.
void decode_zlib_payload(InputFile& file, std::uint64_t expected_bytes, SampleWriter& sink, const std::string& description);

/// The container of a deflate stream: zlib (RFC 1950), gzip (RFC 1952, several members allowed),
/// or either, told by its first bytes.
enum class CompressedContainer { Zlib, Gzip, ZlibOrGzip };

/// At most this many bytes can a deflate stream of `compressed` bytes inflate to (1032:1, plus
/// a little slack for headers and checksums).
std::uint64_t max_inflated_size(std::uint64_t compressed);

/// The inflated bytes of the compressed stream that fills the rest of `file`, read in order.
/// Every failure throws dsreg::Error naming the file: corrupt data, or the file ending inside
/// the stream ("truncated payload: <context>, but the gzip stream is cut off after ...").
class InflateStream {
public:
    InflateStream(InputFile& file, CompressedContainer container);
    ~InflateStream();
    InflateStream(const InflateStream&) = delete;
    InflateStream& operator=(const InflateStream&) = delete;

    /// Inflates up to `count` bytes; fewer only once the (last) stream has ended.
    std::size_t read(std::uint8_t* destination, std::size_t count, const std::string& context);
    /// Discards `count` inflated bytes; throws if the stream ends before.
    void skip(std::uint64_t count, const std::string& context);
    /// Feeds exactly `count` inflated bytes to `sink` (with a region, only those up to the end of
    /// its box's last slice: SampleWriter::bytes_needed); throws if the stream ends before.
    void decode(std::uint64_t count, SampleWriter& sink, const std::string& context);

    std::uint64_t produced() const { return produced_; }
    bool ended() const { return ended_; }
    /// Compressed bytes not consumed yet (buffered, plus the rest of the file).
    std::uint64_t unread_input() const;
    const char* name() const;  ///< "zlib" or "gzip", for messages

private:
    void refill();
    bool next_member_follows();

    InputFile& file_;
    CompressedContainer container_;
    z_stream stream_{};
    std::vector<std::uint8_t> input_;
    std::uint64_t produced_ = 0;
    bool ended_ = false;
};

/// Writes a payload to a stream, either as is or as one zlib stream (what zlib's compress()
/// would produce), in bounded chunks.
class PayloadWriter {
public:
    PayloadWriter(const std::string& path, std::ostream& out, bool compress);
    ~PayloadWriter();
    PayloadWriter(const PayloadWriter&) = delete;
    PayloadWriter& operator=(const PayloadWriter&) = delete;

    void write(const std::uint8_t* data, std::size_t count);
    void finish();  ///< must be called once, after the last write()

private:
    void deflate_pending(int flush);

    std::string path_;
    std::ostream& out_;
    bool compress_;
    bool finished_ = false;
    z_stream stream_{};
    std::vector<std::uint8_t> chunk_;
};

/// Throws (naming `path`) unless dims are positive and `value_count` equals their product.
void check_writer_input(const std::string& path, const Index3& dims, std::size_t value_count);

}  // namespace dsreg::volume_io_detail
