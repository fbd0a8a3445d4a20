// dsreg Python module — numpy arrays in and out (numpy_arrays.hpp).
#include "numpy_arrays.hpp"

#include "dsreg/error.hpp"

namespace dsreg::python {

namespace {

std::string shape_text(const py::array& a) {
    std::string text = "(";
    for (py::ssize_t d = 0; d < a.ndim(); ++d) text += (d ? ", " : "") + std::to_string(a.shape(d));
    return text + (a.ndim() == 1 ? ",)" : ")");
}

bool host_is_big_endian() { return py::dtype::of<std::uint16_t>().attr("byteorder").cast<std::string>() == ">"; }

}  // namespace

VoxelArray voxel_array_of(const py::array& values, const std::string& what) {
    if (values.ndim() != 3)
        throw Error(what + ": a 3-D array indexed [i, j, k] is needed (got " + std::to_string(values.ndim()) +
                    "-D, shape " + shape_text(values) + ")");
    const py::dtype dtype = values.dtype();
    const char kind = dtype.kind();
    VoxelArray array;
    if (kind == 'b' || kind == 'u') array.kind = ValueKind::Unsigned;
    else if (kind == 'i') array.kind = ValueKind::Signed;
    else if (kind == 'f') array.kind = ValueKind::Float;
    else
        throw Error(what + ": dtype " + dtype.attr("name").cast<std::string>() +
                    " is not supported (bool, integers or floats)");
    array.bytes = static_cast<int>(dtype.itemsize());
    const std::string order = dtype.attr("byteorder").cast<std::string>();
    array.big_endian = order == ">" || (order == "=" && host_is_big_endian());
    array.data = static_cast<const std::uint8_t*>(values.data());
    for (int axis = 0; axis < 3; ++axis) {
        array.dims[axis] = values.shape(axis);
        array.byte_strides[axis] = values.strides(axis);
    }
    array.description = what + " " + std::to_string(array.dims[0]) + "x" + std::to_string(array.dims[1]) + "x" +
                        std::to_string(array.dims[2]) + " " + (kind == 'b' ? "bool" : value_type_name(array));
    check_voxel_array(array);  // e.g. float128, or an empty axis
    return array;
}

}  // namespace dsreg::python
