// Robustness of the default solver (amg under `auto`) on real volumes and on thin, noisy and
// strongly anisotropic cases: iterations, hierarchy, set-up and solve time of regularize(),
// with the dsreg command's settings (biweight integral invariants, r = 5 voxels for files; error
// bound 5e-5 voxel). One Markdown table row per case (docs/solvers.md).
//
//   build/bench/dsreg_bench_robustness [CASE-SUBSTRING...]
#include <sys/resource.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <random>
#include <string>
#include <vector>

#include "dsreg/digital_surface.hpp"
#include "dsreg/implicit_shape.hpp"
#include "dsreg/normals.hpp"
#include "dsreg/regularization.hpp"
#include "dsreg/volume_io.hpp"

// DSREG_SHARED_DATA_DIR: ../shared/data of the source tree (bench/CMakeLists.txt).

namespace {

using namespace dsreg;

struct Case {
    std::string name;
    std::function<BinaryVolume()> volume;
    double radius;         ///< integral-invariant radius, physical units (0: trivial normals)
};

double cpu_seconds() {
    rusage usage{};
    getrusage(RUSAGE_SELF, &usage);
    return double(usage.ru_utime.tv_sec + usage.ru_stime.tv_sec) + 1e-6 * double(usage.ru_utime.tv_usec + usage.ru_stime.tv_usec);
}

/// Flips each voxel next to the boundary with probability p (noisy segmentation).
BinaryVolume with_boundary_noise(BinaryVolume v, double p, unsigned seed) {
    std::mt19937 rng(seed);
    std::bernoulli_distribution flip(p);
    const Index3 d = v.grid.dims;
    const BinaryVolume original = v;
    for (std::int64_t k = 1; k + 1 < d[2]; ++k)
        for (std::int64_t j = 1; j + 1 < d[1]; ++j)
            for (std::int64_t i = 1; i + 1 < d[0]; ++i) {
                const auto at = [&](std::int64_t a, std::int64_t b, std::int64_t c) { return original.mask[std::size_t(original.grid.linear_index(a, b, c))]; };
                const std::uint8_t self = at(i, j, k);
                const bool boundary = at(i - 1, j, k) != self || at(i + 1, j, k) != self || at(i, j - 1, k) != self ||
                                      at(i, j + 1, k) != self || at(i, j, k - 1) != self || at(i, j, k + 1) != self;
                if (boundary && flip(rng)) v.mask[std::size_t(v.grid.linear_index(i, j, k))] = self ? 0 : 1;
            }
    return v;
}

std::vector<Case> cases() {
    std::vector<Case> all;
    for (const char* file : {"lobster.vol", "Al.100.vol", "bunny-64.vol", "bunny-128.vol", "cat10.vol"}) {
        const std::string path = std::string(DSREG_SHARED_DATA_DIR) + "/" + file;
        if (std::filesystem::exists(path)) all.push_back({file, [path] { return read_volume(path); }, 5.0});
    }
    const std::string lobster = std::string(DSREG_SHARED_DATA_DIR) + "/lobster.vol";
    if (std::filesystem::exists(lobster)) all.push_back({"lobster.vol, trivial normals", [lobster] { return read_volume(lobster); }, 0.0});
    all.push_back({"goursat h=0.25", [] { return digitize(make_shape("goursat"), 0.25); }, 1.89});
    all.push_back({"goursat h=0.25, trivial normals", [] { return digitize(make_shape("goursat"), 0.25); }, 0.0});
    all.push_back({"goursat h=0.25, 10% boundary noise", [] { return with_boundary_noise(digitize(make_shape("goursat"), 0.25), 0.1, 1); }, 1.89});
    all.push_back({"goursat h=0.1, 30% boundary noise", [] { return with_boundary_noise(digitize(make_shape("goursat"), 0.1), 0.3, 2); }, 1.39});
    all.push_back({"torus R=4 r=0.6 (2.4 voxels) h=0.25",
                   [] { return digitize(make_shape("(x^2+y^2+z^2+15.64)^2-64*(x^2+y^2)", 5.0), 0.25); }, 0.75});
    all.push_back({"thin tube R=4 r=0.375 (1.5 voxels) h=0.25",
                   [] { return digitize(make_shape("(x^2+y^2+z^2+15.859375)^2-64*(x^2+y^2)", 5.0), 0.25); }, 0.75});
    all.push_back({"plate 3 voxels thick h=0.05", [] { return digitize(make_shape("x^8+y^8+998872123*z^8-1", 1.2), 0.05); }, 0.15});
    all.push_back({"shell 2.4 voxels thick h=0.05",
                   [] { return digitize(make_shape("(x^2+y^2+z^2-1)^2-0.0144", 1.5), 0.05); }, 0.15});
    all.push_back({"leopold h=0.1", [] { return digitize(make_shape("leopold"), 0.1); }, 3 * std::cbrt(0.1)});
    return all;
}

}  // namespace

int main(int argc, char** argv) {
    std::printf("| case | surfels | components | solver | iterations | levels | operator complexity | error bound (voxel) | assembly s | solve s (wall) | solve CPU s |\n");
    std::printf("|---|---|---|---|---|---|---|---|---|---|---|\n");
    for (const Case& c : cases()) {
        bool wanted = argc < 2;
        for (int a = 1; a < argc; ++a) wanted = wanted || c.name.find(argv[a]) != std::string::npos;
        if (!wanted) continue;
        const BinaryVolume volume = c.volume();
        const DigitalSurface surface = extract_digital_surface(volume, Connectivity::TwentySix);
        const PointMatrix u = c.radius > 0 ? integral_invariant_normals(volume, surface, c.radius) : trivial_normals(surface);
        SolverOptions options;
        options.max_error_voxels = kDefaultMaxErrorVoxels;
        const double cpu = cpu_seconds();
        const RegularizationResult r = regularize(surface, u, RegularizationWeights{}, options);
        const double solve_cpu = cpu_seconds() - cpu;
        std::printf("| %s | %lld | %d | %s | %d | %d | %.2f | %.1e | %.3f | %.3f | %.3f |\n", c.name.c_str(),
                    static_cast<long long>(surface.face_count()), surface.component_count, r.solve.solver.c_str(), r.solve.iterations,
                    r.solve.multigrid_levels, r.solve.operator_complexity, r.solve.error_bound / volume.grid.spacing.minCoeff(),
                    r.assembly_seconds, r.solve_seconds, solve_cpu);
        std::fflush(stdout);
    }
    return 0;
}
