// dsreg — the multigrid convergence experiment of the paper's Fig. 7, and ground-truth normals
// of clipped solids.
#include <array>
#include <chrono>
#include <cmath>
#include <limits>
#include <unordered_map>

#include "dsreg/error.hpp"
#include "dsreg/evaluation.hpp"
#include "dsreg/normals.hpp"
#include "dsreg/regularization.hpp"
#include "parallel_checked.hpp"

namespace dsreg {
namespace {

/// True when surfel s bounds the object only because the voxel across it lies beyond a clipped
/// box face (F ≤ 0 there, so without the box that voxel would be object too).
bool is_box_wall_face(const ImplicitShape& shape, const VoxelGrid& grid, const Surfel& s) {
    const int a = s.axis;
    if (!shape.clipped[std::size_t(a)]) return false;
    std::array<std::int64_t, 3> across{s.voxel[0], s.voxel[1], s.voxel[2]};
    across[std::size_t(a)] += s.sign;
    const Eigen::Vector3d q = grid.voxel_center(across[0], across[1], across[2]);
    return (q[a] > shape.upper[a] || q[a] < shape.lower[a]) && shape.polynomial.value(q) <= 0;
}

void check_options(const ConvergenceOptions& o) {
    if (o.normals == InputNormalField::IntegralInvariant && (!(o.radius_k > 0) || !std::isfinite(o.radius_k)))
        throw Error("convergence: the radius factor k (r = k·h^(1/3)) must be positive and finite");
    if (!(o.alpha_k > 0) || !std::isfinite(o.alpha_k))
        throw Error("convergence: the alpha factor A (α = A·h²) must be positive and finite");
    if (!(o.wall_margin >= 0) || !std::isfinite(o.wall_margin))
        throw Error("convergence: the wall margin must be finite and non-negative");
}

ErrorNorms norms_of(std::vector<double> errors) {
    const ErrorStats s = error_stats(std::move(errors));
    return ErrorNorms{s.l2, s.linf};
}

double ratio(double numerator, double denominator) {
    return denominator > 0 ? numerator / denominator : std::numeric_limits<double>::quiet_NaN();
}

/// Distances to ∂X of p and p* over the vertices whose p lies in the region.
void measure_vertices(const ImplicitShape& shape, const PointMatrix& p, const PointMatrix& p_star, double wall_margin,
                      ConvergenceStep& step) {
    std::vector<Eigen::Index> region;
    for (Eigen::Index i = 0; i < p.rows(); ++i)
        if (in_evaluation_region(shape, p.row(i).transpose(), wall_margin)) region.push_back(i);
    if (region.empty())
        throw Error("convergence: no vertex of the digital surface at h = " + std::to_string(step.h) +
                    " lies in the evaluation region (reduce the wall margin)");
    PointMatrix kept(Eigen::Index(region.size()), 3), kept_star(Eigen::Index(region.size()), 3);
    for (std::size_t r = 0; r < region.size(); ++r) {
        kept.row(Eigen::Index(r)) = p.row(region[r]);
        kept_star.row(Eigen::Index(r)) = p_star.row(region[r]);
    }
    const std::vector<double> d = distances_to_surface(shape, kept);
    const std::vector<double> d_star = distances_to_surface(shape, kept_star);
    std::int64_t closer = 0;
    for (std::size_t r = 0; r < d.size(); ++r) closer += d_star[r] < d[r] ? 1 : 0;
    step.vertices_evaluated = std::int64_t(region.size());
    step.closer_share = double(closer) / double(region.size());
    step.p = norms_of(d);
    step.pstar = norms_of(d_star);
    step.ratio = ErrorNorms{ratio(step.pstar.l2, step.p.l2), ratio(step.pstar.linf, step.p.linf)};
}

/// |u*_f − u_f| over the faces whose centroid (of p) lies in the region.
void measure_faces(const ImplicitShape& shape, const DigitalSurface& surface, const PointMatrix& u,
                   const PointMatrix& p_star, double wall_margin, ConvergenceStep& step) {
    const PointMatrix u_star = face_normals(p_star, surface.quads);
    const PointMatrix centroids = face_centroids(surface.vertices, surface.quads);
    std::vector<double> differences;
    for (Eigen::Index f = 0; f < surface.quads.rows(); ++f) {
        if (!in_evaluation_region(shape, centroids.row(f).transpose(), wall_margin)) continue;
        if (u_star.row(f).isZero()) {
            step.faces_degenerate += 1;
            continue;
        }
        differences.push_back((u_star.row(f) - u.row(f)).norm());
    }
    step.faces_evaluated = std::int64_t(differences.size());
    step.normal = norms_of(std::move(differences));
}

/// Integral-invariant input field of the experiment. For a shape without clipped axes: the II
/// normals of the digitized object. For a clipped shape (e.g. the plane in [-1,1]³), the box is
/// only there to make the object finite, so:
///  * a face on a clipped box wall gets the wall's normal, as in solid_exact_normals();
///  * every other face gets the II normal computed in the digitization of the same shape in a
///    box enlarged by r + 2h along the clipped axes, so that no ball sees the walls. (Measured on
///    the plane at h = 0.05: with balls truncated by the walls, the faces within r of the walls
///    get biased normals, and with α = 1e-5·h² the plane part drifts as a whole along its normal,
///    by about 0.55·h on average, farther than the digital surface; with exact normals on those
///    faces only, 0.006·h. See docs/convergence.md.)
/// Each face of the first kind is the same surfel (same voxel, same side) in both digitizations:
/// its voxel is inside both, and the voxel across it is outside because F > 0 there.
PointMatrix integral_invariant_input(const ImplicitShape& shape, const BinaryVolume& volume, const DigitalSurface& surface,
                                     double radius, const ConvergenceOptions& options, double h) {
    const auto field = [&](const BinaryVolume& v, const DigitalSurface& s) {
        return options.ii_extrapolate ? extrapolated_integral_invariant_normals(v, s, radius, options.ii_kernel)
                                      : integral_invariant_normals(v, s, radius, options.ii_kernel);
    };
    if (!(shape.clipped[0] || shape.clipped[1] || shape.clipped[2])) return field(volume, surface);
    ImplicitShape unclipped = shape;
    for (int a = 0; a < 3; ++a)
        if (shape.clipped[std::size_t(a)]) unclipped.lower[a] -= radius + 2 * h, unclipped.upper[a] += radius + 2 * h;
    const BinaryVolume wide = digitize(unclipped, h);
    const DigitalSurface wide_surface = extract_digital_surface(wide, options.connectivity);
    const PointMatrix wide_u = field(wide, wide_surface);

    // Surfel key: voxel index in the wide grid, axis and side.
    const auto key = [&](std::int64_t i, std::int64_t j, std::int64_t k, int axis, int sign) {
        return ((std::uint64_t(i) * std::uint64_t(wide.grid.dims[1]) + std::uint64_t(j)) * std::uint64_t(wide.grid.dims[2]) +
                std::uint64_t(k)) * 6u + std::uint64_t(2 * axis + (sign > 0 ? 1 : 0));
    };
    std::unordered_map<std::uint64_t, std::int64_t> wide_face;
    wide_face.reserve(std::size_t(wide_surface.face_count()));
    for (std::int64_t f = 0; f < wide_surface.face_count(); ++f) {
        const Surfel& s = wide_surface.surfels[std::size_t(f)];
        wide_face.emplace(key(s.voxel[0], s.voxel[1], s.voxel[2], s.axis, s.sign), f);
    }
    PointMatrix u(surface.face_count(), 3);
    for (std::int64_t f = 0; f < surface.face_count(); ++f) {
        const Surfel& s = surface.surfels[std::size_t(f)];
        if (is_box_wall_face(shape, surface.grid, s)) {
            u.row(f) = s.trivial_normal().transpose();
            continue;
        }
        const Eigen::Vector3d centre = surface.grid.voxel_center(s.voxel[0], s.voxel[1], s.voxel[2]);
        const Eigen::Vector3d index = ((centre - wide.grid.origin).array() / h).round().matrix();
        const auto found = wide_face.find(key(std::int64_t(index[0]), std::int64_t(index[1]), std::int64_t(index[2]), s.axis, s.sign));
        if (found == wide_face.end())
            throw Error("convergence: internal error: a face of '" + shape.name + "' at h = " + std::to_string(h) +
                        " has no counterpart in the digitization of the enlarged box");
        u.row(f) = wide_u.row(found->second);
    }
    return u;
}

}  // namespace

PointMatrix solid_exact_normals(const ImplicitShape& shape, const DigitalSurface& surface) {
    const PointMatrix centers = surfel_centers(surface);
    PointMatrix u(surface.face_count(), 3);
    detail::parallel_for_checked(surface.face_count(), [&](std::int64_t f) {
        const Surfel& s = surface.surfels[std::size_t(f)];
        if (is_box_wall_face(shape, surface.grid, s)) u.row(f) = s.trivial_normal().transpose();
        else u.row(f) = true_normal(shape, closest_point(shape, centers.row(f).transpose())).transpose();
    });
    return u;
}

ConvergenceStep run_convergence_step(const ImplicitShape& shape, double h, const ConvergenceOptions& options) {
    check_options(options);
    const auto started = std::chrono::steady_clock::now();
    ConvergenceStep step;
    step.h = h;
    const BinaryVolume volume = digitize(shape, h);
    if (volume.object_voxel_count() == 0)
        throw Error("convergence: the digitization of '" + shape.name + "' at h = " + std::to_string(h) + " is empty");
    const DigitalSurface surface = extract_digital_surface(volume, options.connectivity);
    step.faces = surface.face_count();
    step.vertices = surface.vertex_count();

    PointMatrix u;
    if (options.normals == InputNormalField::IntegralInvariant) {
        step.radius = options.radius_k * std::cbrt(h);
        u = integral_invariant_input(shape, volume, surface, step.radius, options, h);
    } else {
        u = solid_exact_normals(shape, surface);
    }

    step.alpha = options.alpha_k * h * h;
    RegularizationWeights weights;
    weights.alpha = step.alpha;
    weights.beta = options.beta;
    weights.gamma = options.gamma;
    const RegularizationResult result = regularize(surface, u, weights, options.solver);
    step.relative_residual = result.solve.relative_residual;

    measure_vertices(shape, surface.vertices, result.positions, options.wall_margin, step);
    measure_faces(shape, surface, u, result.positions, options.wall_margin, step);
    step.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
    return step;
}

ConvergenceSlopes convergence_slopes(const std::vector<ConvergenceStep>& steps) {
    std::vector<double> h;
    for (const ConvergenceStep& s : steps) h.push_back(s.h);
    auto slope = [&](auto member) {
        std::vector<double> y;
        for (const ConvergenceStep& s : steps) y.push_back(member(s));
        return log_log_slope(h, y);
    };
    ConvergenceSlopes slopes;
    slopes.normal = {slope([](const ConvergenceStep& s) { return s.normal.l2; }),
                     slope([](const ConvergenceStep& s) { return s.normal.linf; })};
    slopes.p = {slope([](const ConvergenceStep& s) { return s.p.l2; }), slope([](const ConvergenceStep& s) { return s.p.linf; })};
    slopes.pstar = {slope([](const ConvergenceStep& s) { return s.pstar.l2; }),
                    slope([](const ConvergenceStep& s) { return s.pstar.linf; })};
    slopes.ratio = {slope([](const ConvergenceStep& s) { return s.ratio.l2; }),
                    slope([](const ConvergenceStep& s) { return s.ratio.linf; })};
    return slopes;
}

}  // namespace dsreg
