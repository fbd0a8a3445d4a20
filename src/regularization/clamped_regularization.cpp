// dsreg — clamped ("reversible") regularization: eq. (1) under per-vertex boxes, and the
// re-digitization check of the result.
#include "dsreg/clamped_regularization.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>

#include "dsreg/error.hpp"
#include "dsreg/evaluation.hpp"
#include "dsreg/label_surface.hpp"

namespace dsreg {

namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

/// How far the unconstrained solution leaves the boxes (vertex count, max excess in spacings).
void measure_box_excess(const DigitalSurface& surface, const PointMatrix& positions, double half_width, ClampReport& report) {
    const Eigen::Vector3d spacing = surface.grid.spacing;
    for (std::int64_t i = 0; i < surface.vertex_count(); ++i) {
        double excess = 0;
        for (int d = 0; d < 3; ++d)
            excess = std::max(excess, std::abs(positions(i, d) - surface.vertices(i, d)) / spacing[d] - half_width);
        if (excess > 0) {
            ++report.unclamped_vertices_outside;
            report.unclamped_max_excess = std::max(report.unclamped_max_excess, excess);
        }
    }
}

std::int64_t vertices_on_their_box(const PointMatrix& positions, const Eigen::VectorXd& lower, const Eigen::VectorXd& upper) {
    std::int64_t count = 0;
    for (Eigen::Index i = 0; i < positions.rows(); ++i) {
        bool on_box = false;
        for (int d = 0; d < 3; ++d) {
            const double x = positions(i, d);
            on_box = on_box || x <= lower[3 * i + d] || x >= upper[3 * i + d];
        }
        count += on_box ? 1 : 0;
    }
    return count;
}

}  // namespace

void clamp_bounds(const DigitalSurface& surface, double half_width, Eigen::VectorXd& lower, Eigen::VectorXd& upper) {
    if (!(half_width > 0) || !std::isfinite(half_width))
        throw Error("clamp half-width must be a positive finite number of voxels (got " + std::to_string(half_width) + ")");
    const Eigen::VectorXd p = flatten_points(surface.vertices);
    lower.resize(p.size());
    upper.resize(p.size());
    for (Eigen::Index q = 0; q < p.size(); ++q) {
        const double reach = half_width * surface.grid.spacing[q % 3];
        lower[q] = p[q] - reach;
        upper[q] = p[q] + reach;
    }
}

ClampedRegularizationResult regularize_clamped(const DigitalSurface& surface, const PointMatrix& normals,
                                               const RegularizationWeights& weights, const ClampOptions& options) {
    ClampedRegularizationResult result;
    auto started = Clock::now();
    const VertexLinks links = fairness_links(surface);  // junction-aware on a label complex
    const RegularizationSystem system =
        assemble_regularization_system(surface.vertices, surface.quads, links, normals, weights);
    Eigen::VectorXd lower, upper;
    clamp_bounds(surface, options.half_width, lower, upper);
    result.assembly_seconds = seconds_since(started);

    // Unconstrained minimizer of eq. (22) (the answer if inside the boxes), then the box QP.
    started = Clock::now();
    BoxQpOptions qp = options.qp;
    if (!(qp.smallest_eigenvalue_bound > 0)) qp.smallest_eigenvalue_bound = smallest_eigenvalue_bound(weights, surface.vertex_count());
    Eigen::VectorXd unconstrained, x;
    result.clamp.qp = solve_box_qp_from_unconstrained(system.matrix, system.rhs, lower, upper, unconstrained, x, qp);
    result.solve_seconds = seconds_since(started);
    result.solve.solver = "cholmod";
    result.solve.relative_residual = result.clamp.qp.unconstrained_residual;
    result.solve.factor_nonzeros = result.clamp.qp.factor_nonzeros;
    result.unclamped_positions = unflatten_points(unconstrained);
    measure_box_excess(surface, result.unclamped_positions, options.half_width, result.clamp);

    result.positions = unflatten_points(x);
    result.clamp.clamped_vertices = vertices_on_their_box(result.positions, lower, upper);
    result.energy_before = regularization_energy(surface.vertices, surface.vertices, surface.quads, links, normals, weights);
    result.energy_after = regularization_energy(result.positions, surface.vertices, surface.quads, links, normals, weights);
    result.clamp.unclamped_energy =
        regularization_energy(result.unclamped_positions, surface.vertices, surface.quads, links, normals, weights);
    return result;
}

VoxelAgreement classify_voxel_centres(const BinaryVolume& volume, const PointMatrix& positions, const FaceMatrix& quads) {
    const FaceMatrix triangles = mesh_triangles(positions, quads);
    const std::vector<std::uint8_t> inside = voxel_centres_inside(positions, triangles, volume.grid);
    VoxelAgreement agreement;
    agreement.total = volume.grid.voxel_count();
    for (std::size_t v = 0; v < inside.size(); ++v) {
        const bool object = volume.mask[v] != 0;
        if (object && !inside[v]) ++agreement.object_outside;
        if (!object && inside[v]) ++agreement.background_inside;
    }
    agreement.correct = agreement.total - agreement.wrong();
    return agreement;
}

}  // namespace dsreg
