#include "dsreg/regularization.hpp"

#include <chrono>

#include "dsreg/label_surface.hpp"

namespace dsreg {

RegularizationResult regularize(const DigitalSurface& surface, const PointMatrix& normals,
                                const RegularizationWeights& weights, const SolverOptions& solver) {
    using Clock = std::chrono::steady_clock;
    const auto seconds_since = [](Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); };
    RegularizationResult result;
    auto started = Clock::now();
    const VertexLinks links = fairness_links(surface);  // junction-aware on a label complex
    const RegularizationSystem system =
        assemble_regularization_system(surface.vertices, surface.quads, links, normals, weights);
    result.assembly_seconds = seconds_since(started);
    Eigen::VectorXd x = flatten_points(surface.vertices);  // warm start at p
    started = Clock::now();
    SolverOptions options = solver;
    if (!(options.smallest_eigenvalue > 0)) options.smallest_eigenvalue = smallest_eigenvalue_bound(weights, surface.vertex_count());
    if (options.max_error == 0 && options.max_error_voxels > 0)
        options.max_error = options.max_error_voxels * surface.grid.spacing.minCoeff();
    result.solve = solve_spd(system.matrix, system.rhs, x, options);
    result.solve_seconds = seconds_since(started);
    result.positions = unflatten_points(x);
    result.energy_before = regularization_energy(surface.vertices, surface.vertices, surface.quads, links, normals, weights);
    result.energy_after = regularization_energy(result.positions, surface.vertices, surface.quads, links, normals, weights);
    return result;
}

}  // namespace dsreg
