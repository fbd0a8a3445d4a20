#include "dsreg/regularization.hpp"

namespace dsreg {

RegularizationResult regularize(const DigitalSurface& surface, const PointMatrix& normals,
                                const RegularizationWeights& weights, const SolverOptions& solver) {
    const VertexLinks links = vertex_links(surface.quads, surface.vertex_count());
    const RegularizationSystem system =
        assemble_regularization_system(surface.vertices, surface.quads, links, normals, weights);
    Eigen::VectorXd x = flatten_points(surface.vertices);  // warm start at p
    RegularizationResult result;
    result.solve = solve_spd(system.matrix, system.rhs, x, solver);
    result.positions = unflatten_points(x);
    result.energy_before = regularization_energy(surface.vertices, surface.vertices, surface.quads, links, normals, weights);
    result.energy_after = regularization_energy(result.positions, surface.vertices, surface.quads, links, normals, weights);
    return result;
}

}  // namespace dsreg
