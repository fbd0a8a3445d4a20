// Google Benchmark comparison of the solvers of R x = b (eq. 22–23) on goursat, with the paper's
// weights (α = 1e-3, β = 1, γ = 1e-2) and with those of its Fig. 7 (α = 1e-5·h², β = 1, γ = 0).
// Argument: 100·h. Options as the dsreg command sets them (iterative solvers stop once their error
// bound is 5e-5 voxel). Counters: iterations, relative residual, error bound and largest vertex
// distance to the reference solution in voxels (max_diff_voxels), levels and operator complexity of amg.
//
//   build/bench/dsreg_bench_solvers --benchmark_filter='Paper/.*/25'
//
// The reference is CHOLMOD's solution, or at h = 0.05 (where CHOLMOD needs more memory than the
// machine should give it) amg's with tolerance 1e-13. Each benchmark runs once: a solve at
// h = 0.05 takes tens of seconds.
#include <benchmark/benchmark.h>

#include <cmath>
#include <map>

#include "dsreg/digital_surface.hpp"
#include "dsreg/implicit_shape.hpp"
#include "dsreg/normals.hpp"
#include "dsreg/regularization.hpp"
#include "dsreg/solvers.hpp"

namespace {

using namespace dsreg;

enum class Weights { Paper, Fig7 };

struct Case {
    RegularizationSystem system;
    Eigen::VectorXd initial;  ///< p, the warm start
    Eigen::VectorXd reference;
    double spacing = 0;
    double surfels = 0;
};

RegularizationWeights weights_for(Weights w, double h) {
    if (w == Weights::Fig7) return RegularizationWeights{1e-5 * h * h, 1.0, 0.0, {}, {}};
    return RegularizationWeights{};
}

const Case& goursat_case(Weights weights, int h_percent) {
    static std::map<std::pair<Weights, int>, Case> cases;
    const auto key = std::make_pair(weights, h_percent);
    auto it = cases.find(key);
    if (it != cases.end()) return it->second;
    const double h = h_percent / 100.0;
    const BinaryVolume volume = digitize(make_shape("goursat"), h);
    const DigitalSurface surface = extract_digital_surface(volume, Connectivity::TwentySix);
    const PointMatrix normals = integral_invariant_normals(volume, surface, 3.0 * std::cbrt(h));
    const VertexLinks links = vertex_links(surface.quads, surface.vertex_count());
    Case c;
    RegularizationSystem system = assemble_regularization_system(surface.vertices, surface.quads, links, normals, weights_for(weights, h));
    c.system.matrix.swap(system.matrix);  // (Eigen 3.4's SparseMatrix has no move assignment)
    c.system.rhs.swap(system.rhs);
    c.initial = flatten_points(surface.vertices);
    c.spacing = h;
    c.surfels = double(surface.face_count());
    SolverOptions reference;
    reference.kind = h_percent >= 10 ? SolverKind::Cholmod : SolverKind::Amg;
    reference.tolerance = 1e-13;
    c.reference = c.initial;
    solve_spd(c.system.matrix, c.system.rhs, c.reference, reference);
    return cases.emplace(key, std::move(c)).first->second;
}

double max_diff_voxels(const Case& c, const Eigen::VectorXd& x) {
    double largest = 0;
    for (Eigen::Index i = 0; i < x.size() / 3; ++i) largest = std::max(largest, (x.segment<3>(3 * i) - c.reference.segment<3>(3 * i)).norm());
    return largest / c.spacing;
}

void BM_Solve(benchmark::State& state, Weights weights, SolverKind kind) {
    const Case& c = goursat_case(weights, int(state.range(0)));
    SolverOptions options;  // as the dsreg command: iterative solvers stop within 5e-5 voxel (error bound)
    options.kind = kind;
    options.smallest_eigenvalue = weights_for(weights, c.spacing).alpha;
    options.max_error = kDefaultMaxErrorVoxels * c.spacing;
    for (auto _ : state) {
        Eigen::VectorXd x = c.initial;
        const SolveReport r = solve_spd(c.system.matrix, c.system.rhs, x, options);
        state.counters["iterations"] = r.iterations;
        state.counters["residual"] = r.relative_residual;
        state.counters["error_bound_voxels"] = r.error_bound / c.spacing;
        state.counters["max_diff_voxels"] = max_diff_voxels(c, x);
        state.counters["levels"] = r.multigrid_levels;
        state.counters["op_complexity"] = r.operator_complexity;
        state.counters["factor_nnz"] = r.factor_nonzeros;
        state.counters["used_amg"] = r.solver == "amg";
    }
    state.counters["surfels"] = c.surfels;
    state.counters["nonzeros"] = double(c.system.matrix.nonZeros());
}

}  // namespace

// Paper weights: the growth series (37.6K, 236K, ~10^6 surfels).
BENCHMARK_CAPTURE(BM_Solve, Paper/cholmod, Weights::Paper, SolverKind::Cholmod)->Arg(25)->Arg(10)->Unit(benchmark::kMillisecond)->Iterations(1);
BENCHMARK_CAPTURE(BM_Solve, Paper/amg, Weights::Paper, SolverKind::Amg)->Arg(25)->Arg(10)->Arg(5)->Unit(benchmark::kMillisecond)->Iterations(1);
BENCHMARK_CAPTURE(BM_Solve, Paper/cg, Weights::Paper, SolverKind::ConjugateGradient)->Arg(25)->Arg(10)->Unit(benchmark::kMillisecond)->Iterations(1);
BENCHMARK_CAPTURE(BM_Solve, Paper/auto, Weights::Paper, SolverKind::Auto)->Arg(25)->Arg(10)->Arg(5)->Unit(benchmark::kMillisecond)->Iterations(1);
// Fig. 7 weights (tiny α): amg is slow there, auto takes CHOLMOD.
BENCHMARK_CAPTURE(BM_Solve, Fig7/cholmod, Weights::Fig7, SolverKind::Cholmod)->Arg(25)->Arg(10)->Unit(benchmark::kMillisecond)->Iterations(1);
BENCHMARK_CAPTURE(BM_Solve, Fig7/amg, Weights::Fig7, SolverKind::Amg)->Arg(25)->Unit(benchmark::kMillisecond)->Iterations(1);
BENCHMARK_CAPTURE(BM_Solve, Fig7/auto, Weights::Fig7, SolverKind::Auto)->Arg(25)->Arg(10)->Unit(benchmark::kMillisecond)->Iterations(1);

BENCHMARK_MAIN();
