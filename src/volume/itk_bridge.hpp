// dsreg — the thin adapter over ITK's image IO (not public API).
//
// itk_bridge.cpp is the only translation unit that includes ITK (heavy to compile, and ITK
// bundles its own Eigen, which must not meet the system Eigen in one translation unit): this
// header is therefore plain C++ with no Eigen, and the adapter only moves headers, voxels and
// tags between files and plain buffers. The checks and the decoding into masks live elsewhere
// (itk_volume_io.cpp, image_geometry.cpp).
//
// Each ImageIO is created explicitly for the format dsreg has recognised from the file name
// (itk::NiftiImageIO::New(), ...): ITK's IO factories are never used, so no factory has to be
// registered at link time (no ITK_USE_FILE, no itkImageIOFactoryRegisterManager) and a file is
// never handed to an IO dsreg did not choose. Every ITK exception becomes a dsreg::Error whose
// message starts with "<path>: ".
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "sample_format.hpp"

namespace dsreg::volume_io_detail {

enum class ItkFormat { Nifti, Nrrd, MetaImage, Tiff, Hdf5, VtkImage, DicomFile };

/// "NIfTI", "NRRD", "MetaImage", "TIFF", "HDF5", "VTK image", "DICOM".
const char* itk_format_name(ItkFormat format);

/// An image as ITK describes it: any number of dimensions, pixels of one or more components.
struct ImageHeader {
    std::string format;                           ///< "NIfTI-1", "NRRD", ... (messages, info)
    std::vector<std::int64_t> sizes;              ///< voxels along each dimension
    std::vector<double> spacing, origin;          ///< one per dimension (world: LPS)
    std::vector<std::vector<double>> direction;   ///< direction[c]: world vector of axis c
    unsigned components = 1;                      ///< values per voxel
    std::string pixel_type = "scalar";            ///< "scalar", "vector", "rgb", "complex", ...
    std::string value_type;                       ///< "uint8" ... "float64", or ITK's name for others
    bool value_type_supported = false;            ///< an integer of 1-8 bytes, float32 or float64
    SampleFormat sample;                          ///< how one value is stored (host byte order)
};

/// ITK's reading of the header of `path` (no voxel is read).
ImageHeader read_itk_header(const std::string& path, ItkFormat format);

/// Reads the DICOM files `paths` through GDCM in one child process (each file's header, and its
/// voxels up to 256 MiB) and throws dsreg::Error naming the file being read if that process dies
/// of a signal. Debian's GDCM is built with its assertions on and aborts on some damaged data
/// instead of failing; check_dicom_meta refuses the cases fuzzing found, this contains the
/// others. A file GDCM fails on normally passes here: the reader that follows reports its error.
void check_dicom_in_child_process(const std::vector<std::string>& paths);

/// An image file opened through ITK to read its voxels.
class ItkImageReader {
public:
    ItkImageReader(const std::string& path, ItkFormat format);  ///< reads the header
    ~ItkImageReader();
    const ImageHeader& header() const { return header_; }
    /// Whether ITK reads a region of slices without decoding the whole image.
    bool can_stream() const;
    /// Values of slices [first, first + count) (of a 3-D or higher image; the whole image for
    /// fewer dimensions) into `buffer`, as header().sample, x fastest.
    void read_slices(std::int64_t first, std::int64_t count, void* buffer);

private:
    struct Io;
    std::string path_;
    ItkFormat format_;
    std::unique_ptr<Io> io_;
    ImageHeader header_;
};

/// A DICOM series in a folder (which must hold exactly one), files sorted by GDCM along the
/// slice normal, read through ITK's series reader as doubles (after rescale slope/intercept).
class DicomSeriesReader {
public:
    explicit DicomSeriesReader(const std::string& folder);
    ~DicomSeriesReader();
    /// 3-D: the third direction is the one from the first to the last slice position (not forced
    /// orthogonal, so that a gantry tilt shows as a sheared grid).
    const ImageHeader& header() const { return header_; }
    const std::vector<std::string>& files() const { return files_; }
    /// Slices [first, first + count) as doubles, x fastest.
    void read_slices(std::int64_t first, std::int64_t count, double* buffer);
    /// The largest difference between the spacing of two neighbouring slices read so far and the
    /// mean spacing (ITK's "ITK_non_uniform_sampling_deviation"), 0 for even slices.
    double spacing_deviation() const { return deviation_; }

private:
    struct Series;
    std::string folder_;
    std::unique_ptr<Series> series_;
    ImageHeader header_;
    std::vector<std::string> files_;
    double deviation_ = 0;
};

/// Writes `image` (3-D scalar: sizes, spacing, origin, direction, sample) with the values in
/// `buffer` (host order) through ITK's writer for `format`.
void write_itk_image(const std::string& path, ItkFormat format, const ImageHeader& image, const void* buffer, bool compress);

/// Writes one DICOM slice (a 3-D image of one slice) with these extra tags ("gggg|eeee", value).
void write_itk_dicom_slice(const std::string& path, const ImageHeader& slice, const void* buffer,
                           const std::vector<std::pair<std::string, std::string>>& tags);

}  // namespace dsreg::volume_io_detail
