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
#include "held_solver.hpp"
#include "mesh_parts.hpp"
#include "spd_system.hpp"

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

namespace {

/// Whether a part is solved with CHOLMOD factorizations (small parts, --solver cholmod, or what
/// `auto` would factor: a small system or a tiny data weight).
bool direct_part(const detail::MeshPart& part, const detail::SpdSystem& system, SolverKind kind) {
    if (part.small || kind == SolverKind::Cholmod) return true;
    return kind == SolverKind::Auto && (system.unknowns() <= 1200 || system.data_weight_ratio() < 1e-6);
}

/// The box QP of one part, from its unconstrained minimizer (written to `unconstrained`).
BoxQpReport clamp_part(const detail::MeshPart& part, const detail::MeshSystem& mesh, const Eigen::VectorXd& lower,
                       const Eigen::VectorXd& upper, const BoxQpOptions& qp, const SolverOptions& solver,
                       Eigen::VectorXd& unconstrained, Eigen::VectorXd& x, SolveReport& solve) {
    const detail::OperatorSystem& system = mesh.system();
    const Eigen::VectorXd& b = mesh.rhs();
    if (!direct_part(part, system, solver.kind)) {
        const auto started = Clock::now();
        const std::unique_ptr<detail::Multigrid> amg = system.multigrid(detail::AmgSettings{});
        if (detail::solve_with_multigrid(system, *amg, b, unconstrained, solver, solver.max_iterations, solve)) {
            const double unconstrained_seconds = seconds_since(started);
            x = unconstrained;
            detail::IterativeHeldSolver held(system, *amg, solver.max_iterations);
            BoxQpReport report = detail::solve_box_qp_with(held, b, lower, upper, x, qp);
            report.unconstrained_seconds = unconstrained_seconds;
            return report;
        }
        if (solver.kind == SolverKind::Amg) throw Error("amg did not reach its accuracy on the unconstrained minimizer; use --solver cholmod");
        solve.note = "auto: amg did not converge, cholmod";  // auto falls back to the factorization
    }
    const BoxQpReport report = solve_box_qp_from_unconstrained(system.matrix(), b, lower, upper, unconstrained, x, qp);
    solve.solver = "cholmod";
    solve.iterations = 0;
    solve.factor_nonzeros = report.factor_nonzeros;
    return report;
}

/// The parts' QP reports as one: KKT figures of the whole system, counts and times summed,
/// iterations of the largest part (the first).
struct MergedQp {
    BoxQpReport report;
    double free_squared = 0, sign_squared = 0, rhs_squared = 0, unconstrained_squared = 0;
    bool first = true;
    int parts = 0;

    void add(const BoxQpReport& r, double rhs_norm, double unconstrained_residual) {
        ++parts;
        const double scale = rhs_norm > 0 ? rhs_norm : 1.0;
        free_squared += std::pow(r.stationarity * scale, 2);
        sign_squared += std::pow(r.multiplier_sign * scale, 2);
        rhs_squared += rhs_norm * rhs_norm;
        unconstrained_squared += std::pow(unconstrained_residual * scale, 2);
        if (first) {
            report.admm_iterations = r.admm_iterations;
            report.active_set_iterations = r.active_set_iterations;
            report.newton_iterations = r.newton_iterations;
            report.admm_rho = r.admm_rho;
            report.converged = r.converged;
            first = false;
        }
        report.converged = report.converged && r.converged;
        report.active_set_cycled = report.active_set_cycled || r.active_set_cycled;
        report.constraint_violation = std::max(report.constraint_violation, r.constraint_violation);
        report.at_lower += r.at_lower;
        report.at_upper += r.at_upper;
        report.factorizations += r.factorizations;
        report.cg_iterations += r.cg_iterations;
        report.factor_nonzeros += r.factor_nonzeros;
        report.admm_seconds += r.admm_seconds;
        report.active_set_seconds += r.active_set_seconds;
        report.unconstrained_seconds += r.unconstrained_seconds;
    }

    BoxQpReport finish() {
        const double scale = rhs_squared > 0 ? std::sqrt(rhs_squared) : 1.0;
        report.stationarity = std::sqrt(free_squared) / scale;
        report.multiplier_sign = std::sqrt(sign_squared) / scale;
        report.kkt_residual = std::sqrt(free_squared + sign_squared) / scale;
        report.unconstrained_residual = std::sqrt(unconstrained_squared) / scale;
        return report;
    }
};

}  // namespace

ClampedRegularizationResult regularize_clamped(const DigitalSurface& surface, const PointMatrix& normals,
                                               const RegularizationWeights& weights, const ClampOptions& options) {
    const std::int64_t n = surface.vertex_count();
    validate_weights(weights, n, surface.face_count());
    if (normals.rows() != surface.face_count())
        throw Error("normal field has " + std::to_string(normals.rows()) + " vectors for " + std::to_string(surface.face_count()) + " faces");
    ClampedRegularizationResult result;
    auto started = Clock::now();
    const VertexLinks links = fairness_links(surface);  // junction-aware on a label complex
    Eigen::VectorXd lower, upper;
    clamp_bounds(surface, options.half_width, lower, upper);
    const std::vector<detail::MeshPart> parts =
        detail::mesh_parts(surface.quads, links, n, detail::kSmallComponentVertices, detail::kBatchVertices);
    result.assembly_seconds = seconds_since(started);

    const SolverOptions solver = detail::completed_options(options.solver, weights, n, surface.grid.spacing.minCoeff());
    BoxQpOptions qp = options.qp;
    if (!(qp.smallest_eigenvalue_bound > 0)) qp.smallest_eigenvalue_bound = solver.smallest_eigenvalue;
    Eigen::VectorXd unconstrained = flatten_points(surface.vertices), x = unconstrained;  // warm start at p
    MergedQp merged;
    double done = 0, largest_residual = 0;
    for (const detail::MeshPart& part : parts) {
        const double share = double(part.vertices.size()) / double(std::max<std::int64_t>(n, 1));
        SolverOptions part_solver = part.small ? SolverOptions{} : solver;
        part_solver.progress = detail::progress_share(solver.progress, done, share);
        BoxQpOptions part_qp = qp;
        part_qp.progress = detail::progress_share(qp.progress, done, share);
        done += share;
        detail::visit_part(part, surface.vertices, surface.quads, links, normals, weights, [&](const detail::PartView& mesh) {
            started = Clock::now();
            const detail::MeshSystem system(mesh.positions, mesh.quads, mesh.links, mesh.normals, mesh.weights);
            Eigen::VectorXd part_unconstrained = detail::gather_part(part, unconstrained), part_x;
            const Eigen::VectorXd part_lower = detail::gather_part(part, lower), part_upper = detail::gather_part(part, upper);
            result.assembly_seconds += seconds_since(started);
            started = Clock::now();
            SolveReport solve;
            const BoxQpReport r = clamp_part(part, system, part_lower, part_upper, part_qp, part_solver, part_unconstrained, part_x, solve);
            result.solve_seconds += seconds_since(started);
            Eigen::VectorXd residual;
            system.system().multiply(part_unconstrained, residual);
            const double rhs_norm = system.rhs().norm();
            const double residual_norm = (residual - system.rhs()).norm();
            merged.add(r, rhs_norm, residual_norm / (rhs_norm > 0 ? rhs_norm : 1.0));
            largest_residual = std::max(largest_residual, residual_norm);
            if (merged.parts == 1) result.solve = solve;  // the largest part's solver
            detail::scatter_part(part, part_unconstrained, unconstrained);
            detail::scatter_part(part, part_x, x);
        });
    }
    result.clamp.qp = merged.finish();
    result.solve.error_bound = solver.smallest_eigenvalue > 0 ? largest_residual / solver.smallest_eigenvalue : -1.0;
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
