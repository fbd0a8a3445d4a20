// dsreg — the voxel data set of an HDF5 image as ITK writes it (/ITKImage/0/VoxelData), checked
// with HDF5's C library before ITK reads it.
//
// HDF5 allocates a chunk as its index says it is stored, and decodes it into a buffer of the
// chunk's dimensions: a chunk index claiming 1.6 GB in a 13 KB file made HDF5 allocate that much
// (found by fuzzing). So the storage the data set claims must fit in the file, and a chunk must
// be no larger than the file could hold compressed and must decode to a whole chunk. HDF5 prints
// its error stack on stderr by default; dsreg turns it off (its own messages, and ITK's, name
// the file).
#include <hdf5.h>
#include <zlib.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "volume_io_internal.hpp"

namespace dsreg::volume_io_detail {

namespace {

/// An HDF5 identifier closed when it goes out of scope.
class Handle {
public:
    Handle(hid_t id, herr_t (*close)(hid_t)) : id_(id), close_(close) {}
    ~Handle() {
        if (id_ >= 0) close_(id_);
    }
    Handle(const Handle&) = delete;
    Handle& operator=(const Handle&) = delete;
    hid_t id() const { return id_; }
    bool valid() const { return id_ >= 0; }

private:
    hid_t id_;
    herr_t (*close_)(hid_t);
};

/// `a` * `b`, or the largest value where that overflows.
std::uint64_t saturated_product(std::uint64_t a, std::uint64_t b) {
    return b != 0 && a > UINT64_MAX / b ? UINT64_MAX : a * b;
}

/// The size a deflate stream inflates to, up to `limit` + 1 bytes (more is not read); −1 if zlib
/// cannot inflate it.
std::int64_t inflated_size(const std::vector<std::uint8_t>& compressed, std::uint64_t limit) {
    std::vector<std::uint8_t> out(static_cast<std::size_t>(limit) + 1);
    z_stream stream{};
    if (inflateInit(&stream) != Z_OK) return -1;
    stream.next_in = const_cast<Bytef*>(compressed.data());
    stream.avail_in = static_cast<uInt>(compressed.size());
    stream.next_out = out.data();
    stream.avail_out = static_cast<uInt>(out.size());
    const int code = inflate(&stream, Z_FINISH);
    const std::int64_t size = code == Z_STREAM_END || code == Z_BUF_ERROR || code == Z_OK ? std::int64_t(stream.total_out) : -1;
    inflateEnd(&stream);
    return size;
}

/// Every chunk must decode to a whole chunk: HDF5 1.10 copied a chunk's bytes as its dimensions
/// count them from what its deflate filter returned, which a damaged stream left shorter (heap
/// overflow in H5VM_memcpyvv; found by fuzzing). So the chunks are read raw and inflated here
/// first; the filters checked are deflate and shuffle (which keeps the size), the ones ITK
/// writes; a data set with another filter is refused.
void check_chunk_sizes(const InputFile& file, hid_t data_set, hid_t properties, std::uint64_t chunk_bytes, hsize_t chunk_slices,
                       const std::optional<std::array<std::int64_t, 2>>& slices) {
    bool deflate_in_pipeline = false;
    unsigned deflate_bit = 0;
    const int filters = H5Pget_nfilters(properties);
    for (int k = 0; k < filters; ++k) {
        unsigned flags = 0, config = 0;
        std::size_t values = 0;
        char name[64] = {0};
        const H5Z_filter_t id = H5Pget_filter2(properties, unsigned(k), &flags, &values, nullptr, sizeof name, name, &config);
        if (id == H5Z_FILTER_DEFLATE) deflate_in_pipeline = true, deflate_bit = unsigned(k);
        else if (id != H5Z_FILTER_SHUFFLE)
            file.fail("the voxel data set uses HDF5 filter " + std::to_string(id) +
                      " (dsreg reads data sets stored plain, shuffled or deflated, as ITK writes them)");
    }
    const Handle space(H5Dget_space(data_set), H5Sclose);
    hsize_t chunks = 0;
    if (!space.valid() || H5Dget_num_chunks(data_set, space.id(), &chunks) < 0) return;  // ITK says what is wrong
    for (hsize_t c = 0; c < chunks; ++c) {
        const auto fail = [&](const std::string& what) { file.fail("chunk " + std::to_string(c) + " of the voxel data set " + what); };
        hsize_t offset[H5S_MAX_RANK];
        unsigned mask = 0;
        haddr_t address = 0;
        hsize_t size = 0;
        if (H5Dget_chunk_info(data_set, space.id(), c, offset, &mask, &address, &size) < 0 || size > file.size())
            fail("cannot be located in the file");
        // HDF5's first dimension is ITK's z (C order): a chunk outside the slices read is not decoded.
        if (slices && (offset[0] >= hsize_t(std::max<std::int64_t>((*slices)[1], 0)) ||
                       offset[0] + chunk_slices <= hsize_t(std::max<std::int64_t>((*slices)[0], 0))))
            continue;
        // H5Dread_chunk finds the chunk by its offset, whose record may not be the one listed at c
        // in a damaged index (it wrote past a buffer of the listed size: found by fuzzing), so the
        // buffer takes the size stored under that offset.
        hsize_t stored = 0;
        if (H5Dget_chunk_storage_size(data_set, offset, &stored) < 0 || stored > file.size())
            fail("cannot be located in the file");
        std::vector<std::uint8_t> raw(static_cast<std::size_t>(stored));
        if (H5Dread_chunk(data_set, H5P_DEFAULT, offset, &mask, raw.data()) < 0) fail("cannot be read");
        const bool deflated = deflate_in_pipeline && !(mask & (1u << deflate_bit));
        const std::int64_t decoded = deflated ? inflated_size(raw, chunk_bytes) : std::int64_t(raw.size());
        if (decoded != std::int64_t(chunk_bytes))
            fail("decodes to " +
                 (decoded < 0 ? std::string("nothing (a damaged deflate stream)") : std::to_string(decoded) + " bytes") +
                 ", not the " + std::to_string(chunk_bytes) + " of a chunk");
    }
}

/// A chunk that the whole file could not hold even compressed is refused: HDF5 allocates it.
void check_chunks(const InputFile& file, hid_t data_set, const std::optional<std::array<std::int64_t, 2>>& slices) {
    const Handle properties(H5Dget_create_plist(data_set), H5Pclose);
    const Handle type(H5Dget_type(data_set), H5Tclose);
    if (!properties.valid() || !type.valid() || H5Pget_layout(properties.id()) != H5D_CHUNKED) return;
    hsize_t chunk[H5S_MAX_RANK];
    const int rank = H5Pget_chunk(properties.id(), H5S_MAX_RANK, chunk);
    std::uint64_t bytes = H5Tget_size(type.id());
    for (int d = 0; d < rank; ++d) bytes = saturated_product(bytes, chunk[d]);
    if (bytes > max_inflated_size(file.size()))
        file.fail("the voxel data set is stored in chunks of " + std::to_string(bytes) + " bytes, more than the " +
                  std::to_string(file.size()) + "-byte file can hold even compressed");
    if (rank > 0) check_chunk_sizes(file, data_set, properties.id(), bytes, chunk[0], slices);
}

}  // namespace

void check_hdf5_voxel_data(const std::string& path, std::optional<std::array<std::int64_t, 2>> slices) {
    const InputFile file(path);
    H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
    const Handle h5(H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), H5Fclose);
    if (!h5.valid()) return;  // ITK says what is wrong
    const Handle data_set(H5Dopen2(h5.id(), "/ITKImage/0/VoxelData", H5P_DEFAULT), H5Dclose);
    if (!data_set.valid()) return;
    const hsize_t stored = H5Dget_storage_size(data_set.id());
    if (stored > file.size())
        file.fail("the voxel data set claims " + std::to_string(stored) + " bytes of storage, but the file holds " +
                  std::to_string(file.size()));
    check_chunks(file, data_set.id(), slices);
}

}  // namespace dsreg::volume_io_detail
