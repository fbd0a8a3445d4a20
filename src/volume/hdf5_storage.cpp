// dsreg — the voxel data set of an HDF5 image as ITK writes it (/ITKImage/0/VoxelData), checked
// with HDF5's C library before ITK reads it.
//
// HDF5 allocates a chunk as its index says it is stored, and decodes it into a buffer of the
// chunk's dimensions: a chunk index claiming 1.6 GB in a 13 KB file made HDF5 allocate that much
// (found by fuzzing). So the storage the data set claims must fit in the file, and a chunk must
// be no larger than the file could hold compressed. HDF5 prints its error stack on stderr by
// default; dsreg turns it off (its own messages, and ITK's, name the file).
#include <hdf5.h>

#include <cstdint>
#include <string>

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

/// A chunk that the whole file could not hold even compressed is refused: HDF5 allocates it.
void check_chunks(const InputFile& file, hid_t data_set) {
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
}

}  // namespace

void check_hdf5_voxel_data(const std::string& path) {
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
    check_chunks(file, data_set.id());
}

}  // namespace dsreg::volume_io_detail
