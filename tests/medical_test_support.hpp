// Shared set-up of the medical-image tests: an ellipsoid fixed in world (LPS) space, sampled on
// an oblique, anisotropic grid, and scratch folders.
#pragma once

#include <gtest/gtest.h>
#include <unistd.h>

#include <Eigen/Geometry>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "dsreg/implicit_shape.hpp"
#include "dsreg/volume.hpp"

namespace dsreg::test {

/// A fresh folder under the system's temporary folder, removed at the end of the test.
class ScratchFolder {
public:
    explicit ScratchFolder(const std::string& name) {
        folder_ = std::filesystem::temp_directory_path() / ("dsreg-" + name + "-" + std::to_string(::getpid()));
        std::filesystem::remove_all(folder_);
        std::filesystem::create_directories(folder_);
    }
    ~ScratchFolder() {
        if (std::getenv("DSREG_KEEP_SCRATCH") != nullptr) return;  // for debugging a test
        std::error_code ignored;
        std::filesystem::remove_all(folder_, ignored);
    }
    std::string path(const std::string& name) const { return (folder_ / name).string(); }
    std::string folder() const { return folder_.string(); }
    /// Names of the files in the folder.
    std::vector<std::string> entries() const {
        std::vector<std::string> names;
        for (const auto& entry : std::filesystem::directory_iterator(folder_)) names.push_back(entry.path().filename().string());
        return names;
    }

private:
    std::filesystem::path folder_;
};

/// Rotation by `degrees` about `axis`.
inline Eigen::Matrix3d rotation(double degrees, const Eigen::Vector3d& axis) {
    return Eigen::AngleAxisd(degrees * M_PI / 180.0, axis.normalized()).toRotationMatrix();
}

/// The grid of the test: direction cosines rotated 25° (about an oblique axis),
/// spacing 0.75 × 1.0 × 1.25 mm (exact in float32, as NIfTI stores it), non-zero origin.
inline VoxelGrid oblique_grid(const Index3& dims = {40, 36, 30}) {
    VoxelGrid grid;
    grid.dims = dims;
    grid.spacing = Eigen::Vector3d(0.75, 1.0, 1.25);
    grid.origin = Eigen::Vector3d(-20.5, 13.25, 7.75);
    grid.direction = rotation(25, Eigen::Vector3d(1, 2, 3));
    return grid;
}

/// World (LPS) position of voxel (i,j,k) of `grid`: origin + D·(spacing ⊙ index).
inline Eigen::Vector3d world_position(const VoxelGrid& grid, double i, double j, double k) {
    return grid.origin + grid.direction * grid.spacing.cwiseProduct(Eigen::Vector3d(i, j, k));
}

/// An ellipsoid fixed in world space: centre, semi-axes and its own rotation.
struct WorldEllipsoid {
    Eigen::Vector3d centre;
    Eigen::Vector3d semi_axes;
    Eigen::Matrix3d axes;  ///< columns: directions of the semi-axes

    /// (x − c)ᵀ M (x − c) − 1 ≤ 0 inside, M = axes · diag(1/a²) · axesᵀ.
    Eigen::Matrix3d quadric() const { return axes * semi_axes.cwiseInverse().cwiseAbs2().asDiagonal() * axes.transpose(); }
    bool inside(const Eigen::Vector3d& x) const { return (x - centre).dot(quadric() * (x - centre)) <= 1.0; }

    /// The same ellipsoid as a dsreg polynomial in world coordinates (for distances).
    ImplicitShape shape() const {
        const Eigen::Matrix3d m = quadric();
        const auto term = [&](int a) {
            return "(" + coordinate(a) + "-(" + number(centre[a]) + "))";
        };
        std::string text;
        for (int a = 0; a < 3; ++a)
            for (int b = 0; b < 3; ++b) text += (text.empty() ? "" : "+") + number(m(a, b)) + "*" + term(a) + "*" + term(b);
        text += "-1";
        return make_shape(text, centre.cwiseAbs().maxCoeff() + semi_axes.maxCoeff() + 5);
    }

    /// The ellipsoid seen in RAS coordinates (x and y negated).
    WorldEllipsoid in_ras() const {
        const Eigen::Matrix3d flip = Eigen::Vector3d(-1, -1, 1).asDiagonal();
        return {flip * centre, semi_axes, flip * axes};
    }

private:
    static std::string coordinate(int a) { return a == 0 ? "x" : a == 1 ? "y" : "z"; }
    static std::string number(double x) {
        char buffer[40];
        std::snprintf(buffer, sizeof buffer, "%.17g", x);
        return buffer;
    }
};

/// The ellipsoid of the tests, well inside oblique_grid() (semi-axes 11, 8, 6 mm).
inline WorldEllipsoid test_ellipsoid(const VoxelGrid& grid) {
    const Eigen::Vector3d middle = world_position(grid, (grid.dims[0] - 1) / 2.0, (grid.dims[1] - 1) / 2.0, (grid.dims[2] - 1) / 2.0);
    return {middle + Eigen::Vector3d(0.4, -0.3, 0.2), Eigen::Vector3d(11, 8, 6), rotation(-40, Eigen::Vector3d(3, -1, 2))};
}

/// Labels of `grid`'s voxels: `label` inside the ellipsoid, 0 outside, x fastest.
inline std::vector<double> sample_ellipsoid(const VoxelGrid& grid, const WorldEllipsoid& ellipsoid, double label = 1) {
    std::vector<double> values;
    values.reserve(static_cast<std::size_t>(grid.voxel_count()));
    for (std::int64_t k = 0; k < grid.dims[2]; ++k)
        for (std::int64_t j = 0; j < grid.dims[1]; ++j)
            for (std::int64_t i = 0; i < grid.dims[0]; ++i)
                values.push_back(ellipsoid.inside(world_position(grid, double(i), double(j), double(k))) ? label : 0.0);
    return values;
}

}  // namespace dsreg::test
