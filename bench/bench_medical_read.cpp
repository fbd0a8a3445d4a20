// dsreg — reading a large NIfTI label map: dsreg's streaming reader against ITK's own reader.
//
//   dsreg_bench_medical_read write FILE [N]   writes an N³ (default 512) uint8 label map with ITK's
//                                             writer (five nested ellipsoids, labels 1..5)
//   dsreg_bench_medical_read dsreg FILE       read_volume: the 1-byte mask, streaming
//   dsreg_bench_medical_read values FILE      read_volume_values: 4 bytes per voxel
//   dsreg_bench_medical_read itk FILE         ITK's NiftiImageIO reading the whole image into
//                                             its buffer (what itk::ImageFileReader does)
//   dsreg_bench_medical_read dims FILE        read_volume_dims: the header alone (the process's
//                                             own memory, for the figures of the others)
//   dsreg_bench_medical_read write-dicom DIR [N]  writes the label map as a DICOM series of N
//                                             slices (int16, default N 256) into the folder DIR
//   dsreg_bench_medical_read dicom-child DIR  check_dicom_in_child_process on the files of DIR:
//                                             what the child-process guard adds to a series read
//   dsreg_bench_medical_read boxes FILE [B]   read_volume_box of every B³ block (default 64) in
//                                             turn, as a block-wise run reads them (any format
//                                             read_volume_box reads: .nii, .nii.gz, .h5, ...)
// Each prints its wall time; bench/medical_read.sh runs them under hyperfine and /usr/bin/time
// for the figures of docs/benchmarks.md.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include "../src/volume/itk_bridge.hpp"
#include "dsreg/blocks.hpp"
#include "dsreg/error.hpp"
#include "dsreg/volume_io.hpp"

using namespace dsreg;

namespace {

std::vector<double> label_map(std::int64_t n) {
    std::vector<double> values(static_cast<std::size_t>(n * n * n));
    const double c = (n - 1) / 2.0;
    std::size_t at = 0;
    for (std::int64_t k = 0; k < n; ++k)
        for (std::int64_t j = 0; j < n; ++j)
            for (std::int64_t i = 0; i < n; ++i) {
                const double x = (i - c) / n, y = (j - c) / n, z = (k - c) / n;
                const double r = std::sqrt(x * x / 0.16 + y * y / 0.09 + z * z / 0.12);
                values[at++] = r < 1 ? std::ceil(5 * (1 - r)) : 0;
            }
    return values;
}

double seconds_since(std::chrono::steady_clock::time_point start) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

int main(int argc, char** argv) {
    if (argc < 3) {
        std::fprintf(stderr, "usage: %s write|write-dicom|dsreg|values|itk|dims|boxes|dicom-child FILE [N|B]\n", argv[0]);
        return 2;
    }
    const std::string mode = argv[1], path = argv[2];
    try {
        const auto start = std::chrono::steady_clock::now();
        if (mode == "write") {
            const std::int64_t n = argc > 3 ? std::stoll(argv[3]) : 512;
            VoxelGrid grid;
            grid.dims = {n, n, n};
            grid.spacing = Eigen::Vector3d(0.7, 0.7, 1.0);
            write_image(path, grid, label_map(n), RawVoxelType::UInt8);
        } else if (mode == "write-dicom") {
            const std::int64_t n = argc > 3 ? std::stoll(argv[3]) : 256;
            VoxelGrid grid;
            grid.dims = {n, n, n};
            grid.spacing = Eigen::Vector3d(0.7, 0.7, 1.0);
            std::filesystem::create_directories(path);
            write_dicom_series(path, grid, label_map(n), RawVoxelType::Int16);
        } else if (mode == "dicom-child") {
            std::vector<std::string> files;
            for (const auto& entry : std::filesystem::directory_iterator(path)) files.push_back(entry.path().string());
            volume_io_detail::check_dicom_in_child_process(files);
            std::printf("%zu files\n", files.size());
        } else if (mode == "dsreg") {
            const BinaryVolume volume = read_volume(path);
            std::printf("%lld object voxels\n", static_cast<long long>(volume.object_voxel_count()));
        } else if (mode == "values") {
            const ScalarVolume volume = read_volume_values(path);
            std::printf("%zu values\n", volume.values.size());
        } else if (mode == "dims") {
            const Index3 dims = read_volume_dims(path);
            std::printf("%lldx%lldx%lld voxels\n", static_cast<long long>(dims[0]), static_cast<long long>(dims[1]),
                        static_cast<long long>(dims[2]));
        } else if (mode == "boxes") {
            const std::int64_t b = argc > 3 ? std::stoll(argv[3]) : 64;
            const BlockLayout layout = blocks_of_size(read_volume_dims(path), {b, b, b});
            std::int64_t object = 0;
            for (std::int64_t block = 0; block < layout.block_count(); ++block)
                object += read_volume_box(path, layout.box(block)).object_voxel_count();
            std::printf("%lld object voxels in %lld boxes\n", static_cast<long long>(object),
                        static_cast<long long>(layout.block_count()));
        } else if (mode == "itk") {
            volume_io_detail::ItkImageReader reader(path, volume_io_detail::ItkFormat::Nifti);
            const auto& sizes = reader.header().sizes;
            std::vector<std::uint8_t> buffer(static_cast<std::size_t>(sizes[0] * sizes[1] * sizes[2]) *
                                             static_cast<std::size_t>(reader.header().sample.bytes));
            reader.read_slices(0, sizes[2], buffer.data());
            std::int64_t object = 0;
            for (const std::uint8_t v : buffer) object += v > 0;
            std::printf("%lld object voxels\n", static_cast<long long>(object));
        } else {
            std::fprintf(stderr, "unknown mode %s\n", mode.c_str());
            return 2;
        }
        std::printf("%s: %.3f s\n", mode.c_str(), seconds_since(start));
    } catch (const Error& error) {
        std::fprintf(stderr, "%s\n", error.what());
        return 1;
    }
    return 0;
}
