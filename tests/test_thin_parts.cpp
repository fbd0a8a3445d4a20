// Thin parts with the default pipeline (no option): a torus whose tube is 1.5 voxels in radius and
// an ellipsoidal shell 2 voxels thick keep their volume (within 3 % of the true solid's) and their
// voxels (99 % of the voxel centres next to the surface, inside and outside, on the right side).
// Also the two corrections behind it: the thin-part data weights and the shrink correction.
#include <gtest/gtest.h>

#include <cmath>

#include "dsreg/digital_surface.hpp"
#include "dsreg/evaluation.hpp"
#include "dsreg/implicit_shape.hpp"
#include "dsreg/local_weights.hpp"
#include "dsreg/pipeline.hpp"
#include "dsreg/shrink_correction.hpp"
#include "test_support.hpp"

namespace dsreg {
namespace {

struct ThinCase {
    const char* polynomial;
    double box;
    bool tube;
};

TEST(ThinParts, TubeAndShellKeepTheirVolumeAndVoxelsWithTheDefaults) {
    const ThinCase cases[] = {
        {"(x^2+y^2+z^2+9-0.140625)^2-36*(x^2+y^2)", 3.6, true},  // tube radius 0.375 = 1.5 voxels
        {"(0.1111111*x^2+0.25*y^2+0.4444444*z^2-1)*(0.0816327*x^2+0.16*y^2+0.25*z^2-1)", 4, false},  // 2 voxels thick
    };
    for (const ThinCase& c : cases) {
        VolumeSource source;
        source.shape = c.polynomial;
        source.box = c.box;
        source.h = 0.25;
        const PipelineResult result = run_pipeline(source, PipelineOptions{});
        const ImplicitShape shape = make_shape(c.polynomial, c.box);
        const PolygonMesh mesh{result.regularization.positions, result.surface.quads, {}, {}};
        const double truth = shape_volume(shape, 16);
        const double volume = enclosed_volume(mesh.vertices, mesh_triangles(mesh.vertices, mesh.faces));
        EXPECT_NEAR(volume / truth, 1.0, 0.03) << c.polynomial;
        const VoxelClassification voxels = classify_voxel_centres(mesh, digitize(shape, 0.25));
        EXPECT_GE(voxels.boundary_share(), 0.99) << c.polynomial;
        EXPECT_GE(voxels.share(), 0.99) << c.polynomial;
        // Without the thin-part weights and the shrink correction the solve loses more than 9 % of
        // the tube's volume (a shell, with a surface on each side, much less). Measured as solved:
        // the validity repair would pull the collapsed tube back to its voxels.
        if (!c.tube) continue;
        PipelineOptions paper;
        paper.extensions.alpha_reach = 0.0;
        paper.extensions.shrink_correction = 0;
        paper.validity = ValidityMode::Off;
        const PipelineResult plain = run_pipeline(source, paper);
        const double plain_volume = enclosed_volume(
            plain.regularization.positions, mesh_triangles(plain.regularization.positions, plain.surface.quads));
        EXPECT_LT(plain_volume / truth, 0.91);
    }
}

TEST(ThinPartAlpha, InverseSquareOfTheSmallestReachAroundEachVertexBelowTheReference) {
    // Two faces of a 2×1 strip of surfels: vertex reach = the smaller of its faces' reaches.
    const BinaryVolume volume = test::make_voxels({2, 1, 1}, {{0, 0, 0}, {1, 0, 0}});
    const DigitalSurface surface = extract_digital_surface(volume, Connectivity::TwentySix);
    Eigen::VectorXd reach = Eigen::VectorXd::Constant(surface.face_count(), 20.0);
    reach[0] = 3.0;
    const Eigen::VectorXd alpha = thin_part_alpha(surface, reach, 12.0);
    ASSERT_EQ(alpha.size(), surface.vertex_count());
    for (std::int64_t v = 0; v < surface.vertex_count(); ++v) {
        bool on_face_0 = false;
        for (int k = 0; k < 4; ++k) on_face_0 |= surface.quads(0, k) == v;
        EXPECT_DOUBLE_EQ(alpha[v], on_face_0 ? 16.0 : 1.0);  // (12/3)², or 1 above the reference
    }
    EXPECT_THROW(thin_part_alpha(surface, reach, 0.0), Error);
    EXPECT_THROW(thin_part_alpha(surface, Eigen::VectorXd::Ones(3), 12.0), Error);
}

TEST(ShrinkCorrection, UndoesAUniformShrinkOfABall) {
    // The digital surface of a ball of radius 10 voxels, moved inward by 0.3 voxel along the
    // radius, with the radial field: the correction brings the mean radius back to the digital
    // surface's (the surfel centres are on average on it), within 0.03 voxel.
    const BinaryVolume volume = test::make_ball(25, 10.0, 12.0);
    const DigitalSurface surface = extract_digital_surface(volume, Connectivity::TwentySix);
    const Eigen::RowVector3d centre(12, 12, 12);
    PointMatrix shrunk = surface.vertices;
    for (Eigen::Index v = 0; v < shrunk.rows(); ++v)
        shrunk.row(v) -= 0.3 * (shrunk.row(v) - centre).normalized();
    const PointMatrix centres = surfel_centers(surface);
    PointMatrix radial(surface.face_count(), 3);
    for (Eigen::Index f = 0; f < radial.rows(); ++f) radial.row(f) = (centres.row(f) - centre).normalized();
    const auto mean_radius = [&](const PointMatrix& p) {
        double sum = 0;
        for (Eigen::Index v = 0; v < p.rows(); ++v) sum += (p.row(v) - centre).norm();
        return sum / double(p.rows());
    };
    const ShrinkCorrection corrected = correct_shrink(surface, shrunk, radial, 40);
    double centre_radius = 0;
    for (Eigen::Index f = 0; f < centres.rows(); ++f) centre_radius += (centres.row(f) - centre).norm();
    centre_radius /= double(centres.rows());
    EXPECT_NEAR(mean_radius(corrected.positions), centre_radius, 0.03);
    EXPECT_NEAR(corrected.mean_shift, 0.3, 0.05);
    // No steps: nothing moves.
    EXPECT_EQ(correct_shrink(surface, shrunk, radial, 0).positions, shrunk);
    EXPECT_THROW(correct_shrink(surface, shrunk, radial, -1), Error);
    EXPECT_THROW(correct_shrink(surface, shrunk.topRows(3), radial, 4), Error);
}

}  // namespace
}  // namespace dsreg
