// dsreg Python module — numpy arrays in and out, without copies where the layouts agree.
#pragma once

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "dsreg/volume.hpp"
#include "dsreg/voxel_array.hpp"

namespace dsreg::python {

namespace py = pybind11;

/// The 3-D array `values` (indexed [i, j, k], i along x) as a VoxelArray read in place: its
/// strides, dtype and byte order as they are. Throws dsreg::Error naming `what` (e.g. "mask")
/// for another number of dimensions or a dtype that is neither bool, integer nor float.
VoxelArray voxel_array_of(const py::array& values, const std::string& what);

/// A numpy array that owns `data` (moved, not copied) and shows it with `dims` as [i, j, k],
/// x fastest (Fortran order, dsreg's linear index).
template <typename T>
py::array fortran_array(std::vector<T>&& data, const Index3& dims, const py::dtype& dtype) {
    auto* owner = new std::vector<T>(std::move(data));
    py::capsule free_owner(owner, [](void* p) { delete static_cast<std::vector<T>*>(p); });
    const auto item = static_cast<py::ssize_t>(sizeof(T));
    const std::vector<py::ssize_t> shape{dims[0], dims[1], dims[2]};
    const std::vector<py::ssize_t> strides{item, item * dims[0], item * dims[0] * dims[1]};
    return py::array(dtype, shape, strides, owner->data(), free_owner);
}

}  // namespace dsreg::python
