#include "regularize_command.hpp"

#include <unistd.h>

#include <cstdio>
#include <iostream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "cli_text.hpp"
#include "dsreg/atomic_file.hpp"
#include "dsreg/digital_surface.hpp"
#include "dsreg/error.hpp"
#include "dsreg/evaluation.hpp"
#include "dsreg/mesh_io.hpp"
#include "dsreg/normals_file.hpp"
#include "dsreg/regularization.hpp"
#include "normal_field.hpp"
#include "output_paths.hpp"
#include "regularization_options.hpp"
#include "stage_clock.hpp"
#include "volume_source.hpp"

namespace dsreg::cli {

namespace {

struct RegularizeOptions {
    VolumeSourceOptions source;
    int connectivity = 26;
    NormalFieldOptions normals;
    double alpha = 1e-3, beta = 1.0, gamma = 1e-2;
    std::string solver = "auto";
    std::string output, input_mesh, report;
    bool triangulate = false, quiet = false, verbose = false;
    ExtensionOptions extensions;  ///< --clamp, --metric, local weight maps
};

/// The output mesh: quads (or triangles) with the field u per face and, after AT, the feature
/// map v per vertex ("v" in PLY).
PolygonMesh make_mesh(const DigitalSurface& surface, const PointMatrix& positions, const NormalField& field,
                      bool triangulate) {
    PolygonMesh mesh;
    mesh.vertices = positions;
    mesh.faces = surface.quads;
    mesh.face_normals = field.normals;
    if (field.at) mesh.vertex_scalars.emplace_back("v", field.at->features);
    return triangulate ? triangulate_shorter_diagonal(mesh) : mesh;
}

nlohmann::json energy_json(const EnergyTerms& e, const RegularizationWeights& w) {
    return {{"data", e.data}, {"alignment", e.alignment}, {"fairness", e.fairness}, {"total", e.total(w)}};
}

void check_options(RegularizeOptions& o) {
    check_mesh_output_path("-o", o.output);
    if (!o.input_mesh.empty()) check_mesh_output_path("--input-mesh", o.input_mesh);
    if (!o.report.empty()) check_output_folder("--report", o.report);
    check_normal_field_options(o.normals, !o.source.shape.empty());
    check_distinct_outputs({{"-o", o.output},
                            {"--input-mesh", o.input_mesh},
                            {"--report", o.report},
                            {"--export-normals", o.normals.export_path},
                            {"--features", o.normals.features_path}});
    parse_solver_kind(o.solver);
    if (!o.source.max_memory.empty()) parse_memory_size("--max-memory", o.source.max_memory);
    // The library checks the weights too; here the message names the option as it was typed.
    const auto check_weight = [](const char* option, double value, bool zero_allowed) {
        if ((zero_allowed ? value >= 0 : value > 0) && std::isfinite(value)) return;
        throw Error(std::string(option) + " " + format("%g", value) + ": must be " +
                    (zero_allowed ? "zero or positive" : "positive (the data term keeps the system positive definite)") +
                    " and finite");
    };
    check_weight("--alpha", o.alpha, false);
    check_weight("--beta", o.beta, true);
    check_weight("--gamma", o.gamma, true);
    RegularizationWeights weights{o.alpha, o.beta, o.gamma, {}, {}};
    validate_weights(weights, 0, 0);
    check_regularization_extension_options(o.extensions);
}

void write_outputs(const RegularizeOptions& o, const DigitalSurface& surface, const NormalField& field,
                   const RegularizationResult& result) {
    write_mesh(o.output, make_mesh(surface, result.positions, field, o.triangulate));
    if (!o.input_mesh.empty()) write_mesh(o.input_mesh, make_mesh(surface, surface.vertices, field, o.triangulate));
    if (!o.normals.export_path.empty())
        write_normals_file(o.normals.export_path, surface, field.normals, field.description);
    write_feature_lines(o.normals, field, surface, result.positions);
}

nlohmann::json make_report(const RegularizeOptions& o, const LoadedVolume& loaded, std::int64_t object_voxels,
                           const DigitalSurface& surface, const NormalField& field, const RegularizationResult& result,
                           const RegularizationWeights& weights, const StageClock& clock) {
    nlohmann::json report;
    report["input"] = loaded.description;
    report["grid"] = {{"dims", loaded.volume.grid.dims},
                      {"spacing", {loaded.volume.grid.spacing.x(), loaded.volume.grid.spacing.y(), loaded.volume.grid.spacing.z()}},
                      {"origin", {loaded.volume.grid.origin.x(), loaded.volume.grid.origin.y(), loaded.volume.grid.origin.z()}}};
    report["counts"] = {{"voxels", loaded.volume.grid.voxel_count()},
                        {"object_voxels", object_voxels},
                        {"surfels", surface.face_count()},
                        {"vertices", surface.vertex_count()},
                        {"components", surface.component_count},
                        {"split_pointels", surface.split_pointel_count},
                        {"euler_characteristics", component_euler_characteristics(surface)}};
    report["parameters"] = {{"alpha", o.alpha}, {"beta", o.beta}, {"gamma", o.gamma},
                            {"min", o.source.min_value ? nlohmann::json(*o.source.min_value) : nlohmann::json(nullptr)},
                            {"max", o.source.max_value ? nlohmann::json(*o.source.max_value) : nlohmann::json(nullptr)},
                            {"connectivity", o.connectivity}, {"normals", o.normals.kind},
                            {"normals_input", field.input},
                            {"radius", field.radius ? nlohmann::json(*field.radius) : nlohmann::json(nullptr)},
                            {"ii_kernel", field.ii_kernel ? nlohmann::json(*field.ii_kernel) : nlohmann::json(nullptr)},
                            {"ii_extrapolated", field.ii_extrapolated},
                            {"solver", result.solve.solver}, {"triangulate", o.triangulate}};
    if (field.at) report["at"] = at_report(o.normals, field, surface);
    report["solve"] = {{"relative_residual", result.solve.relative_residual},
                       {"error_bound", result.solve.error_bound},
                       {"solver", result.solve.solver},
                       {"note", result.solve.note},
                       {"multigrid_levels", result.solve.multigrid_levels},
                       {"operator_complexity", result.solve.operator_complexity},
                       {"iterations", result.solve.iterations},
                       {"factor_nonzeros", std::int64_t(result.solve.factor_nonzeros)},
                       {"unknowns", 3 * surface.vertex_count()}};
    report["energy_before"] = energy_json(result.energy_before, weights);
    report["energy_after"] = energy_json(result.energy_after, weights);
    nlohmann::json stages = nlohmann::json::object();
    for (const auto& [name, seconds] : clock.stage_seconds()) stages[name] = seconds;
    stages["assembly"] = result.assembly_seconds;
    stages["solve"] = result.solve_seconds;
    report["seconds"] = stages;
    report["total_seconds"] = clock.total_seconds();
    report["peak_memory_bytes"] = peak_memory_bytes();
    report["outputs"] = {{"mesh", o.output}, {"input_mesh", o.input_mesh},
                         {"normals", o.normals.export_path}, {"features", o.normals.features_path}};
    return report;
}

void run(RegularizeOptions& o) {
    check_options(o);
    const bool progress = !o.quiet && (o.verbose || isatty(STDERR_FILENO));
    StageClock clock(progress);

    clock.start(o.source.shape.empty() ? "read" : "digitize");
    const LoadedVolume loaded = load_volume(o.source);
    const std::int64_t object_voxels = loaded.volume.object_voxel_count();
    clock.finish(std::to_string(object_voxels) + " object voxels");
    if (object_voxels == 0 && o.source.shape.empty()) {
        const std::string values = file_value_range(o.source);
        throw Error(o.source.input_path + ": the object is empty: no voxel has " + object_value_range(o.source) +
                    (values.empty() ? "" : "; " + values) + " (choose the object's values with --min and --max)");
    }
    if (!o.source.max_memory.empty()) {
        // Before anything proportional to the surface is allocated: count its surfels (one pass).
        const SolverKind kind = parse_solver_kind(o.solver);
        check_run_memory(o.source, loaded.volume.grid.voxel_count(), count_surfels(loaded.volume),
                         kind == SolverKind::Cholmod || kind == SolverKind::Auto);
    }

    clock.start("surface");
    const DigitalSurface surface = extract_digital_surface(
        loaded.volume, o.connectivity == 6 ? Connectivity::Six : Connectivity::TwentySix);
    clock.finish(std::to_string(surface.face_count()) + " surfels, " + std::to_string(surface.vertex_count()) +
                 " vertices, " + std::to_string(surface.component_count) +
                 (surface.component_count == 1 ? " component" : " components"));

    const NormalField field = compute_normal_field(o.normals, loaded, surface, clock);

    clock.start("regularize");
    RegularizationWeights weights{o.alpha, o.beta, o.gamma, {}, {}};
    apply_regularization_extensions(o.extensions, o.source, surface, field.normals, weights);
    SolverOptions solver;
    solver.kind = parse_solver_kind(o.solver);
    solver.max_error_voxels = kDefaultMaxErrorVoxels;  // iterative solvers: within 5e-5 voxel of the exact answer
    nlohmann::json extension_report;
    const RegularizationResult result =
        run_regularization(o.extensions, loaded.volume, surface, field.normals, weights, solver, extension_report);
    clock.finish(result.solve.solver + ", relative residual " + format("%.2e", result.solve.relative_residual));

    // Faces the solve turned against their normal (where u itself points inward, e.g. on parts
    // thinner than the integral-invariant ball): reported, since they show as creases.
    const std::int64_t folded = count_faces_against_field(result.positions, surface.quads, field.normals);

    clock.start("write");
    write_outputs(o, surface, field, result);
    clock.finish(o.output);

    if (!o.report.empty()) {
        nlohmann::json report = make_report(o, loaded, object_voxels, surface, field, result, weights, clock);
        report.update(extension_report);
        report["counts"]["faces_against_field"] = folded;
        const std::string text = report.dump(2) + "\n";
        write_file_atomically(o.report, [&](std::ostream& out) { out << text; });
    }

    if (!o.quiet) {
        std::ostringstream line;
        line << "dsreg: " << loaded.description << ": " << surface.face_count() << " surfels, " << surface.vertex_count()
             << " vertices, " << surface.component_count << (surface.component_count == 1 ? " component" : " components")
             << "; energy " << format("%.4g", result.energy_before.total(weights)) << " -> "
             << format("%.4g", result.energy_after.total(weights)) << "; " << result.solve.solver << " residual "
             << format("%.1e", result.solve.relative_residual);
        if (folded > 0) line << "; " << folded << " faces folded against u";
        if (field.at)
            line << "; Ambrosio-Tortorelli " << field.at->total_rounds() << " rounds, "
                 << (field.at->features.array() < o.normals.feature_threshold).count() << " feature vertices";
        line << "; " << format("%.2f", clock.total_seconds()) << " s, "
             << human_bytes(peak_memory_bytes()) << " peak -> " << o.output;
        std::cerr << line.str() << '\n';
    }
}

}  // namespace

void add_regularize_command(CLI::App& app) {
    auto options = std::make_shared<RegularizeOptions>();
    CLI::App* cmd = app.add_subcommand("regularize", "Regularize the digital surface of a volume into a smooth quad mesh");
    add_volume_source_options(*cmd, options->source);
    cmd->add_option("-o,--output", options->output, "Output mesh: .obj .off .ply (quads) or .stl (triangles)")->required();
    cmd->add_option("--connectivity", options->connectivity,
                    "Object connectivity where voxels touch by an edge: 6 keeps them apart, 26 joins them")
        ->check(CLI::IsMember({6, 26}))
        ->capture_default_str();
    add_normal_field_options(*cmd, options->normals);
    add_regularization_extension_options(*cmd, options->extensions);
    cmd->add_option("--alpha", options->alpha, "Weight of data attachment (> 0)")->capture_default_str();
    cmd->add_option("--beta", options->beta, "Weight of normal alignment (>= 0)")->capture_default_str();
    cmd->add_option("--gamma", options->gamma, "Weight of fairness (>= 0)")->capture_default_str();
    cmd->add_option("--solver", options->solver,
                    "Linear solver: auto (cholmod for small systems and tiny alpha, else amg), cholmod (sparse "
                    "Cholesky), amg (CG preconditioned by smoothed aggregation multigrid) or cg (block-Jacobi CG); "
                    "iterative solvers stop once their error bound is below 5e-5 voxel")
        ->check(CLI::IsMember(solver_names()))
        ->capture_default_str();
    cmd->add_flag("--triangulate", options->triangulate, "Split each quad along its shorter diagonal");
    cmd->add_option("--input-mesh", options->input_mesh, "Also write the unregularized digital surface to this file");
    cmd->add_option("--report", options->report, "Write counts, timings, energies and parameters as JSON");
    cmd->add_flag("-q,--quiet", options->quiet, "Print nothing but errors");
    cmd->add_flag("-v,--verbose", options->verbose, "Print each stage as it finishes");
    cmd->callback([options] { run(*options); });
}

}  // namespace dsreg::cli
