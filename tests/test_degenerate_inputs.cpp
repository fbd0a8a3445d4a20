// Degenerate but valid inputs (empty object, full domain, one voxel, one-voxel-thick sheets,
// objects on the domain border, many components) run through the pipeline or get a clear
// message; invalid parameters (zero or NaN normals, α ≤ 0, negative weights, h ≤ 0) are rejected
// with a message naming them; outputs are atomic.
#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>

#include "dsreg/atomic_file.hpp"
#include "dsreg/error.hpp"
#include "dsreg/implicit_shape.hpp"
#include "dsreg/mesh_io.hpp"
#include "dsreg/normals.hpp"
#include "dsreg/normals_file.hpp"
#include "dsreg/regularization.hpp"
#include "dsreg/volume_io.hpp"
#include "test_support.hpp"

namespace dsreg {
namespace {

namespace fs = std::filesystem;

using test::error_of;

/// A fresh folder for one test's files.
fs::path scratch_folder(const std::string& name) {
    const fs::path folder = fs::temp_directory_path() / ("dsreg-degenerate-" + name + "-" + std::to_string(::getpid()));
    fs::remove_all(folder);
    fs::create_directories(folder);
    return folder;
}

/// Every edge of every face is glued to exactly one face edge going back, each component's Euler
/// characteristic is even and at most 2.
void expect_closed_manifold(const DigitalSurface& s) {
    ASSERT_GT(s.face_count(), 0);
    for (std::int64_t f = 0; f < s.face_count(); ++f)
        for (int e = 0; e < 4; ++e) {
            const std::int64_t g = s.adjacent_face(f, e);
            ASSERT_TRUE(g >= 0 && g < s.face_count());
            // The edge a→b of f is b→a in g.
            const auto a = s.quads(f, e), b = s.quads(f, (e + 1) % 4);
            int back = 0;
            for (int k = 0; k < 4; ++k) back += (s.quads(g, k) == b && s.quads(g, (k + 1) % 4) == a) ? 1 : 0;
            EXPECT_EQ(back, 1) << "face " << f << " edge " << e;
        }
    for (const std::int64_t chi : component_euler_characteristics(s)) {
        EXPECT_LE(chi, 2);
        EXPECT_EQ(chi % 2, 0);
    }
}

/// Runs the regularization with the given normals; positions must be finite and the energy must
/// not increase (p* minimizes it; p̂ = p is a candidate).
void expect_regularizes(const DigitalSurface& surface, const PointMatrix& normals) {
    SolverOptions solver;
    solver.kind = SolverKind::Cholmod;
    const RegularizationWeights weights;
    const RegularizationResult result = regularize(surface, normals, weights, solver);
    ASSERT_EQ(result.positions.rows(), surface.vertex_count());
    EXPECT_TRUE(result.positions.allFinite());
    EXPECT_LE(result.energy_after.total(weights), result.energy_before.total(weights) * (1 + 1e-12) + 1e-12);
}

void expect_unit_normals(const PointMatrix& normals, std::int64_t count) {
    ASSERT_EQ(normals.rows(), count);
    for (std::int64_t f = 0; f < normals.rows(); ++f) {
        ASSERT_TRUE(normals.row(f).allFinite()) << "face " << f;
        EXPECT_NEAR(normals.row(f).norm(), 1.0, 1e-9) << "face " << f;
    }
}

TEST(DegenerateInputs, EmptyObjectGetsAClearMessage) {
    const BinaryVolume empty = test::make_volume({4, 4, 4}, [](double, double, double) { return false; });
    EXPECT_NE(error_of([&] { extract_digital_surface(empty, Connectivity::TwentySix); }).find("the object is empty"),
              std::string::npos);
}

TEST(DegenerateInputs, EmptyObjectFromAFileWithValuesOutsideTheRange) {
    const fs::path folder = scratch_folder("empty-range");
    const std::string path = (folder / "values.vol").string();
    write_vol(path, {3, 3, 3}, std::vector<std::uint8_t>(27, 7), 2);
    ValueRange range;
    range.has_min = true;
    range.min = 8;  // every voxel is 7
    const BinaryVolume volume = read_vol(path, range);
    EXPECT_EQ(volume.object_voxel_count(), 0);
    EXPECT_NE(error_of([&] { extract_digital_surface(volume, Connectivity::Six); }).find("empty"), std::string::npos);
    fs::remove_all(folder);
}

TEST(DegenerateInputs, FullDomainIsABoxOnTheBorder) {
    const BinaryVolume full = test::make_volume({4, 3, 2}, [](double, double, double) { return true; });
    const DigitalSurface s = extract_digital_surface(full, Connectivity::TwentySix);
    EXPECT_EQ(s.face_count(), 2 * (4 * 3 + 3 * 2 + 4 * 2));
    EXPECT_EQ(s.component_count, 1);
    expect_closed_manifold(s);
    EXPECT_EQ(component_euler_characteristics(s), std::vector<std::int64_t>{2});
    // Vertices span the whole domain: pointels 0..n along each axis (at -0.5 .. n-0.5).
    EXPECT_DOUBLE_EQ(s.vertices.col(0).minCoeff(), -0.5);
    EXPECT_DOUBLE_EQ(s.vertices.col(0).maxCoeff(), 3.5);
    const PointMatrix ii = integral_invariant_normals(full, s, 3.0);
    expect_unit_normals(ii, s.face_count());
    expect_regularizes(s, ii);
}

TEST(DegenerateInputs, OneVoxelInAOneVoxelDomain) {
    const BinaryVolume one = test::make_volume({1, 1, 1}, [](double, double, double) { return true; });
    const DigitalSurface s = extract_digital_surface(one, Connectivity::Six);
    EXPECT_EQ(s.face_count(), 6);
    EXPECT_EQ(s.vertex_count(), 8);
    expect_closed_manifold(s);
    expect_unit_normals(integral_invariant_normals(one, s, 3.0), 6);
    expect_regularizes(s, trivial_normals(s));
    expect_regularizes(s, integral_invariant_normals(one, s, 3.0));
}

TEST(DegenerateInputs, OneVoxelThickSheet) {
    const BinaryVolume sheet =
        test::make_volume({7, 7, 3}, [](double x, double y, double z) { return z == 1 && x >= 1 && x <= 5 && y >= 1 && y <= 5; });
    const DigitalSurface s = extract_digital_surface(sheet, Connectivity::TwentySix);
    EXPECT_EQ(s.face_count(), 2 * 25 + 4 * 5);
    EXPECT_EQ(s.component_count, 1);
    expect_closed_manifold(s);
    // Integral invariants on a sheet thinner than the ball: still unit, finite normals.
    const PointMatrix ii = integral_invariant_normals(sheet, s, 3.0);
    expect_unit_normals(ii, s.face_count());
    expect_regularizes(s, ii);
}

TEST(DegenerateInputs, OneVoxelThickLineAlongTheWholeDomain) {
    const BinaryVolume line = test::make_volume({1, 1, 40}, [](double, double, double) { return true; });
    const DigitalSurface s = extract_digital_surface(line, Connectivity::Six);
    EXPECT_EQ(s.face_count(), 4 * 40 + 2);
    expect_closed_manifold(s);
    expect_regularizes(s, integral_invariant_normals(line, s, 3.0));
}

TEST(DegenerateInputs, ObjectCutByTheDomainBorder) {
    // A ball centred on a corner of the domain: the border closes it.
    const BinaryVolume cut = test::make_volume({6, 6, 6}, [](double x, double y, double z) { return x * x + y * y + z * z <= 16; });
    const DigitalSurface s = extract_digital_surface(cut, Connectivity::TwentySix);
    EXPECT_EQ(s.component_count, 1);
    expect_closed_manifold(s);
    EXPECT_DOUBLE_EQ(s.vertices.minCoeff(), -0.5);
    expect_regularizes(s, integral_invariant_normals(cut, s, 2.0));
}

TEST(DegenerateInputs, ManyComponents) {
    // 5x5x5 isolated voxels (every other voxel along each axis), corners on the border.
    const BinaryVolume dots = test::make_volume({9, 9, 9}, [](double x, double y, double z) {
        return std::fmod(x, 2) == 0 && std::fmod(y, 2) == 0 && std::fmod(z, 2) == 0;
    });
    const DigitalSurface s = extract_digital_surface(dots, Connectivity::TwentySix);
    EXPECT_EQ(s.component_count, 125);
    EXPECT_EQ(s.face_count(), 6 * 125);
    expect_closed_manifold(s);
    expect_regularizes(s, integral_invariant_normals(dots, s, 1.5));
}

TEST(DegenerateInputs, VoxelsTouchingAlongAnEdgeOrAtACorner) {
    const BinaryVolume edge = test::make_voxels({2, 2, 1}, {{0, 0, 0}, {1, 1, 0}});
    EXPECT_EQ(extract_digital_surface(edge, Connectivity::Six).component_count, 2);
    // Joined along that edge alone, the surface would be pinched there: kept apart with 26 too
    // (digital_surface.hpp).
    const DigitalSurface joined = extract_digital_surface(edge, Connectivity::TwentySix);
    EXPECT_EQ(joined.component_count, 2);
    expect_closed_manifold(joined);
    expect_regularizes(joined, trivial_normals(joined));
    const BinaryVolume corner = test::make_voxels({2, 2, 2}, {{0, 0, 0}, {1, 1, 1}});
    const DigitalSurface c6 = extract_digital_surface(corner, Connectivity::Six);
    EXPECT_EQ(c6.component_count, 2);
    expect_closed_manifold(c6);
    expect_closed_manifold(extract_digital_surface(corner, Connectivity::TwentySix));
}

// ----------------------------------------------------------------------------------------------
// Normals files with zero or NaN normals

class NormalsFileValues : public ::testing::Test {
protected:
    void SetUp() override {
        const BinaryVolume one = test::make_volume({1, 1, 1}, [](double, double, double) { return true; });
        surface = extract_digital_surface(one, Connectivity::Six);
    }
    /// The text of a valid file for `surface` (trivial normals), with line `line` (1-based
    /// among the data lines) given the normal `replacement`.
    std::string file_with(int line, const std::string& replacement) const {
        std::ostringstream text;
        for (std::int64_t f = 0; f < surface.face_count(); ++f) {
            const Surfel& s = surface.surfels[std::size_t(f)];
            text << s.voxel[0] << ' ' << s.voxel[1] << ' ' << s.voxel[2] << ' ' << surfel_direction_name(s) << ' ';
            if (f + 1 == line)
                text << replacement;
            else
                text << s.trivial_normal().x() << ' ' << s.trivial_normal().y() << ' ' << s.trivial_normal().z();
            text << '\n';
        }
        return text.str();
    }
    std::string read_error(const std::string& text) const {
        std::istringstream in(text);
        return error_of([&] { read_normals(in, "n.txt", surface); });
    }
    DigitalSurface surface;
};

TEST_F(NormalsFileValues, ValidFileReads) {
    std::istringstream in(file_with(0, ""));
    expect_unit_normals(read_normals(in, "n.txt", surface), 6);
}

TEST_F(NormalsFileValues, ZeroNormalIsRejectedWithItsLine) {
    const std::string message = read_error(file_with(3, "0 0 0"));
    EXPECT_EQ(message.rfind("n.txt:3", 0), 0u) << message;
}

TEST_F(NormalsFileValues, NaNAndInfiniteNormalsAreRejectedWithTheirLine) {
    for (const char* bad : {"nan 0 1", "0 NaN 1", "inf 0 0", "0 0 -inf", "1e999 0 0"}) {
        const std::string message = read_error(file_with(2, bad));
        EXPECT_EQ(message.rfind("n.txt:2", 0), 0u) << bad << ": " << message;
    }
}

TEST_F(NormalsFileValues, TinyButNonZeroNormalIsNormalized) {
    std::istringstream in(file_with(1, "1e-300 0 0"));
    const PointMatrix normals = read_normals(in, "n.txt", surface);
    expect_unit_normals(normals, 6);
}

// ----------------------------------------------------------------------------------------------
// Parameters: weights that would make R singular or indefinite, grid steps ≤ 0

TEST(DegenerateParameters, AlphaMustBePositive) {
    const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
    for (const double alpha : {0.0, -1e-3, nan, inf}) {
        const RegularizationWeights w{alpha, 1.0, 1e-2, {}, {}};
        EXPECT_NE(error_of([&] { validate_weights(w, 8, 6); }).find("alpha"), std::string::npos) << alpha;
    }
}

TEST(DegenerateParameters, NegativeOrNaNBetaGammaAreRejected) {
    const double nan = std::numeric_limits<double>::quiet_NaN();
    for (const double bad : {-1.0, nan}) {
        const RegularizationWeights b{1e-3, bad, 1e-2, {}, {}};
        EXPECT_NE(error_of([&] { validate_weights(b, 8, 6); }).find("beta"), std::string::npos) << bad;
        const RegularizationWeights g{1e-3, 1.0, bad, {}, {}};
        EXPECT_NE(error_of([&] { validate_weights(g, 8, 6); }).find("gamma"), std::string::npos) << bad;
    }
}

TEST(DegenerateParameters, NegativeLocalWeightsAreRejected) {
    RegularizationWeights w;
    w.vertex_weights = Eigen::VectorXd::Ones(8);
    w.vertex_weights[3] = -1;
    EXPECT_FALSE(error_of([&] { validate_weights(w, 8, 6); }).empty());
    RegularizationWeights zero_alpha_i;
    zero_alpha_i.vertex_alpha = Eigen::VectorXd::Ones(8);
    zero_alpha_i.vertex_alpha[0] = 0;  // α_i = 0 would leave vertex 0 free: R singular
    EXPECT_FALSE(error_of([&] { validate_weights(zero_alpha_i, 8, 6); }).empty());
}

TEST(DegenerateParameters, ZeroBetaAndGammaStillSolve) {
    // β = γ = 0 is valid: R = α I is SPD, and p* = p.
    const BinaryVolume one = test::make_volume({1, 1, 1}, [](double, double, double) { return true; });
    const DigitalSurface s = extract_digital_surface(one, Connectivity::Six);
    const RegularizationWeights w{1e-3, 0.0, 0.0, {}, {}};
    SolverOptions solver;
    solver.kind = SolverKind::Cholmod;
    const RegularizationResult r = regularize(s, trivial_normals(s), w, solver);
    EXPECT_LT((r.positions - s.vertices).cwiseAbs().maxCoeff(), 1e-9);
}

TEST(DegenerateParameters, GridStepMustBePositiveAndFinite) {
    const ImplicitShape sphere = make_shape("sphere1");
    for (const double h : {0.0, -0.25, std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity()})
        EXPECT_NE(error_of([&] { digitize(sphere, h); }).find("grid step h"), std::string::npos) << h;
}

TEST(DegenerateParameters, GridStepTooSmallIsRefusedBeforeAllocating) {
    const ImplicitShape sphere = make_shape("sphere1");
    EXPECT_NE(error_of([&] { digitize(sphere, 1e-9); }).find("use a larger h"), std::string::npos);
}

// ----------------------------------------------------------------------------------------------
// Atomic outputs

TEST(AtomicOutputs, FailedWriteKeepsTheExistingFileAndLeavesNoTemporary) {
    const fs::path folder = scratch_folder("atomic");
    const std::string path = (folder / "mesh.obj").string();
    {
        std::ofstream out(path);
        out << "precious\n";
    }
    PolygonMesh bad;
    bad.vertices = PointMatrix::Zero(3, 3);
    bad.vertices(1, 2) = std::numeric_limits<double>::quiet_NaN();
    bad.faces.resize(1, 3);
    bad.faces << 0, 1, 2;
    EXPECT_NE(error_of([&] { write_mesh(path, bad); }).find("mesh.obj"), std::string::npos);
    EXPECT_THROW(write_file_atomically(path,
                                       [](std::ostream& out) {
                                           out << "partial";
                                           throw Error("the writer fails half way");
                                       }),
                 Error);
    std::ifstream in(path);
    std::string content;
    std::getline(in, content);
    EXPECT_EQ(content, "precious");
    int files = 0;
    for ([[maybe_unused]] const auto& entry : fs::directory_iterator(folder)) ++files;
    EXPECT_EQ(files, 1) << "a temporary file was left behind";
    fs::remove_all(folder);
}

TEST(AtomicOutputs, SuccessfulWriteReplacesTheFile) {
    const fs::path folder = scratch_folder("atomic-ok");
    const std::string path = (folder / "volume.vol").string();
    {
        std::ofstream out(path);
        out << "old";
    }
    write_vol(path, {2, 1, 1}, {0, 5}, 3);
    const BinaryVolume v = read_vol(path);
    EXPECT_EQ(v.object_voxel_count(), 1);
    fs::remove_all(folder);
}

}  // namespace
}  // namespace dsreg
