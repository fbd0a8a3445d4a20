// Input normal fields from outside and from convolution: the normals text file (round trip,
// tolerant syntax, every malformed file rejected with its name and line) and the convolved
// trivial normals (against brute force).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <random>
#include <sstream>

#include "dsreg/ambrosio_tortorelli.hpp"
#include "dsreg/error.hpp"
#include "dsreg/normals.hpp"
#include "dsreg/normals_file.hpp"
#include "dsreg/regularization.hpp"
#include "test_support.hpp"

namespace dsreg {
namespace {

/// A small surface with non-trivial normals.
struct Ball {
    BinaryVolume volume = test::make_ball(12, 4.5, 5.5);
    DigitalSurface surface = extract_digital_surface(volume, Connectivity::TwentySix);
    PointMatrix normals = integral_invariant_normals(volume, surface, 3.0);
};

const Ball& ball() {
    static const Ball b;
    return b;
}

std::string temp_path(const std::string& name) { return ::testing::TempDir() + "dsreg_normals_" + name; }

std::string read_text(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
}

void write_text(const std::string& path, const std::string& text) {
    std::ofstream out(path, std::ios::binary);
    out << text;
}

/// The data lines of a valid file for ball(), without the header comments.
std::vector<std::string> valid_lines() {
    const std::string path = temp_path("valid.txt");
    write_normals_file(path, ball().surface, ball().normals);
    std::istringstream in(read_text(path));
    std::vector<std::string> lines;
    for (std::string line; std::getline(in, line);)
        if (!line.empty() && line[0] != '#') lines.push_back(line);
    std::remove(path.c_str());
    return lines;
}

std::string join(const std::vector<std::string>& lines) {
    std::string text;
    for (const std::string& line : lines) text += line + "\n";
    return text;
}

/// Reading `text` (saved as `name`) fails with a message containing every one of `parts`.
void expect_rejected(const std::string& name, const std::string& text, const std::vector<std::string>& parts) {
    const std::string path = temp_path(name);
    write_text(path, text);
    try {
        read_normals_file(path, ball().surface);
        ADD_FAILURE() << name << ": accepted";
    } catch (const Error& e) {
        const std::string message = e.what();
        EXPECT_NE(message.find(path), std::string::npos) << message;
        for (const std::string& part : parts) EXPECT_NE(message.find(part), std::string::npos) << message;
    }
    std::remove(path.c_str());
}

/// A valid file whose line `line` (0-based) has its fields from `index` on replaced by `values`.
std::string with_field(std::size_t line, std::size_t index, const std::string& values) {
    std::vector<std::string> lines = valid_lines();
    std::istringstream in(lines[line]);
    std::vector<std::string> fields;
    for (std::string f; in >> f;) fields.push_back(f);
    std::string rebuilt;
    for (std::size_t q = 0; q < index; ++q) rebuilt += fields[q] + " ";
    rebuilt += values;
    for (std::size_t q = index + 1; q < fields.size() && values.find(' ') == std::string::npos; ++q) rebuilt += " " + fields[q];
    lines[line] = rebuilt;
    return join(lines);
}

// ---- the file format ---------------------------------------------------------------------------

TEST(NormalsFile, WriteThenReadGivesTheSameBits) {
    const std::string path = temp_path("roundtrip.txt");
    write_normals_file(path, ball().surface, ball().normals, "integral invariants, r = 3");
    const std::string text = read_text(path);
    EXPECT_EQ(text.rfind("# dsreg normals", 0), 0u);
    EXPECT_NE(text.find("# field: integral invariants, r = 3"), std::string::npos);
    const PointMatrix back = read_normals_file(path, ball().surface);
    EXPECT_EQ(back, ball().normals);  // shortest exact decimals, unit vectors kept as they are
    std::remove(path.c_str());
}

TEST(NormalsFile, LinesNameTheVoxelAndTheSideOfItsFace) {
    const DigitalSurface s = extract_digital_surface(test::make_voxels({3, 3, 3}, {{1, 2, 0}}), Connectivity::Six);
    const std::string path = temp_path("voxel.txt");
    write_normals_file(path, s, trivial_normals(s));
    const std::string text = read_text(path);
    for (const char* line : {"1 2 0 +x 1 0 0\n", "1 2 0 -x -1 0 0\n", "1 2 0 +y 0 1 0\n", "1 2 0 -y 0 -1 0\n",
                             "1 2 0 +z 0 0 1\n", "1 2 0 -z 0 0 -1\n"})
        EXPECT_NE(text.find(line), std::string::npos) << line << " in\n" << text;
    std::remove(path.c_str());
}

TEST(NormalsFile, AcceptsAnyOrderCommentsBlankLinesCrlfTabsAndUnnormalizedVectors) {
    std::vector<std::string> lines = valid_lines();
    std::reverse(lines.begin(), lines.end());
    std::string text = "\xEF\xBB\xBF# an external estimator, UTF-8 with a byte order mark\n\n";
    for (std::size_t q = 0; q < lines.size(); ++q) {
        std::string line = lines[q];
        if (q % 3 == 0) std::replace(line.begin(), line.end(), ' ', '\t');
        if (q % 5 == 0) line += "  # trailing comment";
        text += line + (q % 2 ? "\r\n" : "\n");
    }
    const std::string path = temp_path("tolerant.txt");
    write_text(path, text);
    EXPECT_LT((read_normals_file(path, ball().surface) - ball().normals).cwiseAbs().maxCoeff(), 1e-15);

    // Upper-case axis, explicit '+' on numbers, a vector of length 2, no final newline.
    const DigitalSurface s = extract_digital_surface(test::make_voxels({3, 3, 3}, {{1, 1, 1}}), Connectivity::Six);
    write_text(path, "1 1 1 +X +2 0 0\n1 1 1 -X -2 0 0\n1 1 1 +Y 0 2 0\n1 1 1 -Y 0 -2 0\n1 1 1 +Z 0 0 2\n1 1 1 -Z 0 0 -2");
    EXPECT_EQ(read_normals_file(path, s), trivial_normals(s));
    std::remove(path.c_str());
}

TEST(NormalsFile, BrokenFilesAreRejectedWithFileAndLine) {
    const std::vector<std::string> lines = valid_lines();
    const std::string all = join(lines);
    expect_rejected("missing.txt", join(std::vector<std::string>(lines.begin() + 1, lines.end())),
                    {"no normal for 1 of the", "voxel", "direction"});
    expect_rejected("empty.txt", "", {"no normal for"});
    expect_rejected("duplicate.txt", all + lines[3] + "\n", {":" + std::to_string(lines.size() + 1) + ":", "already given on line 4"});
    expect_rejected("fields.txt", with_field(2, 4, "0.5 0.5 0.5 0.5"), {":3:", "expected 7 fields"});
    expect_rejected("short.txt", "5 5 5 +x 1 0\n", {":1:", "expected 7 fields"});
    expect_rejected("word.txt", with_field(4, 5, "north"), {":5:", "'north' is not a number"});
    expect_rejected("trailing.txt", with_field(4, 4, "0.5x"), {":5:", "not a number"});
    expect_rejected("index.txt", with_field(0, 1, "2.5"), {":1:", "not an integer"});
    expect_rejected("huge-index.txt", with_field(0, 0, "99999999999999999999999"), {":1:", "not an integer"});
    expect_rejected("direction.txt", with_field(1, 3, "+w"), {":2:", "not one of +x -x +y -y +z -z"});
    expect_rejected("zero.txt", with_field(6, 4, "0 0 0"), {":7:", "zero"});
    expect_rejected("nan.txt", with_field(7, 5, "nan"), {":8:", "not finite"});
    expect_rejected("inf.txt", with_field(7, 6, "-inf"), {":8:", "not finite"});
    expect_rejected("outside.txt", with_field(0, 2, "12"), {":1:", "outside the grid"});
    expect_rejected("negative.txt", with_field(0, 2, "-1"), {":1:", "outside the grid"});
    // The face between two object voxels (the ball's centre) is not a surfel.
    expect_rejected("interior.txt", all + "5 5 5 +x 1 0 0\n", {":" + std::to_string(lines.size() + 1) + ":", "not a surfel"});
    expect_rejected("long.txt", all + std::string(5000, '1') + "\n", {"longer than 1024"});
    expect_rejected("binary.txt", std::string("\x7f" "ELF\x02\x01\x01\0\0\0", 10) + "\n" + all, {":1:"});
    EXPECT_THROW(read_normals_file(temp_path("does-not-exist.txt"), ball().surface), Error);
}

TEST(NormalsFile, WritingChecksTheFieldSize) {
    EXPECT_THROW(write_normals_file(temp_path("bad.txt"), ball().surface, ball().normals.topRows(2)), Error);
}

TEST(NormalsFile, ExportedAtFieldGivesTheSameRegularizedMesh) {
    const AmbrosioTortorelliResult at = ambrosio_tortorelli_normals(ball().surface, ball().normals, {});
    const std::string path = temp_path("at.txt");
    write_normals_file(path, ball().surface, at.normals, "Ambrosio-Tortorelli");
    const PointMatrix imported = read_normals_file(path, ball().surface);
    const RegularizationResult direct = regularize(ball().surface, at.normals, RegularizationWeights{}, SolverOptions{});
    const RegularizationResult reread = regularize(ball().surface, imported, RegularizationWeights{}, SolverOptions{});
    EXPECT_EQ(direct.positions, reread.positions);
    std::remove(path.c_str());
}

// ---- convolved trivial normals -----------------------------------------------------------------

/// The definition: the sum of the trivial normals within r, each weighted by its face's area.
PointMatrix brute_force_convolved(const DigitalSurface& s, double r) {
    const PointMatrix c = surfel_centers(s);
    const Eigen::Vector3d& h = s.grid.spacing;
    PointMatrix u(s.face_count(), 3);
    for (std::int64_t f = 0; f < s.face_count(); ++f) {
        Eigen::RowVector3d sum = Eigen::RowVector3d::Zero();
        for (std::int64_t g = 0; g < s.face_count(); ++g) {
            const int axis = s.surfels[std::size_t(g)].axis;
            const double area = h.prod() / h[axis];
            if ((c.row(g) - c.row(f)).squaredNorm() <= r * r) sum += area * s.surfels[std::size_t(g)].trivial_normal().transpose();
        }
        u.row(f) = sum.normalized();
    }
    return u;
}

TEST(ConvolvedNormals, EqualBruteForceOnAnAnisotropicGrid) {
    std::mt19937 rng(5);
    std::bernoulli_distribution coin(0.7);
    BinaryVolume v = test::make_volume({10, 9, 8}, [&](double x, double y, double z) {
        return (x - 4.5) * (x - 4.5) + (y - 4) * (y - 4) + (z - 3.5) * (z - 3.5) < 12 && coin(rng);
    });
    v.grid.spacing = Eigen::Vector3d(0.7, 1.0, 1.6);
    v.grid.origin = Eigen::Vector3d(3, -2, 0.5);
    const DigitalSurface s = extract_digital_surface(v, Connectivity::TwentySix);
    for (double r : {0.9, 2.0, 3.3}) {
        const PointMatrix fast = convolved_trivial_normals(s, r);
        const PointMatrix slow = brute_force_convolved(s, r);
        for (std::int64_t f = 0; f < s.face_count(); ++f) {
            // Where the neighbours cancel out exactly, the surfel keeps its own normal.
            const Eigen::RowVector3d expected = slow.row(f).norm() > 0
                                                    ? Eigen::RowVector3d(slow.row(f))
                                                    : Eigen::RowVector3d(s.surfels[std::size_t(f)].trivial_normal().transpose());
            EXPECT_LT((fast.row(f) - expected).norm(), 1e-12) << "r " << r << " face " << f;
        }
    }
}

TEST(ConvolvedNormals, TinyRadiusGivesTheTrivialNormals) {
    const DigitalSurface& s = ball().surface;
    EXPECT_EQ(convolved_trivial_normals(s, 0.3), trivial_normals(s));
}

TEST(ConvolvedNormals, ApproachTheTrueNormalOfATiltedPlane) {
    const Eigen::Vector3d n = Eigen::Vector3d(1, 2, 5).normalized();
    const BinaryVolume v = test::make_volume({30, 30, 30}, [&](double x, double y, double z) {
        return n.dot(Eigen::Vector3d(x, y, z) - Eigen::Vector3d::Constant(14.5)) <= 0;
    });
    const DigitalSurface s = extract_digital_surface(v, Connectivity::TwentySix);
    const PointMatrix c = surfel_centers(s);
    const PointMatrix trivial = trivial_normals(s), convolved = convolved_trivial_normals(s, 5.0);
    double trivial_error = 0, convolved_error = 0;
    int count = 0;
    for (std::int64_t f = 0; f < s.face_count(); ++f) {
        const Eigen::Vector3d p = c.row(f).transpose() - Eigen::Vector3d::Constant(14.5);
        if (std::abs(p.dot(n)) > 2 || (p - p.dot(n) * n).norm() > 8) continue;  // on the plane, far from the box
        trivial_error += std::acos(std::min(1.0, trivial.row(f).dot(n)));
        convolved_error += std::acos(std::min(1.0, convolved.row(f).dot(n)));
        ++count;
    }
    ASSERT_GT(count, 100);
    EXPECT_LT(convolved_error / count, 0.1 * trivial_error / count);
}

TEST(ConvolvedNormals, ApproachTheTrueNormalOfATiltedPlaneOnAnAnisotropicGrid) {
    // Without the area weights the sum leans towards the axes of the smaller faces: on this grid
    // (faces across x are 1.6 times smaller than across z) the mean error is 15 degrees, not 2.
    const Eigen::Vector3d h(0.7, 1.0, 1.6), n = Eigen::Vector3d(1, 2, 2).normalized();
    const Eigen::Vector3d centre(14.5 * 0.7, 14.5, 10.5 * 1.6);
    BinaryVolume v = test::make_volume({30, 30, 22}, [&](double x, double y, double z) {
        return n.dot(h.cwiseProduct(Eigen::Vector3d(x, y, z)) - centre) <= 0;
    });
    v.grid.spacing = h;
    const DigitalSurface s = extract_digital_surface(v, Connectivity::TwentySix);
    const PointMatrix c = surfel_centers(s), convolved = convolved_trivial_normals(s, 5.0);
    double error = 0, unweighted_error = 0;
    int count = 0;
    for (std::int64_t f = 0; f < s.face_count(); ++f) {
        const Eigen::Vector3d p = c.row(f).transpose() - centre;
        if (std::abs(p.dot(n)) > 2 || (p - p.dot(n) * n).norm() > 6) continue;  // on the plane, far from the box
        error += std::acos(std::min(1.0, convolved.row(f).dot(n)));
        Eigen::RowVector3d unweighted = Eigen::RowVector3d::Zero();  // the plain sum of the trivial normals
        for (std::int64_t g = 0; g < s.face_count(); ++g)
            if ((c.row(g) - c.row(f)).squaredNorm() <= 25.0) unweighted += s.surfels[std::size_t(g)].trivial_normal().transpose();
        unweighted_error += std::acos(std::min(1.0, unweighted.normalized().dot(n.transpose())));
        ++count;
    }
    ASSERT_GT(count, 50);
    std::printf("convolved trivial normals, tilted plane, spacing 0.7 x 1 x 1.6: mean error %.2f degrees weighted by area, "
                "%.2f unweighted\n", error / count * 180 / M_PI, unweighted_error / count * 180 / M_PI);
    EXPECT_LT(error, 0.5 * unweighted_error);
}

TEST(ConvolvedNormals, ThinPlateKeepsUnitNormalsAndRadiusIsChecked) {
    const BinaryVolume plate = test::make_volume({8, 8, 3}, [](double, double, double z) { return z == 1; });
    const DigitalSurface s = extract_digital_surface(plate, Connectivity::TwentySix);
    const PointMatrix u = convolved_trivial_normals(s, 4.0);
    for (std::int64_t f = 0; f < s.face_count(); ++f) EXPECT_NEAR(u.row(f).norm(), 1.0, 1e-12);
    EXPECT_THROW(convolved_trivial_normals(s, 0.0), Error);
    EXPECT_THROW(convolved_trivial_normals(s, NAN), Error);
    EXPECT_THROW(convolved_trivial_normals(s, INFINITY), Error);
}

}  // namespace
}  // namespace dsreg
