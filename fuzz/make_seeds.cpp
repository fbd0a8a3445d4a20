// dsreg — writes the seed corpus of the fuzz targets with the project's own writers:
//
//   dsreg_fuzz_seeds OUT_DIR      creates OUT_DIR/<target>/seed-* for every target
//
// Small volumes (.vol v2/v3, .longvol v2/v3, .pgm3d P2/P5 with 1- and 2-byte values, .raw of
// several types; NIfTI, NRRD, MetaImage, TIFF, HDF5 and VTK images by ITK's writers, single
// DICOM slices, .npy), polynomials (the named
// shapes, written by Polynomial::to_string), normals files (write_normals_file) and meshes
// (write_mesh: OBJ, OFF, PLY with attributes, STL, VTK, VTP).
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <string>
#include <utility>
#include <vector>

#include "dsreg/implicit_shape.hpp"
#include "dsreg/mesh_io.hpp"
#include "dsreg/normals_file.hpp"
#include "dsreg/volume_io.hpp"
#include "fuzz_targets.hpp"

namespace fs = std::filesystem;
using namespace dsreg;

namespace {

void write_bytes(const fs::path& path, const std::vector<std::uint8_t>& bytes) {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
    if (!out) throw std::runtime_error("cannot write " + path.string());
}

void write_text(const fs::path& path, const std::string& text) {
    write_bytes(path, std::vector<std::uint8_t>(text.begin(), text.end()));
}

std::vector<std::uint8_t> read_bytes(const fs::path& path) {
    std::ifstream in(path, std::ios::binary);
    return std::vector<std::uint8_t>(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

/// A small ball-like object in a dims[0]×dims[1]×dims[2] grid, values in 0..max_value.
template <typename T>
std::vector<T> ball_values(const Index3& dims, T max_value) {
    std::vector<T> values;
    const double cx = (dims[0] - 1) / 2.0, cy = (dims[1] - 1) / 2.0, cz = (dims[2] - 1) / 2.0;
    const double r = std::min({dims[0], dims[1], dims[2]}) / 2.0;
    for (std::int64_t k = 0; k < dims[2]; ++k)
        for (std::int64_t j = 0; j < dims[1]; ++j)
            for (std::int64_t i = 0; i < dims[0]; ++i) {
                const double d = std::sqrt((i - cx) * (i - cx) + (j - cy) * (j - cy) + (k - cz) * (k - cz));
                values.push_back(d <= r ? static_cast<T>(std::llround(max_value * (1.0 - d / (r + 1)))) : T(0));
            }
    return values;
}

void volume_seeds(const fs::path& out) {
    const Index3 dims{5, 4, 3};
    const auto bytes = ball_values<std::uint8_t>(dims, 200);
    write_vol((out / "vol" / "seed-v2.vol").string(), dims, bytes, 2);
    write_vol((out / "vol" / "seed-v3.vol").string(), dims, bytes, 3);
    write_vol((out / "vol" / "seed-one-voxel.vol").string(), {1, 1, 1}, {1}, 3);
    const auto longs = ball_values<std::uint64_t>(dims, std::uint64_t(1) << 40);
    write_longvol((out / "longvol" / "seed-v2.longvol").string(), dims, longs, 2);
    write_longvol((out / "longvol" / "seed-v3.longvol").string(), dims, longs, 3);
    write_pgm3d((out / "pgm3d" / "seed-p5-byte.pgm3d").string(), dims, ball_values<std::uint16_t>(dims, 200), true);
    write_pgm3d((out / "pgm3d" / "seed-p5-word.pgm3d").string(), dims, ball_values<std::uint16_t>(dims, 4000), true);
    write_pgm3d((out / "pgm3d" / "seed-p2.pgm3d").string(), dims, ball_values<std::uint16_t>(dims, 300), false);

    // .raw: the payload of a .vol v2 (its bytes after the header), then 16-bit and float layouts.
    const std::vector<std::uint8_t> vol = read_bytes(out / "vol" / "seed-v2.vol");
    const std::vector<std::uint8_t> payload(vol.end() - static_cast<std::ptrdiff_t>(bytes.size()), vol.end());
    write_bytes(out / "raw" / "seed-uint8", fuzz::raw_input(5, 4, 3, 0, false, 0, payload));
    std::vector<std::uint8_t> words;
    for (const std::uint8_t b : payload) words.insert(words.end(), {std::uint8_t(0), b});
    write_bytes(out / "raw" / "seed-int16-big-endian", fuzz::raw_input(5, 4, 3, 3, true, 0, words));
    std::vector<std::uint8_t> floats = {'H', 'D', 'R', '!'};
    for (const std::uint8_t b : payload) {
        const float value = b / 100.0f;
        const auto* p = reinterpret_cast<const std::uint8_t*>(&value);
        floats.insert(floats.end(), p, p + 4);
    }
    write_bytes(out / "raw" / "seed-float32-header", fuzz::raw_input(5, 4, 3, 8, false, 4, floats));
}

/// One slice of a DICOM series written by write_dicom_series (a single-frame .dcm file).
void dicom_slice_seed(const fs::path& out, const std::string& name, const VoxelGrid& grid, const std::vector<double>& values,
                      RawVoxelType type) {
    const fs::path series = out / ".dicom-series";
    fs::create_directories(series);
    write_dicom_series(series.string(), grid, values, type);
    fs::copy_file(series / "slice0001.dcm", out / "dicom" / name);
    fs::remove_all(series);
}

/// TIFF stacks, HDF5 and VTK legacy images by ITK's writers (write_image), and DICOM slices: the
/// formats ITK decodes, of the same small image.
void itk_seeds(const fs::path& out, const VoxelGrid& grid, const std::vector<double>& values) {
    const std::pair<const char*, RawVoxelType> images[] = {
        {"tiff/seed-uint8.tif", RawVoxelType::UInt8},   {"tiff/seed-uint16.tif", RawVoxelType::UInt16},
        {"hdf5/seed-uint8.h5", RawVoxelType::UInt8},    {"hdf5/seed-float32.h5", RawVoxelType::Float32},
        {"vtkimage/seed-uint8.vtk", RawVoxelType::UInt8}, {"vtkimage/seed-int16.vtk", RawVoxelType::Int16},
    };
    for (const auto& [file, type] : images) write_image((out / file).string(), grid, values, type, false);
    dicom_slice_seed(out, "seed-uint8.dcm", grid, values, RawVoxelType::UInt8);
    dicom_slice_seed(out, "seed-int16.dcm", grid, values, RawVoxelType::Int16);
}

/// NIfTI (.nii, .nii.gz, 8- and 16-bit), NRRD (raw, gzip), MetaImage (raw, compressed) and .npy
/// files of a small oblique image, written by ITK's writers (write_image) and write_npy.
void medical_seeds(const fs::path& out) {
    VoxelGrid grid;
    grid.dims = {5, 4, 3};
    grid.spacing = Eigen::Vector3d(0.75, 1.0, 1.25);
    grid.origin = Eigen::Vector3d(-3.5, 2.25, 1.0);
    const double c = std::cos(0.4), s = std::sin(0.4);
    grid.direction << c, -s, 0, s, c, 0, 0, 0, 1;
    std::vector<double> values;
    for (const std::uint8_t b : ball_values<std::uint8_t>(grid.dims, 200)) values.push_back(b);
    write_image((out / "nifti" / "seed-uint8.nii").string(), grid, values, RawVoxelType::UInt8, false);
    write_image((out / "nifti" / "seed-int16.nii.gz").string(), grid, values, RawVoxelType::Int16, true);
    write_image((out / "nrrd" / "seed-raw.nrrd").string(), grid, values, RawVoxelType::UInt16, false);
    write_image((out / "nrrd" / "seed-gzip.nrrd").string(), grid, values, RawVoxelType::Float32, true);
    write_image((out / "metaimage" / "seed-raw.mha").string(), grid, values, RawVoxelType::Int32, false);
    write_image((out / "metaimage" / "seed-zlib.mha").string(), grid, values, RawVoxelType::UInt8, true);
    write_npy((out / "npy" / "seed-c-order.npy").string(), grid.dims, values, RawVoxelType::Int16, false);
    write_npy((out / "npy" / "seed-fortran.npy").string(), grid.dims, values, RawVoxelType::Float64, true);
    itk_seeds(out, grid, values);
}

void polynomial_seeds(const fs::path& out) {
    int n = 0;
    for (const std::string& name : named_shape_names())
        write_text(out / "polynomial" / ("seed-" + name), make_shape(name).polynomial.to_string());
    for (const char* text : {"x^2+y^2+z^2-81", "-1*(8-0.03*x^4+2*x^2)", "(x-1)^3*(y+.5)-2.5E+4*z", "x^4+y^4+z^4-2*(x^2+y^2+z^2)"})
        write_text(out / "polynomial" / ("seed-text-" + std::to_string(n++)), Polynomial::parse(text).to_string());
}

void normals_seeds(const fs::path& out) {
    const DigitalSurface surface = fuzz::normals_target_surface();
    PointMatrix trivial(surface.face_count(), 3);
    PointMatrix tilted(surface.face_count(), 3);
    for (std::int64_t f = 0; f < surface.face_count(); ++f) {
        trivial.row(f) = surface.surfels[std::size_t(f)].trivial_normal().transpose();
        tilted.row(f) = (trivial.row(f) + Eigen::RowVector3d(0.1, -0.2, 0.05 * double(f % 3))).normalized();
    }
    write_normals_file((out / "normals" / "seed-trivial").string(), surface, trivial, "trivial normals");
    write_normals_file((out / "normals" / "seed-tilted").string(), surface, tilted, "tilted");
}

void mesh_seeds(const fs::path& out) {
    const DigitalSurface surface = fuzz::normals_target_surface();
    PolygonMesh quads;
    quads.vertices = surface.vertices;
    quads.faces = surface.quads;
    PolygonMesh attributed = quads;
    attributed.face_normals.resize(quads.faces.rows(), 3);
    for (std::int64_t f = 0; f < quads.faces.rows(); ++f)
        attributed.face_normals.row(f) = surface.surfels[std::size_t(f)].trivial_normal().transpose();
    attributed.vertex_scalars.emplace_back("v", Eigen::VectorXd::LinSpaced(quads.vertices.rows(), 0.0, 1.0));
    const PolygonMesh triangles = triangulate_shorter_diagonal(quads);
    for (const char* format : {"obj", "off", "ply", "stl", "vtk", "vtp"}) {
        const fs::path folder = out / format;
        write_mesh((folder / (std::string("seed-quads.") + format)).string(), quads);
        write_mesh((folder / (std::string("seed-triangles.") + format)).string(), triangles);
    }
    attributed.coordinate_system = "LPS";
    for (const char* format : {"ply", "vtk", "vtp"})
        write_mesh((out / format / (std::string("seed-attributes.") + format)).string(), attributed);
}

}  // namespace

int main(int argc, char** argv) {
    if (argc != 2) {
        std::cerr << "usage: dsreg_fuzz_seeds OUT_DIR\n";
        return 2;
    }
    try {
        const fs::path out = argv[1];
        for (const auto& target : fuzz::targets()) fs::create_directories(out / target.name);
        volume_seeds(out);
        medical_seeds(out);
        polynomial_seeds(out);
        normals_seeds(out);
        mesh_seeds(out);
        std::size_t count = 0;
        for (const auto& entry : fs::recursive_directory_iterator(out)) count += entry.is_regular_file() ? 1 : 0;
        std::cout << "dsreg_fuzz_seeds: " << count << " seed inputs in " << out.string() << "\n";
    } catch (const std::exception& error) {
        std::cerr << "dsreg_fuzz_seeds: " << error.what() << "\n";
        return 1;
    }
    return 0;
}
