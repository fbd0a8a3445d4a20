// Google Benchmark programs for each stage of the pipeline, on goursat at h = 0.25 (the issue's
// reference case), on bunny-128.vol when ../shared/data is present, and on spheres of growing
// size for the growth of time with the number of surfels.
//
//   build/release/bench/dsreg_bench --benchmark_filter=Goursat
#include <benchmark/benchmark.h>

#include <filesystem>
#include <map>

#include "dsreg/digital_surface.hpp"
#include "dsreg/implicit_shape.hpp"
#include "dsreg/local_reach.hpp"
#include "dsreg/normals.hpp"
#include "dsreg/regularization.hpp"
#include "dsreg/volume_io.hpp"

#ifndef DSREG_SHARED_DATA_DIR
#define DSREG_SHARED_DATA_DIR "../shared/data"
#endif

namespace {

using namespace dsreg;

/// Volume, surface and II normals of one benchmark case, computed once.
struct Case {
    BinaryVolume volume;
    DigitalSurface surface;
    PointMatrix normals;
    double radius = 0;
};

const Case& goursat_case(double h) {
    static std::map<double, Case> cases;
    auto it = cases.find(h);
    if (it == cases.end()) {
        Case c;
        c.volume = digitize(make_shape("goursat"), h);
        c.surface = extract_digital_surface(c.volume, Connectivity::TwentySix);
        c.radius = 3.0 * std::cbrt(h);  // r = k·h^(1/3), k = 3: 7.56 voxels at h = 0.25
        c.normals = integral_invariant_normals(c.volume, c.surface, c.radius);
        it = cases.emplace(h, std::move(c)).first;
    }
    return it->second;
}

void report_size(benchmark::State& state, const DigitalSurface& s) {
    state.counters["surfels"] = double(s.face_count());
    state.counters["vertices"] = double(s.vertex_count());
}

void BM_GoursatDigitize(benchmark::State& state) {
    const double h = state.range(0) / 100.0;
    const ImplicitShape shape = make_shape("goursat");
    for (auto _ : state) benchmark::DoNotOptimize(digitize(shape, h).mask.data());
}

void BM_GoursatSurface(benchmark::State& state) {
    const Case& c = goursat_case(state.range(0) / 100.0);
    for (auto _ : state) benchmark::DoNotOptimize(extract_digital_surface(c.volume, Connectivity::TwentySix).quads.data());
    report_size(state, c.surface);
}

void BM_GoursatIntegralInvariants(benchmark::State& state) {
    const Case& c = goursat_case(state.range(0) / 100.0);
    for (auto _ : state) benchmark::DoNotOptimize(integral_invariant_normals(c.volume, c.surface, c.radius).data());
    report_size(state, c.surface);
}

/// The distance maps of the thin-part weights at the pipeline's default cap (a reference reach
/// of 12 voxels plus one): the object and the background, on the grid grown by the cap.
void BM_GoursatReachMaps(benchmark::State& state) {
    const Case& c = goursat_case(state.range(0) / 100.0);
    const double cap = 13.0 * c.volume.grid.spacing.maxCoeff();
    for (auto _ : state) benchmark::DoNotOptimize(reach_maps(c.volume, cap).distance.data());
    state.counters["voxels"] = double(c.volume.grid.voxel_count());
}

void BM_GoursatAssembly(benchmark::State& state) {
    const Case& c = goursat_case(state.range(0) / 100.0);
    const VertexLinks links = vertex_links(c.surface.quads, c.surface.vertex_count());
    for (auto _ : state) {
        const RegularizationSystem s =
            assemble_regularization_system(c.surface.vertices, c.surface.quads, links, c.normals, RegularizationWeights{});
        benchmark::DoNotOptimize(s.matrix.valuePtr());
        state.counters["nonzeros"] = double(s.matrix.nonZeros());
    }
    report_size(state, c.surface);
}

void BM_GoursatSolve(benchmark::State& state, SolverKind kind) {
    const Case& c = goursat_case(state.range(0) / 100.0);
    const VertexLinks links = vertex_links(c.surface.quads, c.surface.vertex_count());
    const RegularizationSystem s =
        assemble_regularization_system(c.surface.vertices, c.surface.quads, links, c.normals, RegularizationWeights{});
    SolverOptions options;
    options.kind = kind;
    options.tolerance = 1e-8;
    for (auto _ : state) {
        Eigen::VectorXd x = flatten_points(c.surface.vertices);
        const SolveReport r = solve_spd(s.matrix, s.rhs, x, options);
        state.counters["residual"] = r.relative_residual;
        state.counters["iterations"] = r.iterations;
        state.counters["factor_nnz"] = r.factor_nonzeros;
    }
    report_size(state, c.surface);
}

/// Whole library pipeline (no file I/O) on a digitized ball of radius R voxels.
void BM_BallPipeline(benchmark::State& state) {
    const double h = 1.0 / double(state.range(0));
    const ImplicitShape sphere = make_shape("sphere1");
    for (auto _ : state) {
        const BinaryVolume v = digitize(sphere, h);
        const DigitalSurface s = extract_digital_surface(v, Connectivity::TwentySix);
        const PointMatrix u = integral_invariant_normals(v, s, 3.0 * h);
        const RegularizationResult r = regularize(s, u, RegularizationWeights{}, SolverOptions{});
        benchmark::DoNotOptimize(r.positions.data());
        report_size(state, s);
    }
}

void BM_BunnyPipeline(benchmark::State& state) {
    const std::string path = std::string(DSREG_SHARED_DATA_DIR) + "/bunny-128.vol";
    if (!std::filesystem::exists(path)) {
        state.SkipWithError("bunny-128.vol not found (../shared/data)");
        return;
    }
    for (auto _ : state) {
        const BinaryVolume v = read_vol(path);
        const DigitalSurface s = extract_digital_surface(v, Connectivity::TwentySix);
        const PointMatrix u = integral_invariant_normals(v, s, 6.0);
        const RegularizationResult r = regularize(s, u, RegularizationWeights{}, SolverOptions{});
        benchmark::DoNotOptimize(r.positions.data());
        report_size(state, s);
    }
}

}  // namespace

BENCHMARK(BM_GoursatDigitize)->Arg(25)->Arg(10)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_GoursatSurface)->Arg(25)->Arg(10)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_GoursatIntegralInvariants)->Arg(25)->Arg(10)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_GoursatReachMaps)->Arg(10)->Arg(5)->Unit(benchmark::kMillisecond)->Iterations(3);
BENCHMARK(BM_GoursatAssembly)->Arg(25)->Arg(10)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_GoursatSolve, cholmod, dsreg::SolverKind::Cholmod)->Arg(25)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_GoursatSolve, cg, dsreg::SolverKind::ConjugateGradient)->Arg(25)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_BallPipeline)->RangeMultiplier(2)->Range(16, 128)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_BunnyPipeline)->Unit(benchmark::kMillisecond)->Iterations(1);

BENCHMARK_MAIN();
