// Google Benchmark of the Ambrosio–Tortorelli normals (--normals at) on the cases of
// docs/ambrosio-tortorelli.md: goursat at h = 0.25 and h = 0.1 (236K surfels: the target case)
// and bunny-128.vol when ../shared/data is present. The input field (integral invariants, the
// CLI's default radius) is computed once, outside the timing; one iteration is the whole AT
// schedule, with per-ε rounds and seconds as counters.
//
//   build/release/bench/dsreg_bench_at --benchmark_filter=Goursat/10
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <string>

#include "dsreg/ambrosio_tortorelli.hpp"
#include "dsreg/digital_surface.hpp"
#include "dsreg/implicit_shape.hpp"
#include "dsreg/normals.hpp"
#include "dsreg/volume_io.hpp"

#ifndef DSREG_SHARED_DATA_DIR
#define DSREG_SHARED_DATA_DIR "../shared/data"
#endif

namespace {

using namespace dsreg;

/// Surface and input field of one case, built once.
struct Case {
    DigitalSurface surface;
    PointMatrix input;
};

Case make_case(const BinaryVolume& volume, double radius) {
    Case c;
    c.surface = extract_digital_surface(volume, Connectivity::TwentySix);
    c.input = integral_invariant_normals(volume, c.surface, radius);
    return c;
}

const Case& goursat_case(double h) {
    static std::map<double, Case> cases;
    auto it = cases.find(h);
    if (it == cases.end()) it = cases.emplace(h, make_case(digitize(make_shape("goursat"), h), 3.0 * std::cbrt(h))).first;
    return it->second;
}

/// Runs the schedule once per iteration and reports rounds and seconds per ε level.
void run_at(benchmark::State& state, const Case& c) {
    const AmbrosioTortorelliParameters parameters;
    for (auto _ : state) {
        const AmbrosioTortorelliResult r = ambrosio_tortorelli_normals(c.surface, c.input, parameters);
        benchmark::DoNotOptimize(r.normals.data());
        for (const AtLevelReport& level : r.levels) {
            char name[32];
            std::snprintf(name, sizeof name, "eps%g_rounds", level.epsilon);
            state.counters[name] = level.rounds;
            std::snprintf(name, sizeof name, "eps%g_s", level.epsilon);
            state.counters[name] = level.seconds;
        }
        state.counters["rounds"] = r.total_rounds();
        state.counters["s_per_round"] = r.seconds / r.total_rounds();
        state.counters["factorizations"] = r.solves.factorizations;
        state.counters["refined_solves"] = r.solves.refined_solves;
        state.counters["max_residual"] = std::max(r.max_u_residual, r.max_v_residual);
    }
    state.counters["surfels"] = double(c.surface.face_count());
    state.counters["vertices"] = double(c.surface.vertex_count());
}

void BM_AtGoursat(benchmark::State& state) { run_at(state, goursat_case(state.range(0) / 100.0)); }

void BM_AtBunny128(benchmark::State& state) {
    const std::string path = std::string(DSREG_SHARED_DATA_DIR) + "/bunny-128.vol";
    if (!std::filesystem::exists(path)) {
        state.SkipWithError("bunny-128.vol not found (../shared/data)");
        return;
    }
    static const Case bunny = make_case(read_volume(path), 3.0);
    run_at(state, bunny);
}

}  // namespace

BENCHMARK(BM_AtGoursat)->Arg(25)->Arg(10)->Unit(benchmark::kSecond)->Iterations(1)->UseRealTime();
BENCHMARK(BM_AtBunny128)->Unit(benchmark::kSecond)->Iterations(1)->UseRealTime();

BENCHMARK_MAIN();
