// dsreg — NIfTI-1, NIfTI-2 and Analyze 7.5 images: .nii, .nii.gz, .hdr/.img pairs (.img.gz).
//
// The 348-byte (NIfTI-1, Analyze) or 540-byte (NIfTI-2) header is parsed here, in either byte
// order, and checked before anything else reads the file; the payload (dims × value size bytes at
// vox_offset of the .nii, or of the .img) is then decoded here as it streams from the file,
// through zlib for .gz files, into the mask or values (one pass, no copy of the image).
// Geometry: ITK's NiftiImageIO reads the NIfTI-1 and Analyze headers, so that a file lands where
// 3D Slicer and SimpleITK put it. ITK 5.2 cannot read NIfTI-2, and it refuses NIfTI-1 files whose
// only transform is a slightly non-orthonormal sform: for those, nifti_geometry() applies ITK's
// own rules (qform/sform choice, RAS to LPS) here; image_geometry() then orthonormalizes a
// direction within 1e-3 (noted) or rejects it.
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <memory>

#include "dsreg/volume_io.hpp"
#include "image_geometry.hpp"
#include "itk_bridge.hpp"
#include "volume_io_internal.hpp"

namespace dsreg::volume_io_detail {

namespace {

std::string format_number(double value) {
    char text[32];
    std::snprintf(text, sizeof text, "%g", value);
    return text;
}

constexpr std::size_t kNifti1HeaderBytes = 348;
constexpr std::size_t kNifti2HeaderBytes = 540;
constexpr int kXformScannerAnat = 1;

/// The fields dsreg uses, widened to the NIfTI-2 types.
struct NiftiHeader {
    int version = 1;              ///< 0 (Analyze 7.5: no NIfTI magic), 1 or 2
    bool swapped = false;         ///< stored in the other byte order than the host's
    bool single_file = false;     ///< "n+1"/"n+2": the data follows the header in the same file
    std::array<std::int64_t, 8> dim{};
    int datatype = 0;
    std::array<double, 8> pixdim{};
    double vox_offset = 0;
    double scl_slope = 0, scl_inter = 0;
    int qform_code = 0, sform_code = 0;
    double quatern_b = 0, quatern_c = 0, quatern_d = 0;
    std::array<double, 3> qoffset{};
    std::array<std::array<double, 4>, 3> srow{};
};

/// Reads numbers from the raw header bytes in the file's byte order.
class HeaderBytes {
public:
    HeaderBytes(const std::uint8_t* bytes, bool swapped) : bytes_(bytes), swapped_(swapped) {}

    template <typename T>
    T get(std::size_t offset) const {
        std::uint8_t raw[sizeof(T)];
        std::memcpy(raw, bytes_ + offset, sizeof(T));
        if (swapped_)
            for (std::size_t i = 0; i < sizeof(T) / 2; ++i) std::swap(raw[i], raw[sizeof(T) - 1 - i]);
        T value;
        std::memcpy(&value, raw, sizeof(T));
        return value;
    }

private:
    const std::uint8_t* bytes_;
    bool swapped_;
};

std::int32_t byte_swapped(std::int32_t value) {
    std::uint32_t bits;
    std::memcpy(&bits, &value, 4);
    bits = (bits >> 24) | ((bits >> 8) & 0xff00u) | ((bits << 8) & 0xff0000u) | (bits << 24);
    std::memcpy(&value, &bits, 4);
    return value;
}

/// The header size its first four bytes announce, in either byte order; sets `swapped`.
std::size_t announced_header_size(const std::string& path, const std::uint8_t* bytes, std::size_t available, bool& swapped) {
    if (available < 4) fail(path, "not a NIfTI or Analyze file: only " + std::to_string(available) + " bytes");
    std::int32_t size;
    std::memcpy(&size, bytes, 4);
    swapped = false;
    if (size != 348 && size != 540) {
        size = byte_swapped(size);
        swapped = true;
    }
    if (size != 348 && size != 540)
        fail(path, "not a NIfTI or Analyze file: the header size field holds " + std::to_string(byte_swapped(size)) +
                       " (expected 348 for NIfTI-1 and Analyze, 540 for NIfTI-2)");
    return static_cast<std::size_t>(size);
}

NiftiHeader parse_nifti1(const std::uint8_t* bytes, bool swapped) {
    const HeaderBytes h(bytes, swapped);
    NiftiHeader header;
    header.swapped = swapped;
    const char* magic = reinterpret_cast<const char*>(bytes + 344);
    if (std::memcmp(magic, "n+1\0", 4) == 0)
        header.single_file = true;
    else if (std::memcmp(magic, "ni1\0", 4) != 0)
        header.version = 0;  // Analyze 7.5
    for (int i = 0; i < 8; ++i) header.dim[i] = h.get<std::int16_t>(40 + 2 * i);
    header.datatype = h.get<std::int16_t>(70);
    for (int i = 0; i < 8; ++i) header.pixdim[i] = h.get<float>(76 + 4 * i);
    header.vox_offset = h.get<float>(108);
    header.scl_slope = h.get<float>(112);
    header.scl_inter = h.get<float>(116);
    if (header.version == 1) {
        header.qform_code = h.get<std::int16_t>(252);
        header.sform_code = h.get<std::int16_t>(254);
        header.quatern_b = h.get<float>(256);
        header.quatern_c = h.get<float>(260);
        header.quatern_d = h.get<float>(264);
        for (int i = 0; i < 3; ++i) header.qoffset[i] = h.get<float>(268 + 4 * i);
        for (int r = 0; r < 3; ++r)
            for (int c = 0; c < 4; ++c) header.srow[r][c] = h.get<float>(280 + 16 * r + 4 * c);
    } else {
        header.scl_slope = 0;  // Analyze 7.5 has no scaling fields (ITK ignores these bytes)
        header.scl_inter = 0;
    }
    return header;
}

NiftiHeader parse_nifti2(const std::string& path, const std::uint8_t* bytes, bool swapped) {
    const HeaderBytes h(bytes, swapped);
    NiftiHeader header;
    header.version = 2;
    header.swapped = swapped;
    const char* magic = reinterpret_cast<const char*>(bytes + 4);
    if (std::memcmp(magic, "n+2\0", 4) == 0)
        header.single_file = true;
    else if (std::memcmp(magic, "ni2\0", 4) != 0)
        fail(path, "540-byte header without the NIfTI-2 magic 'n+2' or 'ni2'");
    header.datatype = h.get<std::int16_t>(12);
    for (int i = 0; i < 8; ++i) header.dim[i] = h.get<std::int64_t>(16 + 8 * i);
    for (int i = 0; i < 8; ++i) header.pixdim[i] = h.get<double>(104 + 8 * i);
    header.vox_offset = static_cast<double>(h.get<std::int64_t>(168));
    header.scl_slope = h.get<double>(176);
    header.scl_inter = h.get<double>(184);
    header.qform_code = h.get<std::int32_t>(344);
    header.sform_code = h.get<std::int32_t>(348);
    header.quatern_b = h.get<double>(352);
    header.quatern_c = h.get<double>(360);
    header.quatern_d = h.get<double>(368);
    for (int i = 0; i < 3; ++i) header.qoffset[i] = h.get<double>(376 + 8 * i);
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 4; ++c) header.srow[r][c] = h.get<double>(400 + 32 * r + 8 * c);
    return header;
}

/// dsreg's sample format of a NIfTI datatype code, or throws with what the code means.
SampleFormat nifti_sample(const std::string& path, const NiftiHeader& header, std::string& type_name) {
    // A swapped file stores big-endian values on a little-endian host (and conversely).
    const bool big_endian = native_sample(1, SampleKind::Unsigned).big_endian != header.swapped;
    const auto sample = [&](int bytes, SampleKind kind) { return SampleFormat{bytes, kind, big_endian}; };
    SampleFormat format;
    switch (header.datatype) {
    case 2: format = sample(1, SampleKind::Unsigned); break;
    case 256: format = sample(1, SampleKind::Signed); break;
    case 4: format = sample(2, SampleKind::Signed); break;
    case 512: format = sample(2, SampleKind::Unsigned); break;
    case 8: format = sample(4, SampleKind::Signed); break;
    case 768: format = sample(4, SampleKind::Unsigned); break;
    case 1024: format = sample(8, SampleKind::Signed); break;
    case 1280: format = sample(8, SampleKind::Unsigned); break;
    case 16: format = sample(4, SampleKind::Float); break;
    case 64: format = sample(8, SampleKind::Float); break;
    case 1: fail(path, "1-bit voxels (NIfTI datatype 1) are not supported");
    case 32:
    case 1792:
    case 2048: fail(path, "complex voxels (NIfTI datatype " + std::to_string(header.datatype) + "): dsreg needs a scalar image");
    case 128:
    case 2304:
        fail(path, "RGB voxels (NIfTI datatype " + std::to_string(header.datatype) + "): dsreg needs a scalar image");
    case 1536: fail(path, "128-bit float voxels (NIfTI datatype 1536) are not supported");
    default: fail(path, "unknown NIfTI datatype " + std::to_string(header.datatype));
    }
    type_name = sample_type_name(format);
    return format;
}

/// Dimensions of the image, with dsreg's messages for 4-D and vector images.
Index3 nifti_dims(const std::string& path, const NiftiHeader& header) {
    const std::int64_t rank = header.dim[0];
    if (rank < 1 || rank > 7)
        fail(path, "dim[0] = " + std::to_string(rank) + " is not a number of dimensions (1 to 7)");
    std::array<std::int64_t, 8> size{};
    for (int d = 1; d <= 7; ++d) {
        size[d] = d <= rank ? header.dim[d] : 1;
        if (size[d] <= 0) fail(path, "dim[" + std::to_string(d) + "] = " + std::to_string(size[d]) + " is not a positive size");
    }
    if (size[5] > 1)
        fail(path, "vector image with " + std::to_string(size[5]) +
                       " values per voxel (dim[5]): dsreg needs a scalar image (one value per voxel)");
    for (int d = 4; d <= 7; ++d)
        if (size[d] > 1)
            fail(path, std::to_string(rank) + "-D image (dim[" + std::to_string(d) + "] = " + std::to_string(size[d]) +
                           "): dsreg needs a single 3-D volume; extract one first (e.g. one time point)");
    return {size[1], size[2], size[3]};
}

// ----------------------------------------------------------------------------------------------
// Geometry by ITK's rules (for what ITK 5.2 cannot read)

struct Affine {
    Eigen::Matrix3d linear = Eigen::Matrix3d::Identity();
    Eigen::Vector3d offset = Eigen::Vector3d::Zero();
};

/// The qform (NIfTI-1 standard, method 2): rotation of the quaternion (b, c, d) with
/// a = √(1 − b² − c² − d²), columns scaled by the voxel sizes, the third by qfac = sign(pixdim[0]).
Affine qform_affine(const NiftiHeader& h) {
    double b = h.quatern_b, c = h.quatern_c, d = h.quatern_d;
    double a = 1.0 - (b * b + c * c + d * d);
    if (a < 1e-7) {  // (b, c, d) is already (nearly) a unit vector: a 180° rotation
        const double scale = 1.0 / std::sqrt(b * b + c * c + d * d);
        b *= scale, c *= scale, d *= scale;
        a = 0;
    } else {
        a = std::sqrt(a);
    }
    Eigen::Matrix3d r;
    r << a * a + b * b - c * c - d * d, 2 * (b * c - a * d), 2 * (b * d + a * c),  //
        2 * (b * c + a * d), a * a + c * c - b * b - d * d, 2 * (c * d - a * b),    //
        2 * (b * d - a * c), 2 * (c * d + a * b), a * a + d * d - c * c - b * b;
    const double qfac = h.pixdim[0] < 0 ? -1.0 : 1.0;
    const Eigen::Vector3d size(h.pixdim[1] > 0 ? h.pixdim[1] : 1.0, h.pixdim[2] > 0 ? h.pixdim[2] : 1.0,
                               (h.pixdim[3] > 0 ? h.pixdim[3] : 1.0) * qfac);
    Affine affine;
    affine.linear = r * size.asDiagonal();
    affine.offset = Eigen::Vector3d(h.qoffset[0], h.qoffset[1], h.qoffset[2]);
    return affine;
}

Affine sform_affine(const NiftiHeader& h) {
    Affine affine;
    for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 3; ++c) affine.linear(r, c) = h.srow[r][c];
        affine.offset[r] = h.srow[r][3];
    }
    return affine;
}

Eigen::Matrix3d unit_columns(const Eigen::Matrix3d& m) {
    Eigen::Matrix3d unit = m;
    for (int c = 0; c < 3; ++c)
        if (unit.col(c).norm() > 0) unit.col(c).normalize();
    return unit;
}

/// ITK's test of an sform it can use: finite, columns orthonormal once normalized (1e-4).
bool sform_orthonormal(const Affine& sform) {
    return sform.linear.allFinite() && sform.offset.allFinite() && orthonormality_error(unit_columns(sform.linear)) <= 1e-4;
}

/// Whether ITK takes its geometry from the sform rather than the qform (ITK 5.2's choice).
bool itk_prefers_sform(const NiftiHeader& h) {
    if (h.sform_code <= 0) return false;
    const Affine sform = sform_affine(h);
    if (!sform_orthonormal(sform)) return false;
    if (h.qform_code <= 0 || h.sform_code == kXformScannerAnat) return true;
    const Affine qform = qform_affine(h);
    return (sform.linear - qform.linear).cwiseAbs().maxCoeff() <= 1e-4 && (sform.offset - qform.offset).cwiseAbs().maxCoeff() <= 1e-4;
}

/// The header as ITK would describe it: spacing = pixdim, origin and direction from the chosen
/// transform, RAS turned to LPS; with neither transform, origin 0 and identity (as ITK does).
ImageHeader nifti_geometry(const NiftiHeader& h, const Index3& dims, const std::string& format) {
    ImageHeader header;
    header.format = format;
    header.sizes = {dims[0], dims[1], dims[2]};
    header.spacing = {h.pixdim[1], h.pixdim[2], h.pixdim[3]};
    header.origin = {0, 0, 0};
    header.direction = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    const bool use_sform = itk_prefers_sform(h) || (h.qform_code <= 0 && h.sform_code > 0);
    if (!use_sform && h.qform_code <= 0) return header;
    const Affine affine = use_sform ? sform_affine(h) : qform_affine(h);
    const Eigen::Vector3d ras_to_lps(-1, -1, 1);
    const Eigen::Vector3d origin = ras_to_lps.cwiseProduct(affine.offset);
    header.origin = {origin[0], origin[1], origin[2]};
    for (int c = 0; c < 3; ++c) {
        const Eigen::Vector3d column = ras_to_lps.cwiseProduct(affine.linear.col(c));
        const Eigen::Vector3d unit = column.norm() > 0 ? Eigen::Vector3d(column.normalized()) : column;
        header.direction[c] = {unit[0], unit[1], unit[2]};
    }
    return header;
}

// ----------------------------------------------------------------------------------------------
// Files

std::string lower_name(const std::string& path) {
    std::string name = std::filesystem::path(path).filename().string();
    for (char& c : name) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    return name;
}

bool ends_with(const std::string& text, const std::string& suffix) {
    return text.size() >= suffix.size() && text.compare(text.size() - suffix.size(), suffix.size(), suffix) == 0;
}

/// `path` with its last `strip` characters replaced by `replacement` (same case as the rest).
std::string replace_suffix(const std::string& path, std::size_t strip, const std::string& replacement) {
    return path.substr(0, path.size() - strip) + replacement;
}

/// The first existing file among `candidates`, or the first candidate.
std::string first_existing(const std::vector<std::string>& candidates) {
    for (const std::string& candidate : candidates) {
        std::error_code error;
        if (std::filesystem::is_regular_file(candidate, error)) return candidate;
    }
    return candidates.front();
}

/// The header file of an image given by its header or its data file (.img → .hdr).
std::string header_file(const std::string& path) {
    const std::string name = lower_name(path);
    if (ends_with(name, ".img.gz")) return first_existing({replace_suffix(path, 7, ".hdr.gz"), replace_suffix(path, 7, ".hdr")});
    if (ends_with(name, ".img")) return first_existing({replace_suffix(path, 4, ".hdr"), replace_suffix(path, 4, ".hdr.gz")});
    return path;
}

/// The data file of a header of a pair (.hdr → .img or .img.gz).
std::string data_file(const std::string& header_path) {
    const std::string name = lower_name(header_path);
    const std::size_t strip = ends_with(name, ".gz") ? 7 : 4;
    const std::string base = header_path.substr(0, header_path.size() - strip);
    const bool upper = !header_path.empty() && std::isupper(static_cast<unsigned char>(header_path[header_path.size() - strip + 1]));
    return first_existing({base + (upper ? ".IMG" : ".img"), base + (upper ? ".IMG.GZ" : ".img.gz")});
}

bool is_gzip_name(const std::string& path) { return ends_with(lower_name(path), ".gz"); }

/// Reads the header (348 or 540 bytes) from the start of the (inflated) file.
template <typename Source>
std::vector<std::uint8_t> read_header_bytes(const std::string& path, Source&& read) {
    std::vector<std::uint8_t> bytes(kNifti2HeaderBytes);
    const std::size_t got = read(bytes.data(), 4);
    bool swapped = false;
    const std::size_t size = announced_header_size(path, bytes.data(), got, swapped);
    const std::size_t rest = read(bytes.data() + 4, size - 4);
    if (rest != size - 4)
        fail(path, "truncated header: " + std::to_string(4 + rest) + " of the " + std::to_string(size) + " header bytes");
    bytes.resize(size);
    return bytes;
}

struct ParsedHeader {
    NiftiHeader header;
    Index3 dims{0, 0, 0};
    SampleFormat sample;
    std::string value_type;
    std::uint64_t data_offset = 0;  ///< where the voxels start in the data file (inflated, for .gz)
};

/// The transform fields must be plausible finite numbers, and the sform's columns non-zero: ITK
/// 5.2 aborts the whole process (vnl's assert_finite) on a NaN in the sform, found by fuzzing.
void check_transform_fields(const std::string& path, const NiftiHeader& h) {
    constexpr double kLargest = 1e10;  // millimetres, or unitless cosines: far beyond any scanner
    const auto check = [&](double value, const std::string& name) {
        if (!std::isfinite(value) || std::abs(value) > kLargest)
            fail(path, name + " holds " + format_number(value) + ", not a plausible finite number");
    };
    for (int i = 0; i < 4; ++i) check(h.pixdim[i], "pixdim[" + std::to_string(i) + "]");
    check(h.quatern_b, "quatern_b");
    check(h.quatern_c, "quatern_c");
    check(h.quatern_d, "quatern_d");
    for (int i = 0; i < 3; ++i) check(h.qoffset[i], std::string("qoffset_") + "xyz"[i]);
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 4; ++c) check(h.srow[r][c], std::string("srow_") + "xyz"[r] + "[" + std::to_string(c) + "]");
    if (h.sform_code > 0)
        for (int c = 0; c < 3; ++c)
            if (h.srow[0][c] == 0 && h.srow[1][c] == 0 && h.srow[2][c] == 0)
                fail(path, "the sform maps axis " + std::to_string(c + 1) + " to a zero vector");
}

ParsedHeader parse_header(const std::string& path, const std::vector<std::uint8_t>& bytes) {
    ParsedHeader parsed;
    bool swapped = false;
    const std::size_t size = announced_header_size(path, bytes.data(), bytes.size(), swapped);
    parsed.header = size == kNifti1HeaderBytes ? parse_nifti1(bytes.data(), swapped) : parse_nifti2(path, bytes.data(), swapped);
    parsed.dims = nifti_dims(path, parsed.header);
    check_transform_fields(path, parsed.header);
    parsed.sample = nifti_sample(path, parsed.header, parsed.value_type);
    const double offset = parsed.header.vox_offset;
    if (!std::isfinite(offset) || offset < 0 || offset != std::floor(offset) || offset > 9e15)
        fail(path, "vox_offset " + std::to_string(offset) + " is not a byte offset");
    parsed.data_offset = static_cast<std::uint64_t>(offset);
    if (parsed.header.single_file && parsed.data_offset < size)
        fail(path, "vox_offset " + std::to_string(parsed.data_offset) + " points inside the " + std::to_string(size) +
                       "-byte header");
    return parsed;
}

/// ITK's rescaling: v·slope + intercept when the slope is non-zero and not the identity.
bool must_rescale(const NiftiHeader& h) {
    constexpr double epsilon = 2.220446049250313e-16;
    return std::isfinite(h.scl_slope) && std::isfinite(h.scl_inter) && std::abs(h.scl_slope) > epsilon &&
           (std::abs(h.scl_slope - 1.0) > epsilon || std::abs(h.scl_inter) > epsilon);
}

std::string format_label(const NiftiHeader& h) {
    return h.version == 0 ? "Analyze 7.5" : h.version == 1 ? "NIfTI-1" : "NIfTI-2";
}

/// Geometry: ITK's reading of NIfTI-1 and Analyze headers, the same rules applied here where
/// ITK 5.2 cannot read the file (NIfTI-2; an sform ITK refuses as non-orthonormal).
VoxelGrid nifti_grid(const std::string& path, const ParsedHeader& parsed, VolumeFileInfo& info) {
    const NiftiHeader& h = parsed.header;
    const bool itk_refuses_sform = h.version == 1 && h.qform_code <= 0 && h.sform_code > 0 && !sform_orthonormal(sform_affine(h));
    ImageHeader geometry;
    if (h.version == 2 || itk_refuses_sform) {
        geometry = nifti_geometry(h, parsed.dims, format_label(h));
        if (itk_refuses_sform)
            info.notes.push_back("the sform is not orthonormal and there is no qform (ITK 5.2 refuses such files); the "
                                 "sform's nearest orthonormal directions are used");
    } else {
        geometry = read_itk_header(path, ItkFormat::Nifti);
        const Index3 itk_dims = image_dims(path, geometry);
        if (itk_dims != parsed.dims)
            fail(path, "ITK reads the dimensions as " + format_dims(itk_dims) + ", the header says " + format_dims(parsed.dims));
    }
    return image_geometry(path, geometry, info);
}

/// Decodes the voxels at `data_offset` of the data file: inflating (after the
/// `already_inflated` bytes the header took, for a .nii.gz) or seeking.
void decode_payload(InputFile& file, const ParsedHeader& parsed, std::uint64_t already_inflated, InflateStream* inflate,
                    const std::string& description, VoxelDestination& destination) {
    const std::string& path = file.path();
    const auto voxels = static_cast<std::int64_t>(destination.size());
    const std::uint64_t bytes = payload_bytes(path, voxels, parsed.sample.bytes);
    SampleWriter sink = destination.writer(path, parsed.sample);
    if (must_rescale(parsed.header)) sink.rescale(parsed.header.scl_slope, parsed.header.scl_inter);
    if (inflate != nullptr) {
        inflate->skip(parsed.data_offset - already_inflated, description);
        inflate->decode(bytes, sink, description);
    } else {
        file.seek(parsed.data_offset);
        decode_stored_prefix(file, sink);
    }
}

}  // namespace

void read_nifti_voxels(const std::string& path, const VolumeLimits& limits, VoxelDestination& destination) {
    const std::string header_path = header_file(path);
    InputFile header_input(header_path);
    const bool header_gzip = is_gzip_name(header_path);
    std::unique_ptr<InflateStream> header_stream;
    if (header_gzip) header_stream = std::make_unique<InflateStream>(header_input, CompressedContainer::Gzip);
    const std::vector<std::uint8_t> bytes = read_header_bytes(header_path, [&](std::uint8_t* out, std::size_t count) {
        return header_gzip ? header_stream->read(out, count, "the header") : header_input.read(out, count);
    });
    const ParsedHeader parsed = parse_header(header_path, bytes);
    const std::int64_t voxels = checked_voxel_count(header_path, parsed.dims, limits);
    const std::uint64_t payload = payload_bytes(header_path, voxels, parsed.sample.bytes);
    const std::string description = "header says " + describe_payload(parsed.dims, voxels, parsed.sample.bytes) +
                                    " at offset " + std::to_string(parsed.data_offset);

    // The voxels are in the same file after the header, or in the .img of the pair.
    const bool same_file = parsed.header.single_file;
    const std::string data_path = same_file ? header_path : data_file(header_path);
    std::unique_ptr<InputFile> data_input;
    if (!same_file) {
        if (!std::filesystem::exists(data_path))
            fail(header_path, "the data file " + data_path + " of this header does not exist");
        data_input = std::make_unique<InputFile>(data_path);
    }
    InputFile& data = same_file ? header_input : *data_input;
    const bool data_gzip = is_gzip_name(data_path);
    const std::uint64_t needed = parsed.data_offset + payload;
    if (data_gzip) {
        if (needed > max_inflated_size(data.size()))
            fail(data_path, "truncated or lying header: " + description + ", but the " + std::to_string(data.size()) +
                                "-byte gzip file can inflate to at most " + std::to_string(max_inflated_size(data.size())) +
                                " bytes");
    } else if (data.size() < needed) {
        fail(data_path, "truncated payload: " + description + ", but the file holds " + std::to_string(data.size()) + " bytes");
    }

    VolumeFileInfo info;
    info.format = format_label(parsed.header);
    info.value_type = parsed.value_type;
    info.world_geometry = true;
    const VoxelGrid geometry = nifti_grid(header_path, parsed, info);
    const bool wanted = destination.allocate(path, parsed.dims);
    destination.set_geometry(geometry);
    destination.info() = info;
    if (!wanted) return;

    if (same_file) return decode_payload(data, parsed, bytes.size(), header_stream.get(), description, destination);
    std::unique_ptr<InflateStream> data_stream;
    if (data_gzip) data_stream = std::make_unique<InflateStream>(data, CompressedContainer::Gzip);
    decode_payload(data, parsed, parsed.data_offset, data_stream.get(), description, destination);
}

}  // namespace dsreg::volume_io_detail
