// Multi-label measurements behind docs/multi-label.md and docs/benchmarks.md.
//
//   dsreg_bench_labels accuracy [H ...]
//       The known partitions of label_shapes.hpp (sectors, layers, nested) at grid steps H
//       (default 1 0.5 0.25): distances of the vertices to the true interfaces and junction
//       curves (voxels) for the digital complex, the joint regularization as the pipeline runs it,
//       two alternatives of its design (integral invariants of the inner label everywhere;
//       quad links instead of junction-aware fairness), and dsreg run once per label (the
//       issue's baseline), with the share of interface vertices that neighbouring labels share.
//
//   dsreg_bench_labels repair [H ...]
//       The validity repair on the solved complex of sectors and layers (default H = 1 0.5): counts,
//       rounds, displacement of junction and other vertices, label volumes, junction accuracy.
//
//   dsreg_bench_labels folds PATH X,Y,Z [SHARE ...]
//       A uint16 .raw label map of dims X,Y,Z (e.g. the --input-file of blobs) solved without the
//       repair, for each --junction-turn-share (default 0 and the default): its folded and
//       intersecting faces by how many of their corners are junction vertices, and by whether a
//       corner is a held turn or a junction point (docs/multi-label.md).
//
//   dsreg_bench_labels blobs --labels N --dims X,Y,Z --radius R [--seed S] [--binary] [--out DIR]
//       A label map of N random blobs packed in a ball of radius R voxels (blob_values below),
//       written as a uint16 .raw file, then one run of the pipeline on it (read included) with
//       --multi-label; with --binary, the same blobs eroded where they touch, as one binary
//       object (value > 0): about as many faces, no shared interface. With --ball-faces F, one
//       binary ball of about F faces in the same grid instead (ball_values below). Prints one JSON line: counts, per-stage seconds, CPU
//       seconds, peak memory. With --out, also writes the meshes there (-o DIR/blobs.ply); with
//       --input-file PATH, keeps the generated volume there (X·Y·Z uint16, for slicer_pipeline.py).
#include <sys/resource.h>
#include <unistd.h>

#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <optional>
#include <random>
#include <set>
#include <string>
#include <vector>

#include "dsreg/adaptive_normals.hpp"
#include "dsreg/error.hpp"
#include "dsreg/label_evaluation.hpp"
#include "dsreg/label_shapes.hpp"
#include "dsreg/label_surface.hpp"
#include "dsreg/mesh_validity.hpp"
#include "dsreg/normals.hpp"
#include "dsreg/validity_repair.hpp"
#include "dsreg/pipeline.hpp"
#include "dsreg/regularization.hpp"
#include "dsreg/text.hpp"
#include "dsreg/volume_io.hpp"

namespace {

using namespace dsreg;

double cpu_seconds() {
    rusage usage{};
    getrusage(RUSAGE_SELF, &usage);
    return double(usage.ru_utime.tv_sec + usage.ru_stime.tv_sec) + 1e-6 * double(usage.ru_utime.tv_usec + usage.ru_stime.tv_usec);
}

// ---- accuracy --------------------------------------------------------------------------------

struct Row {
    std::string method;
    double all_mean = 0, all_p95 = 0, junction_mean = 0, junction_p95 = 0, shared = 0;
};

Row errors_row(const std::string& method, const LabelShape& shape, const DigitalSurface& surface, const PointMatrix& p,
               double h) {
    const LabelComplexErrors e = label_complex_errors(shape, surface, p);
    return {method, e.interfaces.mean / h, e.interfaces.p95 / h, e.junctions.mean / h, e.junctions.p95 / h, 1.0};
}

PointMatrix regularize_with(const DigitalSurface& surface, const VertexLinks& links, const PointMatrix& u, double gamma = 1e-2) {
    RegularizationWeights weights;
    weights.gamma = gamma;
    const RegularizationSystem system = assemble_regularization_system(surface.vertices, surface.quads, links, u, weights);
    Eigen::VectorXd x = flatten_points(surface.vertices);
    SolverOptions solver;
    solver.kind = SolverKind::Cholmod;
    solve_spd(system.matrix, system.rhs, x, solver);
    return unflatten_points(x);
}

/// dsreg once per label (its indicator as a binary volume, the same default field, adaptive, and
/// weights): the
/// distances of each label's vertices to its true interfaces, those at junction pointels of the
/// complex to the true junction curves, and how many interface vertices two neighbours share
/// (positions equal bit for bit).
Row separate_runs(const LabelShape& shape, const LabelVolume& labels, const DigitalSurface& complex,
                  const AdaptiveNormalOptions& field, double h) {
    std::map<std::array<std::int32_t, 3>, std::vector<std::int64_t>> junction_sets;
    const Junctions junctions = find_junctions(complex, complex_edges(complex));
    const auto sets = vertex_label_values(complex);
    for (std::int64_t v = 0; v < complex.vertex_count(); ++v)
        if (junctions.vertex[std::size_t(v)])
            junction_sets[{complex.vertex_pointels(v, 0), complex.vertex_pointels(v, 1), complex.vertex_pointels(v, 2)}] = sets[std::size_t(v)];
    std::vector<double> all, at_junctions;
    std::map<std::array<std::int32_t, 3>, std::vector<std::array<double, 3>>> interface_positions;  // pointel → positions
    for (std::uint32_t label = 1; label < labels.values.size(); ++label) {
        BinaryVolume indicator;
        indicator.grid = labels.grid;
        indicator.mask.resize(labels.labels.size());
        for (std::size_t q = 0; q < labels.labels.size(); ++q) indicator.mask[q] = labels.labels[q] == label;
        const DigitalSurface s = extract_digital_surface(indicator, Connectivity::TwentySix);
        const PointMatrix p = regularize_with(s, vertex_links(s.quads, s.vertex_count()),
                                              adaptive_integral_invariant_normals(indicator, s, field).normals);
        const std::int64_t value = labels.values[label];
        for (std::int64_t v = 0; v < s.vertex_count(); ++v) {
            const Eigen::Vector3d x = p.row(v).transpose();
            double best = std::numeric_limits<double>::infinity();
            for (std::int64_t other = 0; other < std::int64_t(labels.values.size()); ++other)
                if (other != value) best = std::min(best, shape.distance(x, {std::min(other, value), std::max(other, value)}));
            all.push_back(best / h);
            const std::array<std::int32_t, 3> pointel{s.vertex_pointels(v, 0), s.vertex_pointels(v, 1), s.vertex_pointels(v, 2)};
            const auto it = junction_sets.find(pointel);
            if (it != junction_sets.end()) at_junctions.push_back(shape.distance(x, it->second) / h);
            interface_positions[pointel].push_back({x.x(), x.y(), x.z()});
        }
    }
    // Pointels on an interface between two labels appear in two runs: do their positions agree?
    std::int64_t shared = 0, candidates = 0;
    for (const auto& [pointel, positions] : interface_positions) {
        if (positions.size() < 2) continue;
        ++candidates;
        shared += positions[0] == positions[1];
    }
    const ErrorStats a = error_stats(all), j = error_stats(at_junctions);
    return {"dsreg once per label", a.mean, a.p95, j.mean, j.p95, candidates ? double(shared) / double(candidates) : 0.0};
}

LoadedVolume digitized_shape(const LabelShape& shape, const std::string& name, double h) {
    LoadedVolume loaded;
    loaded.labels = digitize_labels(shape, h);
    loaded.volume.grid = loaded.labels->grid;
    loaded.description = name;
    loaded.h = h;
    return loaded;
}

int accuracy(const std::vector<double>& steps) {
    std::printf("| shape | h (ball radius) | faces | junction vertices | method | all: mean | p95 | junctions: mean | p95 | shared |\n");
    std::printf("|---|---|---|---|---|---|---|---|---|---|\n");
    for (const std::string& name : label_shape_names())
        for (const double h : steps) {
            const LabelShape shape = make_label_shape(name);
            const LoadedVolume loaded = digitized_shape(shape, name, h);
            PipelineOptions options;
            options.solver = SolverKind::Cholmod;
            const PipelineResult result = run_pipeline(loaded, options);
            const DigitalSurface& s = result.surface;
            std::vector<Row> rows;
            rows.push_back(errors_row("digital surface", shape, s, s.vertices, h));
            rows.push_back(errors_row("**joint (default)**", shape, s, result.regularization.positions, h));
            PipelineOptions chords = options;  // the turns of junction curves not held outside their chords
            chords.extensions.junction_turn_share = 0.0;
            rows.push_back(errors_row("joint, --junction-turn-share 0", shape, s, run_pipeline(loaded, chords).regularization.positions, h));
            const PointMatrix& indicator_ii = result.field.adaptive->normals;  // before the interface normals
            rows.push_back(errors_row("joint, II of the inner label everywhere", shape, s, regularize_with(s, fairness_links(s), indicator_ii), h));
            rows.push_back(errors_row("joint, quad links (no junction fairness)", shape, s,
                                      regularize_with(s, vertex_links(s.quads, s.vertex_count()), result.field.normals), h));
            for (const double gamma : {0.1, 1.0}) {
                const std::string g = ", γ = " + format("%g", gamma);
                rows.push_back(errors_row("joint" + g, shape, s, regularize_with(s, fairness_links(s), result.field.normals, gamma), h));
                rows.push_back(errors_row("joint, quad links" + g, shape, s,
                                          regularize_with(s, vertex_links(s.quads, s.vertex_count()), result.field.normals, gamma), h));
            }
            rows.push_back(separate_runs(shape, *loaded.labels, s, default_adaptive_options(options.normals, loaded), h));
            for (const Row& r : rows)
                std::printf("| %s | %g (%g voxels) | %lld | %lld | %s | %.3f | %.3f | %.3f | %.3f | %.0f %% |\n", name.c_str(), h, 10 / h,
                            (long long)s.face_count(), (long long)result.junctions.vertex_count, r.method.c_str(), r.all_mean,
                            r.all_p95, r.junction_mean, r.junction_p95, 100 * r.shared);
            std::fflush(stdout);
        }
    return 0;
}

// ---- folds -----------------------------------------------------------------------------------

int folds(const std::string& path, const Index3& dims, std::vector<std::optional<double>> shares) {
    RawVolumeLayout layout;
    layout.dims = dims;
    layout.type = RawVoxelType::UInt16;
    LoadedVolume loaded;
    loaded.labels = read_label_volume(path, &layout);
    loaded.volume.grid = loaded.labels->grid;
    loaded.description = path;
    loaded.h = 1;
    if (shares.empty()) shares = {0.0, std::nullopt};
    std::printf("| share | junction corners | faces | folded | intersecting | folded with a held turn | folded with a junction point |\n");
    std::printf("|---|---|---|---|---|---|---|\n");
    for (const std::optional<double>& share : shares) {
        PipelineOptions options;
        options.validity = ValidityMode::Check;
        options.extensions.junction_turn_share = share;
        const PipelineResult r = run_pipeline(loaded, options);
        const DigitalSurface& s = r.surface;
        const ComplexEdges edges = complex_edges(s);
        const Junctions junctions = find_junctions(s, edges);
        const std::vector<char> turn = junction_turn_vertices(s, edges);
        std::vector<char> folded(std::size_t(s.face_count()), 0), crossing(folded.size(), 0);
        for (const std::int32_t f : r.validity->before.folded) folded[std::size_t(f)] = 1;
        for (const std::int32_t f : r.validity->before.intersecting_faces) crossing[std::size_t(f)] = 1;
        std::array<std::int64_t, 5> faces{}, fold{}, cross{}, with_turn{}, with_point{};
        for (std::int64_t f = 0; f < s.face_count(); ++f) {
            int corners = 0;
            bool has_turn = false, has_point = false;
            for (int k = 0; k < 4; ++k) {
                const std::int32_t v = s.quads(f, k);
                corners += junctions.vertex[std::size_t(v)] ? 1 : 0;
                has_turn |= turn[std::size_t(v)] && r.weights.fairness_targets.rows() > 0 && !r.weights.fairness_targets.row(v).isZero(0.0);
                has_point |= junctions.vertex[std::size_t(v)] && junctions.edges_at_vertex[std::size_t(v)] != 2;
            }
            ++faces[std::size_t(corners)];
            fold[std::size_t(corners)] += folded[std::size_t(f)];
            cross[std::size_t(corners)] += crossing[std::size_t(f)];
            with_turn[std::size_t(corners)] += folded[std::size_t(f)] && has_turn;
            with_point[std::size_t(corners)] += folded[std::size_t(f)] && has_point;
        }
        // The folded corners (apexes) of the folded faces with three junction corners: the turn
        // (the corner between two junction edges), its two neighbours on the curve, or the face's
        // fourth corner, in a sheet.
        std::array<std::int64_t, 3> apex{};  // turn, curve neighbour, sheet corner
        for (std::int64_t f = 0; f < s.face_count(); ++f) {
            if (!folded[std::size_t(f)]) continue;
            std::array<Eigen::Vector3d, 4> quad;
            int corners = 0;
            for (int k = 0; k < 4; ++k) {
                quad[std::size_t(k)] = r.regularization.positions.row(s.quads(f, k)).transpose();
                corners += junctions.vertex[std::size_t(s.quads(f, k))] ? 1 : 0;
            }
            if (corners != 3) continue;
            const std::array<bool, 4> at = folded_corners(quad, r.field.normals.row(f).transpose());
            for (int k = 0; k < 4; ++k) {
                if (!at[std::size_t(k)]) continue;
                const std::int32_t v = s.quads(f, k);
                if (!junctions.vertex[std::size_t(v)]) ++apex[2];
                else if (junctions.vertex[std::size_t(s.quads(f, (k + 1) % 4))] && junctions.vertex[std::size_t(s.quads(f, (k + 3) % 4))]) ++apex[0];
                else ++apex[1];
            }
        }
        const std::string name = share ? format("%g", *share) : "default";
        std::printf("| %s | folded corners of the three-junction-corner faces: turn %lld, curve neighbour %lld, sheet corner %lld |\n",
                    name.c_str(), (long long)apex[0], (long long)apex[1], (long long)apex[2]);
        for (int c = 0; c <= 4; ++c)
            std::printf("| %s | %d | %lld | %lld | %lld | %lld | %lld |\n", name.c_str(), c, (long long)faces[std::size_t(c)],
                        (long long)fold[std::size_t(c)], (long long)cross[std::size_t(c)], (long long)with_turn[std::size_t(c)],
                        (long long)with_point[std::size_t(c)]);
        std::fflush(stdout);
    }
    return 0;
}

// ---- blobs -----------------------------------------------------------------------------------

struct BlobOptions {
    std::int64_t ball_faces = 0;  ///< > 0: instead of blobs, one binary ball (or shell) of about these faces
    int labels = 100;
    Index3 dims{256, 256, 256};
    double radius = 100;  ///< the total interface area is about that of one ball of this radius
    unsigned seed = 1;
    bool binary = false;
    std::string out;
    std::string input_file;  ///< keep the generated .raw here (for bench/slicer_pipeline.py)
};

/// Labels 1..N of random blobs packed in a ball of radius R (the "body"), as uint16 values (0 =
/// background): N seeds uniform in the ball, each voxel of the ball taking the label of its
/// nearest seed if that seed reaches it (reach: 0.9 to 1.3 times the cell radius R/N^(1/3)), so
/// that blobs touch their neighbours where seeds are close and leave background between them
/// elsewhere — organs in a body, grains in a material.
std::vector<std::uint16_t> blob_values(const BlobOptions& o) {
    const std::int64_t nx = o.dims[0], ny = o.dims[1], nz = o.dims[2];
    const Eigen::Vector3d centre(0.5 * double(nx - 1), 0.5 * double(ny - 1), 0.5 * double(nz - 1));
    const double cell = o.radius / std::cbrt(double(o.labels));
    const double largest = 0.49 * double(std::min({nx, ny, nz}));
    std::mt19937 rng(o.seed);
    std::uniform_real_distribution<double> unit(-1.0, 1.0), jitter(0.9, 1.3);
    std::vector<std::uint16_t> values(std::size_t(nx * ny * nz), 0);
    std::vector<float> nearest(values.size(), std::numeric_limits<float>::infinity());
    for (int label = 1; label <= o.labels; ++label) {
        Eigen::Vector3d offset;
        do offset = Eigen::Vector3d(unit(rng), unit(rng), unit(rng));
        while (offset.squaredNorm() > 1.0);
        const Eigen::Vector3d c = centre + o.radius * offset;
        const double reach = std::min(largest, cell * jitter(rng));
        const auto first = [&](double x) { return std::max<std::int64_t>(0, std::int64_t(std::floor(x - reach))); };
        const auto last = [&](double x, std::int64_t n) { return std::min<std::int64_t>(n - 1, std::int64_t(std::ceil(x + reach))); };
        for (std::int64_t k = first(c.z()); k <= last(c.z(), nz); ++k)
            for (std::int64_t j = first(c.y()); j <= last(c.y(), ny); ++j)
                for (std::int64_t i = first(c.x()); i <= last(c.x(), nx); ++i) {
                    const Eigen::Vector3d p{double(i), double(j), double(k)};
                    const double d = (p - c).norm();
                    const std::size_t q = std::size_t(i + nx * (j + ny * k));
                    if (d <= reach && d < nearest[q] && (p - centre).norm() <= o.radius) {
                        nearest[q] = float(d);
                        values[q] = std::uint16_t(label);
                    }
                }
    }
    if (!o.binary) return values;
    // One binary object with about the same faces: each blob keeps only its voxels whose six
    // neighbours are of its label or background, so blobs no longer touch.
    std::vector<std::uint16_t> eroded(values.size(), 0);
    for (std::int64_t k = 0; k < nz; ++k)
        for (std::int64_t j = 0; j < ny; ++j)
            for (std::int64_t i = 0; i < nx; ++i) {
                const std::size_t q = std::size_t(i + nx * (j + ny * k));
                if (!values[q]) continue;
                bool alone = true;
                const std::int64_t n[6][3] = {{i - 1, j, k}, {i + 1, j, k}, {i, j - 1, k}, {i, j + 1, k}, {i, j, k - 1}, {i, j, k + 1}};
                for (const auto& w : n) {
                    if (w[0] < 0 || w[1] < 0 || w[2] < 0 || w[0] >= nx || w[1] >= ny || w[2] >= nz) continue;
                    const std::uint16_t other = values[std::size_t(w[0] + nx * (w[1] + ny * w[2]))];
                    alone = alone && (other == 0 || other == values[q] || values[q] < other);
                }
                eroded[q] = alone ? 1 : 0;
            }
    return eroded;
}

/// One binary object of about `faces` faces in the grid: a ball of radius sqrt(faces/6π) (a digital
/// sphere has about 1.5 faces per unit of area), or, if that does not fit, the largest ball that
/// does with a concentric cavity for the remaining faces.
std::vector<std::uint16_t> ball_values(const BlobOptions& o) {
    const std::int64_t nx = o.dims[0], ny = o.dims[1], nz = o.dims[2];
    const Eigen::Vector3d centre(0.5 * double(nx - 1), 0.5 * double(ny - 1), 0.5 * double(nz - 1));
    const double per_area = 6.0 * M_PI;
    const double outer = std::min(0.48 * double(std::min({nx, ny, nz})), std::sqrt(double(o.ball_faces) / per_area));
    const double rest = double(o.ball_faces) - per_area * outer * outer;
    const double inner = rest > 0 ? std::min(outer - 3.0, std::sqrt(rest / per_area)) : -1.0;
    std::vector<std::uint16_t> values(std::size_t(nx * ny * nz), 0);
    for (std::int64_t k = 0; k < nz; ++k)
        for (std::int64_t j = 0; j < ny; ++j)
            for (std::int64_t i = 0; i < nx; ++i) {
                const double r = (Eigen::Vector3d{double(i), double(j), double(k)} - centre).norm();
                values[std::size_t(i + nx * (j + ny * k))] = r <= outer && r > inner ? 1 : 0;
            }
    return values;
}

Index3 parse_dims(const std::string& text) {
    Index3 dims{};
    if (std::sscanf(text.c_str(), "%ld,%ld,%ld", &dims[0], &dims[1], &dims[2]) != 3) throw Error("--dims X,Y,Z");
    return dims;
}

int blobs(const BlobOptions& o) {
    const auto folder = std::filesystem::temp_directory_path() / ("dsreg_bench_labels_" + std::to_string(::getpid()));
    std::filesystem::create_directories(folder);
    const std::string input = o.input_file.empty() ? (folder / "blobs.raw").string() : o.input_file;
    {
        const std::vector<std::uint16_t> values = o.ball_faces > 0 ? ball_values(o) : blob_values(o);
        std::ofstream(input, std::ios::binary).write(reinterpret_cast<const char*>(values.data()), std::streamsize(2 * values.size()));
    }
    VolumeSource source;
    source.input_path = input;
    RawVolumeLayout layout;
    layout.dims = o.dims;
    layout.type = RawVoxelType::UInt16;
    source.raw_layout = layout;
    source.multi_label = !o.binary && o.ball_faces == 0;
    PipelineOptions options;  // the defaults of dsreg regularize
    const double cpu_start = cpu_seconds();
    const auto wall_start = std::chrono::steady_clock::now();
    // CPU seconds of each stage (the process's, all threads), from the stage events.
    std::map<std::string, double> stage_cpu;
    double stage_start = cpu_start;
    const ProgressCallback progress = [&](const ProgressEvent& e) {
        if (e.finished) stage_cpu[e.stage] += cpu_seconds() - stage_start;
        else if (e.fraction == 0.0) stage_start = cpu_seconds();
    };
    PipelineResult result = run_pipeline(source, options, progress);
    if (!o.out.empty()) {
        PipelineOutputs outputs;
        outputs.mesh = (std::filesystem::path(o.out) / "blobs.ply").string();
        write_pipeline_outputs(result, options, outputs, source, progress);
    }
    const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
    const double cpu = cpu_seconds() - cpu_start;
    nlohmann::json line = {{"mode", o.ball_faces > 0 ? "ball" : o.binary ? "binary" : "labels"},
                           {"labels", o.binary ? 1 : std::int64_t(result.label_meshes.size())},
                           {"blobs", o.labels},
                           {"dims", o.dims},
                           {"faces", result.surface.face_count()},
                           {"vertices", result.surface.vertex_count()},
                           {"junction_vertices", result.junctions.vertex_count},
                           {"wall_seconds", wall},
                           {"cpu_seconds", cpu},
                           {"peak_memory_bytes", peak_memory_bytes()},
                           {"solver", result.regularization.solve.solver}};
    for (const auto& [stage, seconds] : result.stage_seconds) line["seconds"][stage] = seconds;
    for (const auto& [stage, seconds] : stage_cpu) line["cpu"][stage] = seconds;
    std::cout << line.dump() << std::endl;
    std::filesystem::remove_all(folder);
    return 0;
}

// ---- repair ----------------------------------------------------------------------------------

/// The validity repair on the solved complex of each known partition at each grid step: counts as
/// solved, rounds, how far junction and other vertices move, every label's volume against its
/// solved one and its voxels', and the junction accuracy before and after.
int repair(const std::vector<double>& steps) {
    std::printf("| shape, h | as solved: pairs / folded | rounds | region | held | moved mean/max, junction vertices | other vertices | label volume after / solved (voxels' ratio) | junctions mean (p95) solved -> repaired | all mean solved -> repaired |\n");
    std::printf("|---|---|---|---|---|---|---|---|---|---|\n");
    for (const std::string name : {"sectors", "layers"})
        for (const double h : steps) {
            const LabelShape shape = make_label_shape(name);
            const LoadedVolume loaded = digitized_shape(shape, name, h);
            PipelineOptions options;
            options.solver = SolverKind::Cholmod;
            options.validity = ValidityMode::Off;
            const PipelineResult r = run_pipeline(loaded, options);
            const ValidityRepairResult repaired =
                repair_validity(r.surface, r.field.normals, r.weights, r.regularization.positions);
            const Junctions junctions = find_junctions(r.surface, complex_edges(r.surface));
            double move[2] = {0, 0}, top[2] = {0, 0};
            std::int64_t count[2] = {0, 0};
            for (std::int64_t v = 0; v < r.surface.vertex_count(); ++v) {
                const int j = junctions.vertex[std::size_t(v)] ? 0 : 1;
                const double d = (repaired.positions.row(v) - r.regularization.positions.row(v)).norm() / h;
                move[j] += d, top[j] = std::max(top[j], d), ++count[j];
            }
            std::string volumes;
            const std::vector<std::int64_t> voxels = loaded.labels->voxel_counts();
            for (const LabelMesh& mesh : label_meshes(r.surface)) {
                const LabelMeasures before = measure_label(r.surface, mesh, r.regularization.positions, voxels[mesh.label]);
                const LabelMeasures after = measure_label(r.surface, mesh, repaired.positions, voxels[mesh.label]);
                char text[96];
                std::snprintf(text, sizeof text, "%s%lld: %.4f (%.3f)", volumes.empty() ? "" : ", ", (long long)after.value,
                              after.volume / before.volume, after.volume / after.voxel_volume);
                volumes += text;
            }
            const LabelComplexErrors e0 = label_complex_errors(shape, r.surface, r.regularization.positions);
            const LabelComplexErrors e1 = label_complex_errors(shape, r.surface, repaired.positions);
            const ValidityRepairReport& rep = repaired.report;
            std::printf("| %s, %g | %lld / %lld | %d | %lld | %lld | %.3f / %.2f | %.3f / %.2f | %s | %.3f (%.3f) -> %.3f (%.3f) | %.3f -> %.3f |\n",
                        name.c_str(), h, (long long)rep.before.intersecting_pairs, (long long)rep.before.folded_faces,
                        rep.rounds, (long long)rep.region_vertices, (long long)rep.held_vertices,
                        move[0] / std::max<std::int64_t>(count[0], 1), top[0], move[1] / std::max<std::int64_t>(count[1], 1),
                        top[1], volumes.c_str(), e0.junctions.mean / h, e0.junctions.p95 / h, e1.junctions.mean / h,
                        e1.junctions.p95 / h, e0.interfaces.mean / h, e1.interfaces.mean / h);
            std::fflush(stdout);
        }
    return 0;
}

}  // namespace

int main(int argc, char** argv) {
    try {
        const std::vector<std::string> args(argv + 1, argv + argc);
        if (!args.empty() && args[0] == "accuracy") {
            std::vector<double> steps;
            for (std::size_t i = 1; i < args.size(); ++i) steps.push_back(std::stod(args[i]));
            if (steps.empty()) steps = {1.0, 0.5, 0.25};
            return accuracy(steps);
        }
        if (!args.empty() && args[0] == "repair") {
            std::vector<double> steps;
            for (std::size_t i = 1; i < args.size(); ++i) steps.push_back(std::stod(args[i]));
            if (steps.empty()) steps = {1.0, 0.5};
            return repair(steps);
        }
        if (args.size() >= 3 && args[0] == "folds") {
            std::vector<std::optional<double>> shares;
            for (std::size_t i = 3; i < args.size(); ++i) shares.emplace_back(std::stod(args[i]));
            return folds(args[1], parse_dims(args[2]), shares);
        }
        if (!args.empty() && args[0] == "blobs") {
            BlobOptions o;
            for (std::size_t i = 1; i < args.size(); ++i) {
                const std::string& a = args[i];
                const auto value = [&]() -> const std::string& {
                    if (i + 1 >= args.size()) throw Error(a + " needs a value");
                    return args[++i];
                };
                if (a == "--labels") o.labels = std::stoi(value());
                else if (a == "--dims") o.dims = parse_dims(value());
                else if (a == "--radius") o.radius = std::stod(value());
                else if (a == "--seed") o.seed = unsigned(std::stoul(value()));
                else if (a == "--binary") o.binary = true;
                else if (a == "--ball-faces") o.ball_faces = std::stoll(value());
                else if (a == "--out") o.out = value();
                else if (a == "--input-file") o.input_file = value();
                else throw Error("unknown option " + a);
            }
            if (o.labels < 1 || o.labels > 65535) throw Error("--labels must be in 1..65535");
            return blobs(o);
        }
        std::cerr << "usage: dsreg_bench_labels accuracy [H ...] | repair [H ...] | folds PATH X,Y,Z [SHARE ...] | blobs --labels N --dims X,Y,Z --radius R [--seed S] [--binary] [--out DIR] [--input-file PATH]\n";
        return 2;
    } catch (const std::exception& e) {
        std::cerr << "dsreg_bench_labels: " << e.what() << '\n';
        return 1;
    }
}
