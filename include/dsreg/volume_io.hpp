// dsreg — reading and writing voxel volumes.
//
// Formats (chosen by the file name, case-insensitively; a folder is a DICOM series):
//  * DGtal's .vol (v2 raw, v3 zlib), .longvol/.lvol, PGM3D .pgm3d/.p3d, headerless .raw;
//  * medical and scientific images, read the way ITK (3D Slicer, SimpleITK, ITK-SNAP) reads
//    them: NIfTI-1/2 (.nii, .nii.gz, .hdr/.img pairs, .img.gz), NRRD (.nrrd, .nhdr with a
//    detached raw or gzip data file), MetaImage (.mha, .mhd with its data file), multi-page TIFF
//    (.tif, .tiff), HDF5 as ITK writes it (.h5, .hdf5, .hdf), VTK legacy images (.vtk), DICOM
//    (a folder holding one series, or one multi-frame .dcm file); NumPy .npy (C or Fortran order:
//    voxel (i,j,k) is array[i, j, k] whatever the memory order).
// Geometry: DGtal formats, .raw and .npy have spacing 1, origin 0 and identity direction; the
// medical formats give ITK's spacing, origin and direction cosines (LPS), see volume.hpp. A
// negative spacing is made positive by flipping its direction column; a direction within 1e-4 of
// orthonormal is orthonormalized (polar decomposition; noted in VolumeFileInfo::notes), others are
// rejected, since the pipeline's grid frame needs distances to be the same as in the world.
// Only scalar images with at most 3 dimensions of more than one voxel are accepted: a 4-D image
// (time series) or a vector, RGB or complex image is rejected with a message saying so.
//
// Readers decode the voxel values and keep those inside a ValueRange as the object, so a volume
// costs one byte per voxel in memory whatever its value type: values are thresholded as they are
// decoded (after conversion to double, so 64-bit values above 2^53 are compared rounded; NIfTI's
// scl_slope/scl_inter are applied first, as ITK does). read_volume_values keeps the values instead
// (as float, 4 bytes per voxel), through the same header parsing, size checks and decoders; e.g.
// for per-vertex weight maps. NIfTI, NRRD, MetaImage and .npy payloads are decoded by dsreg itself
// as they stream from the file (ITK reads their headers; its readers would hold the whole image
// in memory, twice for .nii.gz); TIFF, HDF5, VTK and DICOM payloads are read by ITK, slab by slab
// where ITK can stream the format (HDF5, VTK, DICOM series), else whole (TIFF, .dcm).
// Every reader checks the header against the real size of the file(s) before allocating: a stored
// payload must fit in its file (exactly, for the DGtal formats and .npy); a compressed payload must
// be large enough to inflate to the announced size (deflate cannot exceed 1032:1; the same bound is
// applied to the images ITK decodes) and is inflated with a hard cap at that size.
// Any malformed input throws dsreg::Error whose message starts with "<path>: " and names the
// problem; ITK's exceptions are translated into such messages.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "dsreg/volume.hpp"

namespace dsreg {

/// A grey-level volume: one value per voxel, x fastest (linear index = grid.linear_index).
/// Values are stored as float: integers up to 2^24 are exact, larger ones are rounded to 24
/// significant bits, float64 values to float precision.
struct ScalarVolume {
    VoxelGrid grid;
    std::vector<float> values;

    float value(std::int64_t i, std::int64_t j, std::int64_t k) const {
        return values[static_cast<std::size_t>(grid.linear_index(i, j, k))];
    }
};

/// Scalar type of the voxels of a headerless raw volume.
enum class RawVoxelType { UInt8, Int8, UInt16, Int16, UInt32, Int32, UInt64, Int64, Float32, Float64 };

/// What a raw volume file does not say about itself.
struct RawVolumeLayout {
    Index3 dims{0, 0, 0};
    RawVoxelType type = RawVoxelType::UInt8;
    bool big_endian = false;
    std::uint64_t header_bytes = 0;  ///< bytes to skip at the start of the file
};

/// What a reader tells about the file besides the voxels (optional output of read_volume).
struct VolumeFileInfo {
    std::string format;               ///< "NIfTI-1", "NRRD", "MetaImage", "DICOM series", ".vol", ...
    std::string value_type;           ///< type of the stored values: "uint8", "int16", "float32", ...
    std::vector<std::string> notes;   ///< what the reader assumed or corrected, one sentence each
    /// The file places its voxels in world space (origin and direction cosines: the medical
    /// formats but TIFF), so that meshes can be written in LPS or RAS (dsreg/world_space.hpp).
    bool world_geometry = false;
};

/// Limits that protect the machine from absurd headers.
struct VolumeLimits {
    std::int64_t max_voxels = std::int64_t(1) << 34;  ///< 16 Gi voxels
    std::int64_t max_labels = std::int64_t(1) << 20;  ///< distinct labels of a label map (read_label_volume)
};

/// Parse a RawVoxelType from its CLI name: uint8 int8 uint16 int16 uint32 int32 uint64 int64
/// float32 float64 (also u8, i16, f32, double, float ...). Throws dsreg::Error otherwise.
RawVoxelType parse_raw_voxel_type(const std::string& name);

/// DGtal .vol, versions 2 (raw bytes) and 3 (zlib payload). Header: "Key: value" lines ended by
/// a line holding a single "."; X, Y, Z (positive integers) and Version (2 or 3) are required,
/// keys may not repeat, Voxel-Size must be 1 if present, other keys (Center-*, Alpha-Color,
/// *-Endian) are ignored. Payload: X·Y·Z unsigned bytes, x fastest.
BinaryVolume read_vol(const std::string& path, const ValueRange& range = {}, const VolumeLimits& limits = {});
/// DGtal .longvol: the .vol header rules, with 8-byte unsigned values stored little-endian
/// (least significant byte first, as DGtal's LongvolWriter writes them). Lvoxel-Size is ignored:
/// DGtal itself writes "Lvoxel-Size: 4" for its 8-byte values.
BinaryVolume read_longvol(const std::string& path, const ValueRange& range = {}, const VolumeLimits& limits = {});
/// PGM 3D, ASCII ("P2-3D") or binary ("P5-3D"; 1 byte per value if maxval < 256, else 2 bytes
/// big-endian). Header: magic, width height depth maxval (maxval in 1..65535), '#' comments
/// allowed between them; P5-3D has exactly one whitespace byte before the data. Values above
/// maxval, non-numeric ASCII values, missing values and trailing data are errors.
BinaryVolume read_pgm3d(const std::string& path, const ValueRange& range = {}, const VolumeLimits& limits = {});
/// Headerless raw volume with the given layout: the file must hold exactly
/// layout.header_bytes + X·Y·Z·(bytes per value) bytes.
BinaryVolume read_raw(const std::string& path, const RawVolumeLayout& layout, const ValueRange& range = {},
                      const VolumeLimits& limits = {});

/// Chooses the reader from the file name (see the list of formats above): a folder is read as a
/// DICOM series. A .raw file needs `raw_layout`; it is ignored for the other formats. Any other
/// extension throws dsreg::Error. `info`, if given, receives the format, value type and notes.
BinaryVolume read_volume(const std::string& path, const ValueRange& range = {}, const RawVolumeLayout* raw_layout = nullptr,
                         const VolumeLimits& limits = {}, VolumeFileInfo* info = nullptr);

/// The grid of a volume file (what read_volume gives as grid: dims, spacing, origin, direction)
/// from its header alone, after the same checks of the header against the file size; `info`, if
/// given, receives the format, value type and whether the file has a world geometry. The
/// formats read_volume_box reads (every format but a DICOM series).
VoxelGrid read_volume_grid(const std::string& path, const RawVolumeLayout* raw_layout = nullptr, const VolumeLimits& limits = {},
                           VolumeFileInfo* info = nullptr);
/// read_volume_grid(...).dims.
Index3 read_volume_dims(const std::string& path, const RawVolumeLayout* raw_layout = nullptr, const VolumeLimits& limits = {});

/// The voxels of `box` of a volume file (a non-empty box inside its grid), as read_volume would
/// give them, with memory for the box alone (plus, for formats ITK decodes, a slab of at most
/// 16 MiB of whole x-y slices): grid.dims = box.size(), the file's spacing and direction, and
/// the origin of the file's grid frame moved to voxel box.lo (origin + spacing ⊙ box.lo).
/// Stored payloads (.raw, .vol and .longvol version 2, binary .pgm3d, .nii, .hdr/.img, raw
/// NRRD and MetaImage, .npy) are read from the offset of the box's first x-y slice to the end of
/// its last; zlib, gzip and ASCII payloads (.nii.gz, gzip NRRD, compressed MetaImage) are decoded
/// from the start, keeping the box (the time of the file up to the box, the memory of the box).
/// HDF5, VTK and the other images ITK reads by slices (ImageIO::CanStreamRead) are read slab by
/// slab over the box's slices; TIFF and DICOM files, which ITK reads whole, and DICOM series are
/// refused (block-wise runs would hold the whole image). The header and payload size checks
/// are those of read_volume; values outside the box are not decoded, so not checked (e.g.
/// against a PGM maxval). Label maps are read whole. Throws dsreg::Error naming the file.
BinaryVolume read_volume_box(const std::string& path, const VoxelBox& box, const ValueRange& range = {},
                             const RawVolumeLayout* raw_layout = nullptr, const VolumeLimits& limits = {});

/// The voxel values of a volume file, any format read_volume accepts (same extension rules,
/// same checks, same errors), without thresholding. PGM values are checked against maxval.
ScalarVolume read_volume_values(const std::string& path, const RawVolumeLayout* raw_layout = nullptr,
                                const VolumeLimits& limits = {}, VolumeFileInfo* info = nullptr);

/// Writes a scalar image through ITK's writer for the format named by `path`'s extension (.nii,
/// .nii.gz, .hdr, .nrrd, .nhdr, .mha, .mhd, .tif, .h5, .vtk), with `grid`'s spacing, origin and
/// direction, one value per voxel (x fastest) converted to `type`, compressed where the format
/// allows it and `compress` is set. For tests, fuzz seeds and users converting volumes. Throws
/// dsreg::Error naming `path` for a bad grid, a value count other than the voxel count, or an
/// ITK failure; formats of one file are written atomically.
void write_image(const std::string& path, const VoxelGrid& grid, const std::vector<double>& values, RawVoxelType type,
                 bool compress = true);

/// Writes a DICOM series through ITK (GDCM): one file per slice k (slice0000.dcm, ...) in the
/// existing folder `folder`, with Image Position/Orientation (Patient) from `grid`, one new Study,
/// Series and Frame of Reference UID, and the values converted to `type` (8/16-bit integers
/// only: uint8, int8, uint16, int16). Throws dsreg::Error naming the folder on failure.
void write_dicom_series(const std::string& folder, const VoxelGrid& grid, const std::vector<double>& values,
                        RawVoxelType type);

/// Writes a NumPy .npy file (format 1.0, little-endian, C order unless `fortran_order`) holding
/// the array a[i, j, k] = values[grid index of (i,j,k)] converted to `type`. Atomic.
void write_npy(const std::string& path, const Index3& dims, const std::vector<double>& values, RawVoxelType type,
               bool fortran_order = false);

/// A label map (any format read_volume accepts, same checks and errors): every distinct value
/// is a label, 0 the background. Values must be integers (below 2^53 in magnitude) and there may
/// be at most limits.max_labels distinct ones; otherwise dsreg::Error names the file and the
/// voxel. 4 bytes per voxel (label indices, volume.hpp). The grid has the file's spacing, origin
/// and direction, as read_volume's; `info`, if given, receives the format, value type and notes.
LabelVolume read_label_volume(const std::string& path, const RawVolumeLayout* raw_layout = nullptr,
                              const VolumeLimits& limits = {}, VolumeFileInfo* info = nullptr);

/// Writers (atomic: a temporary file renamed into place). `values` holds one value per voxel of
/// `dims`, x fastest. Used by tests, fuzz seeds and users converting volumes. They throw
/// dsreg::Error (and create no file) unless dims are positive, values.size() is their product
/// and version is 2 or 3. .vol/.longvol headers carry every key DGtal's readers require, and no
/// Center-* keys (so DGtal reads the domain from (0,0,0)); version 3 payloads are one zlib
/// stream, as compress() makes. write_pgm3d uses maxval = max(1, largest value).
void write_vol(const std::string& path, const Index3& dims, const std::vector<std::uint8_t>& values, int version = 3);
void write_longvol(const std::string& path, const Index3& dims, const std::vector<std::uint64_t>& values, int version = 3);
void write_pgm3d(const std::string& path, const Index3& dims, const std::vector<std::uint16_t>& values, bool binary = true);

}  // namespace dsreg
