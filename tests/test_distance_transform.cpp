// The separable distance transform against the definition (nearest target voxel centre by brute
// force), on random volumes with anisotropic spacing, the border counting as background.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include "dsreg/distance_transform.hpp"
#include "dsreg/error.hpp"
#include "test_support.hpp"

namespace dsreg {
namespace {

/// The distance from voxel (i,j,k) to the nearest target voxel centre, by trying every voxel
/// and, for the background, every voxel of the one-voxel layer around the grid.
double brute_force_distance(const BinaryVolume& v, const Index3& p, DistanceTarget target) {
    const Index3& d = v.grid.dims;
    double best = std::numeric_limits<double>::infinity();
    const bool to_background = target == DistanceTarget::background;
    const std::int64_t margin = to_background ? 1 : 0;
    for (std::int64_t k = -margin; k < d[2] + margin; ++k)
        for (std::int64_t j = -margin; j < d[1] + margin; ++j)
            for (std::int64_t i = -margin; i < d[0] + margin; ++i) {
                if (v.inside(i, j, k) == to_background) continue;  // inside() is false outside the grid
                const Eigen::Vector3d delta = v.grid.spacing.cwiseProduct(
                    Eigen::Vector3d(double(i - p[0]), double(j - p[1]), double(k - p[2])));
                best = std::min(best, delta.norm());
            }
    return best;
}

TEST(DistanceTransform, MatchesTheDefinitionOnRandomAnisotropicVolumes) {
    std::mt19937 random(7);
    for (int trial = 0; trial < 4; ++trial) {
        std::bernoulli_distribution coin(trial < 2 ? 0.7 : 0.1);
        BinaryVolume v = test::make_volume({9, 7, 6}, [&](double, double, double) { return coin(random); });
        v.grid.spacing = Eigen::Vector3d(1.0, 0.6, 1.7);
        for (DistanceTarget target : {DistanceTarget::background, DistanceTarget::object, DistanceTarget::other_kind}) {
            const std::vector<float> d = euclidean_distance_transform(v, target);
            ASSERT_EQ(d.size(), v.mask.size());
            for (std::int64_t k = 0; k < 6; ++k)
                for (std::int64_t j = 0; j < 7; ++j)
                    for (std::int64_t i = 0; i < 9; ++i) {
                        // other_kind: an object voxel's distance to the background, a background
                        // voxel's to the object.
                        const DistanceTarget own = target != DistanceTarget::other_kind ? target
                                                   : v.inside(i, j, k)                  ? DistanceTarget::background
                                                                                        : DistanceTarget::object;
                        const double expected = brute_force_distance(v, {i, j, k}, own);
                        EXPECT_NEAR(d[std::size_t(v.grid.linear_index(i, j, k))], expected, 1e-5 * (1 + expected))
                            << "voxel " << i << " " << j << " " << k;
                    }
        }
    }
}

TEST(DistanceTransform, CappedIsTheExactDistanceClampedAtTheCap) {
    // Wider than the 16 lines the passes along y and z take together (two tiles and a partial
    // one), sparse targets so that many distances exceed the cap.
    std::mt19937 random(11);
    std::bernoulli_distribution coin(0.02);
    BinaryVolume v = test::make_volume({35, 20, 9}, [&](double, double, double) { return coin(random); });
    v.grid.spacing = Eigen::Vector3d(0.8, 1.0, 1.9);
    const double cap = 3.5;
    const std::vector<float> exact = euclidean_distance_transform(v, DistanceTarget::object);
    const std::vector<float> capped = euclidean_distance_transform(v, DistanceTarget::object, cap);
    const std::vector<float> both = euclidean_distance_transform(v, DistanceTarget::other_kind, cap);
    std::int64_t beyond = 0;
    for (std::int64_t k = 0; k < 9; ++k)
        for (std::int64_t j = 0; j < 20; ++j)
            for (std::int64_t i = 0; i < 35; ++i) {
                const std::size_t at = std::size_t(v.grid.linear_index(i, j, k));
                const double expected = brute_force_distance(v, {i, j, k}, DistanceTarget::object);
                EXPECT_NEAR(exact[at], expected, 1e-5 * (1 + expected)) << "voxel " << i << " " << j << " " << k;
                EXPECT_NEAR(capped[at], std::min(expected, cap), 1e-5 * (1 + cap)) << "voxel " << i << " " << j << " " << k;
                const double other = v.inside(i, j, k) ? brute_force_distance(v, {i, j, k}, DistanceTarget::background) : expected;
                EXPECT_NEAR(both[at], std::min(other, cap), 1e-5 * (1 + cap)) << "voxel " << i << " " << j << " " << k;
                beyond += expected > cap ? 1 : 0;
            }
    EXPECT_GT(beyond, 100);
    EXPECT_THROW(euclidean_distance_transform(v, DistanceTarget::object, 0.0), Error);
}

TEST(DistanceTransform, BallCentreIsTheNearestLatticePointOutsideAway) {
    // A digital ball of radius 6 voxels holds the lattice points within 6 of its centre, so the
    // nearest background voxel is at the smallest squared norm above 36: (6,1,0), √37 away.
    const BinaryVolume ball = test::make_ball(17, 6.0, 8.0);
    const std::vector<float> d = euclidean_distance_transform(ball, DistanceTarget::background);
    EXPECT_FLOAT_EQ(d[std::size_t(ball.grid.linear_index(8, 8, 8))], std::sqrt(37.0f));
    // A corner of the grid, outside the ball: its distance to the ball's nearest voxel.
    const std::vector<float> out = euclidean_distance_transform(ball, DistanceTarget::object);
    EXPECT_NEAR(out[0], brute_force_distance(ball, {0, 0, 0}, DistanceTarget::object), 1e-5);
    EXPECT_EQ(out[std::size_t(ball.grid.linear_index(8, 8, 8))], 0.0f);
}

TEST(DistanceTransform, NoObjectIsInfinitelyFar) {
    const BinaryVolume empty = test::make_volume({4, 3, 2}, [](double, double, double) { return false; });
    for (float d : euclidean_distance_transform(empty, DistanceTarget::object)) EXPECT_TRUE(std::isinf(d));
    for (float d : euclidean_distance_transform(empty, DistanceTarget::background)) EXPECT_EQ(d, 0.0f);
}

}  // namespace
}  // namespace dsreg
