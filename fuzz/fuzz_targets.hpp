// dsreg — fuzz targets: one function per reader of untrusted input.
//
// Each target takes arbitrary bytes, hands them to one reader (through a temporary file for the
// file readers) and checks what the reader promises: either a dsreg::Error, or a result that
// satisfies the reader's guarantees (sizes match, indices in range, values finite, round trips
// exact). A broken promise aborts (a libFuzzer finding); any exception other than dsreg::Error
// escapes (std::bad_alloc, std::length_error, ...: also a finding).
//
// The same functions serve three programs (fuzz/CMakeLists.txt):
//   * dsreg_fuzz_<target>: libFuzzer executables (clang, DSREG_BUILD_FUZZERS=ON);
//   * dsreg_fuzz_replay: runs targets on files (regression corpus, seeds) with any compiler;
//   * dsreg_fuzz_seeds: writes the seed corpus with the project's own writers.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "dsreg/digital_surface.hpp"

namespace dsreg::fuzz {

/// What one input gave: accepted (parsed and checked), or rejected with this dsreg::Error message.
struct Outcome {
    bool accepted = false;
    std::string message;
};

using TargetFunction = Outcome (*)(const std::uint8_t* data, std::size_t size);

struct Target {
    const char* name;         ///< "vol", "ply", ...
    const char* description;  ///< what it reads
    TargetFunction run;
};

/// All targets: vol longvol pgm3d nifti nrrd metaimage npy tiff hdf5 dicom vtkimage raw polynomial normals obj off ply stl vtk vtp.
const std::vector<Target>& targets();

/// The target named `name`, or nullptr.
const Target* find_target(const std::string& name);

/// The .raw target reads a 15-byte prefix before the file contents: dims X, Y, Z as little-endian
/// signed 32-bit integers, the voxel type (byte % 10, in RawVoxelType order), flags (bit 0:
/// big-endian) and the number of header bytes to skip. This builds such an input.
std::vector<std::uint8_t> raw_input(std::int32_t x, std::int32_t y, std::int32_t z, int type, bool big_endian,
                                    int header_bytes, const std::vector<std::uint8_t>& file_contents);

/// The surface the "normals" target reads normals files for: the digital surface of four object
/// voxels of a 3x3x2 grid, two of them touching only along an edge, one only at a corner.
DigitalSurface normals_target_surface();

}  // namespace dsreg::fuzz
