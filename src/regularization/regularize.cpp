#include <algorithm>
#include <chrono>
#include <cmath>

#include "dsreg/label_surface.hpp"
#include "dsreg/regularization.hpp"
#include "mesh_parts.hpp"
#include "spd_system.hpp"

namespace dsreg {

namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

/// The solver of a part: the batches of small components go to CHOLMOD whatever the choice.
SolverOptions part_options(const SolverOptions& options, const detail::MeshPart& part) {
    SolverOptions o = options;
    if (part.small) o.kind = SolverKind::Cholmod;
    return o;
}

/// The reports of the parts as one: the largest part's solver and work, the largest error bound
/// (each part's bounds every vertex of that part), the residual of the whole system.
struct MergedReport {
    SolveReport report;
    double residual_squared = 0, rhs_squared = 0;
    std::int64_t small_components = 0;
    bool first = true;

    void add(const SolveReport& r, const detail::MeshPart& part, double residual_norm, double rhs_norm) {
        residual_squared += residual_norm * residual_norm;
        rhs_squared += rhs_norm * rhs_norm;
        report.factor_nonzeros += r.factor_nonzeros;
        report.error_bound = std::max(report.error_bound, r.error_bound);
        if (part.small) small_components += part.components;
        if (first) {
            const double factor = report.factor_nonzeros, bound = report.error_bound;
            report = r;
            report.factor_nonzeros = factor;
            report.error_bound = bound;
            first = false;
        } else {
            report.iterations = std::max(report.iterations, r.iterations);
        }
    }

    SolveReport finish() {
        const double norm_b = std::sqrt(rhs_squared), norm_r = std::sqrt(residual_squared);
        report.relative_residual = norm_b > 0 ? norm_r / norm_b : norm_r;
        if (small_components > 0) {
            const std::string note = std::to_string(small_components) + " small component" + (small_components > 1 ? "s" : "") +
                                     " (at most " + std::to_string(detail::kSmallComponentVertices) + " vertices) solved directly";
            report.note = report.note.empty() ? note : report.note + "; " + note;
        }
        return report;
    }
};

}  // namespace

RegularizationResult regularize(const DigitalSurface& surface, const PointMatrix& normals,
                                const RegularizationWeights& weights, const SolverOptions& solver) {
    const std::int64_t n = surface.vertex_count();
    validate_weights(weights, n, surface.face_count());
    if (normals.rows() != surface.face_count())
        throw Error("normal field has " + std::to_string(normals.rows()) + " vectors for " + std::to_string(surface.face_count()) + " faces");
    RegularizationResult result;
    const SolverOptions options = detail::completed_options(solver, weights, n, surface.grid.spacing.minCoeff());

    auto started = Clock::now();
    const VertexLinks links = fairness_links(surface);  // junction-aware on a label complex
    const std::vector<detail::MeshPart> parts =
        detail::mesh_parts(surface.quads, links, n, detail::kSmallComponentVertices, detail::kBatchVertices);
    result.assembly_seconds = seconds_since(started);
    // The solution, made after the first part's solve (the largest: not beside its multigrid
    // hierarchy); the vertices of the parts not solved yet keep p.
    Eigen::VectorXd x;
    MergedReport merged;
    double done = 0;
    for (const detail::MeshPart& part : parts) {
        SolverOptions o = part_options(options, part);
        const double share = double(part.vertices.size()) / double(std::max<std::int64_t>(n, 1));
        o.progress = detail::progress_share(options.progress, done, share);
        detail::visit_part(part, surface.vertices, surface.quads, links, normals, weights, [&](const detail::PartView& mesh) {
            started = Clock::now();
            Eigen::VectorXd local = flatten_points(mesh.positions);  // warm start at p
            const detail::MeshSystem system(mesh.positions, mesh.quads, mesh.links, mesh.normals, mesh.weights);
            result.assembly_seconds += seconds_since(started);
            started = Clock::now();
            const SolveReport r = detail::solve_system(system.system(), system.rhs(), local, o);
            result.solve_seconds += seconds_since(started);
            if (x.size() == 0) x = flatten_points(surface.vertices);
            detail::scatter_part(part, local, x);
            const double rhs_norm = system.rhs().norm();
            merged.add(r, part, r.relative_residual * (rhs_norm > 0 ? rhs_norm : 1.0), rhs_norm);
        });
        done += share;
    }
    result.solve = merged.finish();
    result.positions = unflatten_points(x);
    result.energy_before = regularization_energy(surface.vertices, surface.vertices, surface.quads, links, normals, weights);
    result.energy_after = regularization_energy(result.positions, surface.vertices, surface.quads, links, normals, weights);
    return result;
}

}  // namespace dsreg
