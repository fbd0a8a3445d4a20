// dsreg — the voxel data set of an HDF5 image as ITK writes it (/ITKImage/0/VoxelData), checked
// with HDF5's C library before ITK reads it.
//
// HDF5 allocates a chunk as its index says it is stored, and decodes it into a buffer of the
// chunk's dimensions: a chunk index claiming 1.6 GB in a 13 KB file made HDF5 allocate that much
// (found by fuzzing). So the storage the data set claims must fit in the file, and its chunks
// must not be larger than the data set. HDF5 prints its error stack on stderr by default; dsreg
// turns it off (its own messages, and ITK's, name the file).
#include <hdf5.h>

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

/// Chunks no larger than the data set along any axis.
void check_chunks(const InputFile& file, hid_t data_set, hid_t space) {
    const Handle properties(H5Dget_create_plist(data_set), H5Pclose);
    if (!properties.valid() || H5Pget_layout(properties.id()) != H5D_CHUNKED) return;
    const int rank = H5Sget_simple_extent_ndims(space);
    if (rank < 1 || rank > 32) return;
    std::vector<hsize_t> dims(static_cast<std::size_t>(rank)), chunk(static_cast<std::size_t>(rank));
    if (H5Sget_simple_extent_dims(space, dims.data(), nullptr) != rank || H5Pget_chunk(properties.id(), rank, chunk.data()) != rank)
        return;
    for (std::size_t d = 0; d < dims.size(); ++d)
        if (chunk[d] > dims[d])
            file.fail("the voxel data set is stored in chunks of " + std::to_string(chunk[d]) + " values along axis " +
                      std::to_string(d + 1) + ", where it holds " + std::to_string(dims[d]));
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
    const Handle space(H5Dget_space(data_set.id()), H5Sclose);
    if (space.valid()) check_chunks(file, data_set.id(), space.id());
}

}  // namespace dsreg::volume_io_detail
