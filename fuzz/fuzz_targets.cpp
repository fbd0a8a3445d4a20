// dsreg — fuzz targets (see fuzz_targets.hpp).
#include "fuzz_targets.hpp"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "dsreg/blocks.hpp"
#include "dsreg/error.hpp"
#include "dsreg/implicit_shape.hpp"
#include "dsreg/label_surface.hpp"
#include "dsreg/mesh_io.hpp"
#include "dsreg/normals_file.hpp"
#include "dsreg/volume_io.hpp"

namespace dsreg::fuzz {

namespace {

/// Voxels above which an accepted header's payload is not decoded (read_volume_file).
constexpr std::int64_t kLargestReadVoxels = std::int64_t(1) << 21;

/// A broken promise: print it and abort, which libFuzzer and the replay tool report as a crash.
[[noreturn]] void violated(const char* target, const std::string& what) {
    std::fprintf(stderr, "dsreg fuzz target %s: broken promise: %s\n", target, what.c_str());
    std::abort();
}

#define FUZZ_CHECK(target, condition, what) \
    do {                                    \
        if (!(condition)) violated(target, what); \
    } while (false)

/// A private scratch folder for the temporary files of this process, removed at exit.
class Scratch {
public:
    Scratch() {
        namespace fs = std::filesystem;
        std::error_code error;
        fs::path base = fs::temp_directory_path(error);
        if (error) base = "/tmp";
        folder_ = base / ("dsreg-fuzz-" + std::to_string(::getpid()));
        fs::create_directories(folder_);
    }
    ~Scratch() {
        std::error_code error;
        std::filesystem::remove_all(folder_, error);
    }
    /// Writes `data` to a file named `name` in the folder; returns its path.
    std::string write(const std::string& name, const std::uint8_t* data, std::size_t size) const {
        const std::string path = (folder_ / name).string();
        std::ofstream out(path, std::ios::binary | std::ios::trunc);
        out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
        out.close();
        if (!out) {
            std::fprintf(stderr, "dsreg fuzz: cannot write the scratch file %s\n", path.c_str());
            std::abort();
        }
        return path;
    }
    std::string path(const std::string& name) const { return (folder_ / name).string(); }

private:
    std::filesystem::path folder_;
};

const Scratch& scratch() {
    static const Scratch instance;
    return instance;
}

// ----------------------------------------------------------------------------------------------
// Volumes

/// Checks the closed-manifold promise of the digital surface: every face edge is glued, in the
/// surface of each label of the face (its inner one; its outer one unless the background), to an
/// edge of an existing face of that label that is glued back, and every corner is a valid vertex.
void check_surface(const char* target, const DigitalSurface& s) {
    const std::int64_t m = s.face_count(), n = s.vertex_count();
    FUZZ_CHECK(target, m > 0 && s.quads.cols() == 4 && s.adjacent_face.rows() == m && s.adjacent_face_outer.rows() == m,
               "surface arrays have the wrong size");
    FUZZ_CHECK(target, static_cast<std::int64_t>(s.surfels.size()) == m && std::int64_t(s.face_labels.size()) == m,
               "one surfel and one label pair per face");
    const auto adjacent = [&](int side) -> const FaceMatrix& { return side == 0 ? s.adjacent_face : s.adjacent_face_outer; };
    for (std::int64_t f = 0; f < m; ++f) {
        const FaceLabels labels = s.face_labels[std::size_t(f)];
        FUZZ_CHECK(target, labels.inner > labels.outer, "a face's inner label is not the higher one");
        for (int side = 0; side < (labels.outer != 0 ? 2 : 1); ++side) {
            const std::uint32_t label = side == 0 ? labels.inner : labels.outer;
            for (int e = 0; e < 4; ++e) {
                const std::int64_t v = s.quads(f, e);
                FUZZ_CHECK(target, v >= 0 && v < n, "quad corner is not a vertex");
                const std::int64_t g = adjacent(side)(f, e);
                FUZZ_CHECK(target, g >= 0 && g < m, "adjacent face out of range");
                const FaceLabels other = s.face_labels[std::size_t(g)];
                FUZZ_CHECK(target, other.inner == label || other.outer == label, "a face is glued to a face of another label");
                const int g_side = other.inner == label ? 0 : 1;
                bool glued_back = false;
                for (int b = 0; b < 4; ++b) glued_back = glued_back || adjacent(g_side)(g, b) == f;
                FUZZ_CHECK(target, glued_back, "face adjacency is not symmetric");
            }
        }
    }
    FUZZ_CHECK(target, s.component_count >= 1 && s.component_count <= m, "component count out of range");
}

/// The label-map reader on a file the values reader accepted: the same header, every value a
/// label. It may refuse only values that are not integers (or too many labels); what it returns
/// names each voxel's value, and a small map gives a label complex whose every label is closed.
void check_label_map(const char* target, const std::string& path, const RawVolumeLayout* layout, const ScalarVolume& values) {
    LabelVolume labels;
    try {
        labels = read_label_volume(path, layout);
    } catch (const Error& error) {
        const std::string message = error.what();
        FUZZ_CHECK(target, message.rfind(path + ": ", 0) == 0, "message does not start with the path: " + message);
        const bool integer_format = layout == nullptr || (layout->type != RawVoxelType::Float32 && layout->type != RawVoxelType::Float64);
        FUZZ_CHECK(target, !integer_format || message.find("is not an integer") != std::string::npos,
                   "the label reader refused integer values: " + message);
        return;
    }
    FUZZ_CHECK(target, labels.grid.dims == values.grid.dims, "label and values readers disagree on the dimensions");
    FUZZ_CHECK(target, labels.labels.size() == values.values.size(), "one label per voxel");
    FUZZ_CHECK(target, !labels.values.empty() && labels.values[0] == 0, "label 0 is not the background");
    for (std::size_t l = 2; l < labels.values.size(); ++l)
        FUZZ_CHECK(target, labels.values[l - 1] < labels.values[l], "label values are not increasing");
    for (std::size_t i = 0; i < labels.labels.size(); ++i) {
        FUZZ_CHECK(target, labels.labels[i] < labels.values.size(), "label index beyond the table");
        FUZZ_CHECK(target, static_cast<float>(labels.values[labels.labels[i]]) == values.values[i],
                   "label value differs from the value at voxel #" + std::to_string(i));
    }
    const bool labelled = std::any_of(labels.labels.begin(), labels.labels.end(), [](std::uint32_t l) { return l != 0; });
    if (labels.grid.voxel_count() > 4096 || !labelled) return;
    const DigitalSurface complex = extract_digital_surface(labels, labels.values.size() % 2 ? Connectivity::Six : Connectivity::TwentySix);
    check_surface(target, complex);
    for (const LabelMesh& mesh : label_meshes(complex)) {
        for (const std::int64_t c : mesh.euler_characteristics())
            FUZZ_CHECK(target, c <= 2 && c % 2 == 0, "a label's surface component is not a closed orientable surface");
        FUZZ_CHECK(target, mesh.component_count >= 1, "a label without components");
    }
    const VertexLinks links = fairness_links(complex);
    FUZZ_CHECK(target, std::int64_t(links.offsets.size()) == complex.vertex_count() + 1, "links of the wrong size");
}

/// Whether `part` holds exactly the voxels of `box` of `volume` (the fuzz build links the readers
/// only, not src/blocks' crop_volume).
bool equals_box_of(const BinaryVolume& part, const BinaryVolume& volume, const VoxelBox& box) {
    const Index3 size{box.hi[0] - box.lo[0], box.hi[1] - box.lo[1], box.hi[2] - box.lo[2]};
    if (part.grid.dims != size || part.mask.size() != std::size_t(size[0] * size[1] * size[2])) return false;
    for (std::int64_t k = 0; k < size[2]; ++k)
        for (std::int64_t j = 0; j < size[1]; ++j)
            for (std::int64_t i = 0; i < size[0]; ++i)
                if (part.inside(i, j, k) != volume.inside(box.lo[0] + i, box.lo[1] + j, box.lo[2] + k)) return false;
    return true;
}

/// Whether block-wise runs must refuse a box of this file: ITK reads TIFF and DICOM files whole
/// (other formats only some files: check_box_read accepts their refusal too).
bool read_whole_only(const std::string& path) {
    const std::string extension = std::filesystem::path(path).extension().string();
    return extension == ".tif" || extension == ".dcm";
}

/// A block-wise run's reads of an accepted file: the header probe gives its grid, and a box (the
/// upper corner, half the grid along each axis) the crop of the whole mask, placed at its corner,
/// or, for the files ITK reads whole, a refusal naming the file.
void check_box_read(const char* target, const std::string& path, const RawVolumeLayout* layout, const BinaryVolume& volume) {
    const VoxelGrid& g = volume.grid;
    const VoxelGrid header = read_volume_grid(path, layout);
    FUZZ_CHECK(target, header.dims == g.dims && header.spacing == g.spacing && header.origin == g.origin &&
                           header.direction == g.direction,
               "read_volume_grid disagrees with read_volume's grid");
    const VoxelBox box{{g.dims[0] / 2, g.dims[1] / 2, g.dims[2] / 2}, g.dims};
    BinaryVolume part;
    try {
        part = read_volume_box(path, box, ValueRange{}, layout);
    } catch (const Error& error) {
        // A box of a file ITK reads whole (TIFF, DICOM; also a VTK image in ASCII: found by
        // fuzzing) is refused, naming the file.
        const std::string message = error.what();
        FUZZ_CHECK(target, message.rfind(path + ": block-wise runs", 0) == 0, "unexpected box read refusal: " + message);
        return;
    }
    FUZZ_CHECK(target, !read_whole_only(path), "a box of a file ITK reads whole was read");
    FUZZ_CHECK(target, equals_box_of(part, volume, box),
               "read_volume_box differs from the crop of read_volume");
    FUZZ_CHECK(target, part.grid.origin == g.voxel_center(box.lo[0], box.lo[1], box.lo[2]), "the box is not placed at its corner");
}

/// A box read of a refused file refuses it too, or reads a box without the broken part; either
/// way no crash, and any message starts with the path.
void check_box_read_of_refused(const char* target, const std::string& path, const RawVolumeLayout* layout) {
    try {
        read_volume_box(path, VoxelBox{{0, 0, 0}, {1, 1, 1}}, ValueRange{}, layout);
    } catch (const Error& error) {
        const std::string message = error.what();
        FUZZ_CHECK(target, message.rfind(path + ": ", 0) == 0, "box read message does not start with the path: " + message);
    }
}

/// Reads the file both ways (mask and values), checks they agree, and extracts the digital
/// surface of small non-empty volumes; then as a label map, and by boxes as block-wise runs do.
Outcome read_volume_file(const char* target, const std::string& path, const RawVolumeLayout* layout) {
    Outcome outcome;
    // A compressed payload within the 16 KiB inputs can hold 16 Mi voxels: a 16 KB zlib stream
    // of zeros in a MetaImage took 8 s under the sanitizers (25 s on a loaded machine, a
    // time-out). Such grids, valid as far as the header probe sees, get its checks only.
    try {
        if (read_volume_grid(path, layout).voxel_count() > kLargestReadVoxels) return outcome;
    } catch (const Error&) {
        // refused by the probe: read_volume must refuse it too (below)
    }
    BinaryVolume volume;
    try {
        volume = read_volume(path, ValueRange{}, layout);
    } catch (const Error& error) {
        outcome.message = error.what();
        FUZZ_CHECK(target, outcome.message.rfind(path + ": ", 0) == 0, "message does not start with the path: " + outcome.message);
        // The values reader parses the same header with the same checks: it must fail too.
        bool values_failed = false;
        try {
            read_volume_values(path, layout);
        } catch (const Error&) {
            values_failed = true;
        }
        FUZZ_CHECK(target, values_failed, "read_volume failed but read_volume_values succeeded: " + outcome.message);
        check_box_read_of_refused(target, path, layout);
        return outcome;
    }
    outcome.accepted = true;
    const VoxelGrid& g = volume.grid;
    FUZZ_CHECK(target, g.dims[0] > 0 && g.dims[1] > 0 && g.dims[2] > 0, "accepted non-positive dimensions");
    FUZZ_CHECK(target, g.voxel_count() <= VolumeLimits{}.max_voxels, "accepted more voxels than the limit");
    FUZZ_CHECK(target, static_cast<std::int64_t>(volume.mask.size()) == g.voxel_count(), "mask size != voxel count");
    const ScalarVolume values = read_volume_values(path, layout);
    FUZZ_CHECK(target, values.grid.dims == g.dims, "values and mask readers disagree on the dimensions");
    FUZZ_CHECK(target, values.values.size() == volume.mask.size(), "values size != mask size");
    for (std::size_t i = 0; i < volume.mask.size(); ++i) {
        FUZZ_CHECK(target, volume.mask[i] <= 1, "mask value other than 0/1");
        // Integer formats: value > 0 survives the rounding to float, so both readers agree.
        // Float64 values below float's smallest positive value round to 0 in the values.
        if (layout == nullptr || layout->type != RawVoxelType::Float64)
            FUZZ_CHECK(target, (volume.mask[i] != 0) == (values.values[i] > 0.0f) || (volume.mask[i] != 0 && values.values[i] == 0.0f),
                       "mask and values disagree at voxel #" + std::to_string(i));
    }
    if (g.voxel_count() <= 4096 && volume.object_voxel_count() > 0) {
        const Connectivity c = volume.object_voxel_count() % 2 ? Connectivity::Six : Connectivity::TwentySix;
        check_surface(target, extract_digital_surface(volume, c));
    }
    check_label_map(target, path, layout, values);
    check_box_read(target, path, layout, volume);
    return outcome;
}

Outcome volume_target(const char* target, const char* extension, const std::uint8_t* data, std::size_t size) {
    return read_volume_file(target, scratch().write(std::string("input.") + extension, data, size), nullptr);
}

Outcome fuzz_vol(const std::uint8_t* data, std::size_t size) { return volume_target("vol", "vol", data, size); }

/// NIfTI: a .nii.gz when the input starts with the gzip magic, else a .nii.
Outcome fuzz_nifti(const std::uint8_t* data, std::size_t size) {
    const bool gzip = size >= 2 && data[0] == 0x1f && data[1] == 0x8b;
    return volume_target("nifti", gzip ? "nii.gz" : "nii", data, size);
}
Outcome fuzz_nrrd(const std::uint8_t* data, std::size_t size) { return volume_target("nrrd", "nrrd", data, size); }
Outcome fuzz_metaimage(const std::uint8_t* data, std::size_t size) { return volume_target("metaimage", "mha", data, size); }
Outcome fuzz_npy(const std::uint8_t* data, std::size_t size) { return volume_target("npy", "npy", data, size); }
Outcome fuzz_longvol(const std::uint8_t* data, std::size_t size) { return volume_target("longvol", "longvol", data, size); }
Outcome fuzz_pgm3d(const std::uint8_t* data, std::size_t size) { return volume_target("pgm3d", "pgm3d", data, size); }
Outcome fuzz_tiff(const std::uint8_t* data, std::size_t size) { return volume_target("tiff", "tif", data, size); }
Outcome fuzz_hdf5(const std::uint8_t* data, std::size_t size) { return volume_target("hdf5", "h5", data, size); }
Outcome fuzz_dicom(const std::uint8_t* data, std::size_t size) { return volume_target("dicom", "dcm", data, size); }
Outcome fuzz_vtkimage(const std::uint8_t* data, std::size_t size) { return volume_target("vtkimage", "vtk", data, size); }

constexpr std::size_t kRawPrefix = 15;

std::int32_t read_int32(const std::uint8_t* p) {
    std::uint32_t bits = 0;
    for (int i = 3; i >= 0; --i) bits = (bits << 8) | p[i];
    std::int32_t value;
    std::memcpy(&value, &bits, sizeof value);
    return value;
}

Outcome fuzz_raw(const std::uint8_t* data, std::size_t size) {
    if (size < kRawPrefix) return Outcome{false, "input shorter than the raw layout prefix"};
    RawVolumeLayout layout;
    layout.dims = {read_int32(data), read_int32(data + 4), read_int32(data + 8)};
    layout.type = static_cast<RawVoxelType>(data[12] % 10);
    layout.big_endian = (data[13] & 1) != 0;
    layout.header_bytes = data[14];
    return read_volume_file("raw", scratch().write("input.raw", data + kRawPrefix, size - kRawPrefix), &layout);
}

// ----------------------------------------------------------------------------------------------
// Polynomials

bool same_polynomial(const Polynomial& a, const Polynomial& b) {
    const auto& x = a.monomials();
    const auto& y = b.monomials();
    if (x.size() != y.size()) return false;
    for (std::size_t i = 0; i < x.size(); ++i)
        if (x[i].coefficient != y[i].coefficient || x[i].ex != y[i].ex || x[i].ey != y[i].ey || x[i].ez != y[i].ez)
            return false;
    return true;
}

Outcome fuzz_polynomial(const std::uint8_t* data, std::size_t size) {
    const std::string text(reinterpret_cast<const char*>(data), size);
    Outcome outcome;
    Polynomial p;
    try {
        p = Polynomial::parse(text);
    } catch (const Error& error) {
        outcome.message = error.what();
        return outcome;
    }
    outcome.accepted = true;
    FUZZ_CHECK("polynomial", p.degree() >= 0 && p.degree() <= Polynomial::max_degree, "degree out of range");
    for (const auto& m : p.monomials()) {
        FUZZ_CHECK("polynomial", std::isfinite(m.coefficient) && m.coefficient != 0.0, "non-finite or zero coefficient");
        FUZZ_CHECK("polynomial", m.ex >= 0 && m.ey >= 0 && m.ez >= 0 && m.ex + m.ey + m.ez <= p.degree(), "bad exponents");
    }
    // to_string() promises a string that parses back to the same polynomial, bit for bit.
    const std::string written = p.to_string();
    Polynomial again;
    try {
        again = Polynomial::parse(written);
    } catch (const Error& error) {
        violated("polynomial", "to_string() gave '" + written + "', which does not parse: " + error.what());
    }
    FUZZ_CHECK("polynomial", same_polynomial(p, again), "to_string() round trip changed the polynomial: '" + written + "'");
    // Small polynomials: digitize on a small grid (exercises evaluation; must not throw).
    if (p.monomials().size() <= 64) {
        ImplicitShape shape = make_shape(written, 2.0);
        const BinaryVolume volume = digitize(shape, 0.5);
        FUZZ_CHECK("polynomial", static_cast<std::int64_t>(volume.mask.size()) == volume.grid.voxel_count(),
                   "digitized mask size");
    }
    return outcome;
}

// ----------------------------------------------------------------------------------------------
// Normals files

Outcome fuzz_normals(const std::uint8_t* data, std::size_t size) {
    static const DigitalSurface surface = normals_target_surface();
    std::istringstream in(std::string(reinterpret_cast<const char*>(data), size));
    Outcome outcome;
    PointMatrix normals;
    try {
        normals = read_normals(in, "fuzz.normals", surface);
    } catch (const Error& error) {
        outcome.message = error.what();
        FUZZ_CHECK("normals", outcome.message.rfind("fuzz.normals", 0) == 0, "message does not name the file: " + outcome.message);
        return outcome;
    }
    outcome.accepted = true;
    FUZZ_CHECK("normals", normals.rows() == surface.face_count(), "one normal per surfel");
    for (std::int64_t f = 0; f < normals.rows(); ++f) {
        const double length = normals.row(f).norm();
        FUZZ_CHECK("normals", std::isfinite(length) && std::abs(length - 1.0) < 1e-9,
                   "normal of face " + std::to_string(f) + " is not a unit vector");
    }
    return outcome;
}

// ----------------------------------------------------------------------------------------------
// Meshes

void check_mesh(const char* target, const PolygonMesh& mesh) {
    const std::int64_t n = mesh.vertices.rows();
    FUZZ_CHECK(target, mesh.faces.rows() == 0 || mesh.faces.cols() == 3 || mesh.faces.cols() == 4, "faces are not triangles or quads");
    for (std::int64_t i = 0; i < mesh.faces.size(); ++i)
        FUZZ_CHECK(target, mesh.faces.data()[i] >= 0 && mesh.faces.data()[i] < n, "face index out of range");
    FUZZ_CHECK(target, mesh.vertices.allFinite(), "non-finite vertex coordinate");
    FUZZ_CHECK(target, mesh.face_normals.rows() == 0 || mesh.face_normals.rows() == mesh.faces.rows(), "face normal count");
    FUZZ_CHECK(target, mesh.coordinate_system.empty() || mesh.coordinate_system == "LPS" || mesh.coordinate_system == "RAS",
               "coordinate system other than LPS, RAS or none");
    for (const auto& [name, values] : mesh.vertex_scalars)
        FUZZ_CHECK(target, values.size() == n, "vertex scalar '" + name + "' has the wrong size");
    for (const auto& [name, values] : mesh.face_integers)
        FUZZ_CHECK(target, values.size() == mesh.faces.rows(), "face integer '" + name + "' has the wrong size");
}

Outcome mesh_target(const char* target, const std::uint8_t* data, std::size_t size) {
    const std::string extension = target;
    const std::string path = scratch().write("input." + extension, data, size);
    Outcome outcome;
    PolygonMesh mesh;
    try {
        mesh = read_mesh(path);
    } catch (const Error& error) {
        outcome.message = error.what();
        FUZZ_CHECK(target, outcome.message.find(path) != std::string::npos, "message does not name the file: " + outcome.message);
        return outcome;
    }
    outcome.accepted = true;
    check_mesh(target, mesh);
    // Whatever the reader accepts, the writer must write and the reader read back. Text formats
    // and PLY (doubles) keep positions and faces exactly; STL stores floats and merges positions.
    const std::string copy = scratch().path("copy." + extension);
    try {
        write_mesh(copy, mesh);
    } catch (const Error& error) {
        violated(target, std::string("the writer rejects what the reader accepted: ") + error.what());
    }
    PolygonMesh again;
    try {
        again = read_mesh(copy);
    } catch (const Error& error) {
        violated(target, std::string("the reader rejects what the writer wrote: ") + error.what());
    }
    check_mesh(target, again);
    if (extension != "stl") {
        FUZZ_CHECK(target, again.vertices == mesh.vertices, "round trip changed the vertices");
        FUZZ_CHECK(target, again.faces == mesh.faces, "round trip changed the faces");
    }
    FUZZ_CHECK(target, again.coordinate_system == mesh.coordinate_system, "round trip changed the coordinate system");
    // (.vtp names are taken verbatim from the XML attribute and escaped when written, so only
    // their values are compared.)
    if (extension == "ply" || extension == "vtk")
        FUZZ_CHECK(target, again.face_integers == mesh.face_integers, "round trip changed the face integers");
    if (extension == "vtp") {
        FUZZ_CHECK(target, again.face_integers.size() == mesh.face_integers.size(), "round trip changed the face integers");
        for (std::size_t i = 0; i < mesh.face_integers.size(); ++i)
            FUZZ_CHECK(target, again.face_integers[i].second == mesh.face_integers[i].second, "round trip changed the face integers");
    }
    return outcome;
}

Outcome fuzz_obj(const std::uint8_t* data, std::size_t size) { return mesh_target("obj", data, size); }
Outcome fuzz_off(const std::uint8_t* data, std::size_t size) { return mesh_target("off", data, size); }
Outcome fuzz_ply(const std::uint8_t* data, std::size_t size) { return mesh_target("ply", data, size); }
Outcome fuzz_stl(const std::uint8_t* data, std::size_t size) { return mesh_target("stl", data, size); }
Outcome fuzz_vtk(const std::uint8_t* data, std::size_t size) { return mesh_target("vtk", data, size); }
Outcome fuzz_vtp(const std::uint8_t* data, std::size_t size) { return mesh_target("vtp", data, size); }

}  // namespace

DigitalSurface normals_target_surface() {
    BinaryVolume volume;
    volume.grid.dims = {3, 3, 2};
    volume.mask.assign(18, 0);
    for (const Index3 v : {Index3{0, 0, 0}, Index3{1, 0, 0}, Index3{2, 1, 0}, Index3{0, 1, 1}})
        volume.mask[static_cast<std::size_t>(volume.grid.linear_index(v[0], v[1], v[2]))] = 1;
    return extract_digital_surface(volume, Connectivity::TwentySix);
}

std::vector<std::uint8_t> raw_input(std::int32_t x, std::int32_t y, std::int32_t z, int type, bool big_endian,
                                    int header_bytes, const std::vector<std::uint8_t>& file_contents) {
    std::vector<std::uint8_t> input;
    for (const std::int32_t d : {x, y, z}) {
        std::uint32_t bits;
        std::memcpy(&bits, &d, sizeof bits);
        for (int i = 0; i < 4; ++i) input.push_back(static_cast<std::uint8_t>(bits >> (8 * i)));
    }
    input.push_back(static_cast<std::uint8_t>(type));
    input.push_back(big_endian ? 1 : 0);
    input.push_back(static_cast<std::uint8_t>(header_bytes));
    input.insert(input.end(), file_contents.begin(), file_contents.end());
    return input;
}

const std::vector<Target>& targets() {
    static const std::vector<Target> all = {
        {"vol", "DGtal .vol, versions 2 (raw) and 3 (zlib)", fuzz_vol},
        {"longvol", "DGtal .longvol, versions 2 and 3", fuzz_longvol},
        {"pgm3d", "PGM3D, P2-3D (ASCII) and P5-3D (binary)", fuzz_pgm3d},
        {"nifti", "NIfTI-1/2 and Analyze header and payload (.nii, or .nii.gz for gzip input)", fuzz_nifti},
        {"nrrd", "NRRD header and attached payload (raw, gzip)", fuzz_nrrd},
        {"metaimage", "MetaImage .mha header and payload (raw, zlib)", fuzz_metaimage},
        {"npy", "NumPy .npy header and payload", fuzz_npy},
        {"tiff", "TIFF stack (.tif): dsreg's page checks, ITK's TIFF reader", fuzz_tiff},
        {"hdf5", "HDF5 image as ITK writes it (.h5), ITK's HDF5 reader", fuzz_hdf5},
        {"dicom", "one DICOM file (.dcm): dsreg's meta information checks, ITK's GDCM reader", fuzz_dicom},
        {"vtkimage", "VTK legacy STRUCTURED_POINTS image (.vtk read as a volume), ITK's reader", fuzz_vtkimage},
        {"raw", "headerless .raw, layout from a 15-byte prefix", fuzz_raw},
        {"polynomial", "polynomial parser (--shape)", fuzz_polynomial},
        {"normals", "normals file (--normals-file)", fuzz_normals},
        {"obj", "OBJ mesh reader (dsreg eval)", fuzz_obj},
        {"off", "OFF mesh reader (dsreg eval)", fuzz_off},
        {"ply", "PLY mesh reader, ASCII and binary (dsreg eval)", fuzz_ply},
        {"stl", "STL mesh reader, ASCII and binary (dsreg eval)", fuzz_stl},
        {"vtk", "VTK legacy PolyData reader, ASCII and binary (dsreg eval)", fuzz_vtk},
        {"vtp", "VTK XML PolyData reader (dsreg eval)", fuzz_vtp},
    };
    return all;
}

const Target* find_target(const std::string& name) {
    for (const Target& t : targets())
        if (name == t.name) return &t;
    return nullptr;
}

}  // namespace dsreg::fuzz
