#include "normal_field.hpp"

#include <cmath>
#include <cstdio>
#include <fstream>

#include "cli_text.hpp"
#include "dsreg/atomic_file.hpp"
#include "dsreg/error.hpp"
#include "dsreg/normals.hpp"
#include "dsreg/normals_file.hpp"
#include "output_paths.hpp"

namespace dsreg::cli {

namespace {

bool given(const CLI::Option* option) { return option != nullptr && option->count() > 0; }

/// A whole-string decimal number, or dsreg::Error naming --at-eps.
double parse_epsilon(const std::string& text, const std::string& whole) {
    if (const std::optional<double> value = parse_whole_number(text)) return *value;
    throw Error("--at-eps " + whole + ": '" + text + "' is not a number (expected EPS1:EPS2, e.g. 2:0.25)");
}

/// "2:0.25" → (2, 0.25); "0.5" → (0.5, 0.5).
void parse_epsilon_range(const std::string& text, AmbrosioTortorelliParameters& at) {
    const std::size_t colon = text.find(':');
    if (colon == std::string::npos) {
        at.epsilon_start = at.epsilon_end = parse_epsilon(text, text);
        return;
    }
    at.epsilon_start = parse_epsilon(text.substr(0, colon), text);
    at.epsilon_end = parse_epsilon(text.substr(colon + 1), text);
}

/// The kind of the input field g: the file, --at-input for AT, or --normals itself.
std::string input_kind(const NormalFieldOptions& o) {
    if (!o.file.empty()) return "file";
    return o.kind == "at" ? o.at_input : o.kind;
}

void check_combinations(const NormalFieldOptions& o, bool input_is_shape) {
    const bool at = o.kind == "at";
    if (!o.file.empty() && given(o.normals_option) && !at)
        throw Error("--normals-file gives the field itself: do not combine it with --normals " + o.kind +
                    " (only with --normals at, to regularize the file's field)");
    if (given(o.at_input_option) && !at) throw Error("--at-input only applies to --normals at");
    if (given(o.at_input_option) && !o.file.empty())
        throw Error("--at-input and --normals-file both choose the field that --normals at regularizes: give one");
    for (const CLI::Option* option : o.at_only_options)
        if (given(option) && !at) throw Error(option->get_name() + " only applies to --normals at");
    if (input_kind(o) == "exact" && !input_is_shape)
        throw Error("--normals exact needs an implicit --shape (the true normals are unknown for a file)");
}

void check_paths(const NormalFieldOptions& o) {
    if (!o.file.empty() && !std::ifstream(o.file))
        throw Error("--normals-file " + o.file + ": cannot open the file");
    if (!o.export_path.empty()) check_output_folder("--export-normals", o.export_path);
    if (!o.features_path.empty()) {
        if (file_extension(o.features_path) != "obj")
            throw Error("--features " + o.features_path + ": the feature lines are written as OBJ polylines (use .obj)");
        check_output_folder("--features", o.features_path);
    }
}

/// --radius when given, else 3·h^(1/3) for a --shape; for a file 3 voxels, or 5 voxels for
/// the biweight kernel of the integral invariants (its weights fade out towards the sphere, so
/// it needs a larger support than the ball for as little noise: docs/accuracy.md). Twice that
/// with --ii-extrapolate, whose extrapolation removes the bias that grows with r.
double field_radius(const NormalFieldOptions& o, const std::string& kind, const LoadedVolume& loaded) {
    if (o.radius) return *o.radius;
    const bool ii = kind == "ii";
    const bool biweight = ii && o.ii_kernel == "biweight";
    const double radius =
        loaded.shape || !biweight ? default_ii_radius(loaded) : 5.0 * loaded.volume.grid.spacing.maxCoeff();
    return ii && o.ii_extrapolate ? 2.0 * radius : radius;
}

/// The input field g (or the whole field, without AT).
PointMatrix estimate_input_field(const NormalFieldOptions& o, const LoadedVolume& loaded, const DigitalSurface& surface,
                                 NormalField& field) {
    const std::string kind = input_kind(o);
    field.input = kind;
    if (kind == "file") {
        field.description = "file " + o.file;
        return read_normals_file(o.file, surface);
    }
    if (kind == "ii" || kind == "ctrivial") {
        field.radius = field_radius(o, kind, loaded);
        const std::string r = ", r = " + format("%g", *field.radius);
        if (kind == "ctrivial") {
            field.description = "convolved trivial normals" + r;
            return convolved_trivial_normals(surface, *field.radius);
        }
        field.ii_kernel = o.ii_kernel;
        field.ii_extrapolated = o.ii_extrapolate;
        const IntegralInvariantKernel kernel = parse_integral_invariant_kernel(o.ii_kernel);
        if (o.ii_extrapolate) {
            field.description = "integral invariants (" + o.ii_kernel + " kernel), extrapolated from r and r/sqrt(2)" + r;
            return extrapolated_integral_invariant_normals(loaded.volume, surface, *field.radius, kernel);
        }
        field.description = "integral invariants (" + o.ii_kernel + " kernel)" + r;
        return integral_invariant_normals(loaded.volume, surface, *field.radius, kernel);
    }
    if (kind == "exact") {
        field.description = "exact normals";
        return exact_normals(*loaded.shape, surface);
    }
    field.description = "trivial normals";
    return trivial_normals(surface);
}

std::int64_t count_below(const Eigen::VectorXd& v, double threshold) { return (v.array() < threshold).count(); }

/// The verbose stage line of AT, e.g. "eps 2 -> 0.25: rounds 6+4+3+3, last |dv| 1.3e-05, …".
std::string at_stage_detail(const AmbrosioTortorelliResult& r, double threshold) {
    std::string rounds, changes;
    for (const AtLevelReport& level : r.levels) {
        rounds += (rounds.empty() ? "" : "+") + std::to_string(level.rounds);
        changes += (changes.empty() ? "" : " ") + format("%.1e", level.v_change);
    }
    return "Ambrosio-Tortorelli eps " + format("%g", r.levels.front().epsilon) + " -> " +
           format("%g", r.levels.back().epsilon) + ": rounds " + rounds + ", |dv|inf " + changes + "; " +
           std::to_string(r.solves.factorizations) + " factorizations, " + std::to_string(r.solves.refined_solves) +
           " refined solves, residual " + format("%.1e", std::max(r.max_u_residual, r.max_v_residual)) + "; v min " +
           format("%.3f", r.features.minCoeff()) + ", " + std::to_string(count_below(r.features, threshold)) +
           " vertices with v < " + format("%g", threshold);
}

}  // namespace

void add_normal_field_options(CLI::App& cmd, NormalFieldOptions& o) {
    o.normals_option =
        cmd.add_option("--normals", o.kind,
                       "Normal field: ii (integral invariants), trivial (voxel faces), ctrivial (trivial normals "
                       "averaged within --radius), exact (true normals of a --shape), or at (Ambrosio-Tortorelli "
                       "piecewise-smooth regularization of --at-input or --normals-file: keeps sharp features)")
            ->check(CLI::IsMember({"ii", "trivial", "ctrivial", "exact", "at"}))
            ->capture_default_str();
    cmd.add_option("--radius", o.radius,
                   "Radius of ii and ctrivial, physical units (default: 3·h^(1/3) for --shape; for files 3 voxels, "
                   "or 5 voxels for ii with the biweight kernel)");
    cmd.add_option("--ii-kernel", o.ii_kernel,
                   "Weights of the integral-invariant ball: biweight (1 - d^2/r^2)^2, smooth, more accurate "
                   "(docs/accuracy.md), or ball (uniform, the paper's integral invariants)")
        ->check(CLI::IsMember({"ball", "biweight"}))
        ->capture_default_str();
    cmd.add_flag("--ii-extrapolate", o.ii_extrapolate,
                 "Integral invariants at r and r/sqrt(2) combined as 2 n(r/sqrt(2)) - n(r): removes the bias that "
                 "grows like r^2 (far more accurate on smooth shapes whose features are much larger than r; "
                 "docs/accuracy.md). Default radius doubles");
    cmd.add_option("--normals-file", o.file,
                   "Read the normal field from this text file (lines 'i j k direction nx ny nz', see "
                   "docs/ambrosio-tortorelli.md); with --normals at, the field to regularize");
    o.at_input_option = cmd.add_option("--at-input", o.at_input, "Field that --normals at regularizes")
                            ->check(CLI::IsMember({"ii", "trivial", "ctrivial", "exact"}))
                            ->capture_default_str();
    o.at_only_options = {
        cmd.add_option("--at-alpha", o.at.alpha, "AT attachment weight a (grid units)")->capture_default_str(),
        cmd.add_option("--at-lambda", o.at.lambda, "AT feature length cost lambda (grid units)")->capture_default_str(),
        cmd.add_option("--at-eps", o.at_epsilon, "AT epsilon from EPS1 down to EPS2, in voxels (EPS1:EPS2)")
            ->capture_default_str(),
        cmd.add_option("--at-eps-ratio", o.at.epsilon_ratio, "AT: epsilon is divided by this between levels (> 1)")
            ->capture_default_str(),
        cmd.add_option("--features", o.features_path,
                       "Write the sharp edges found by --normals at (mesh edges with v < --feature-threshold at both "
                       "ends) as OBJ polylines"),
        cmd.add_option("--feature-threshold", o.feature_threshold, "v below which a vertex is on a feature")
            ->capture_default_str(),
    };
    cmd.add_option("--export-normals", o.export_path,
                   "Write the normal field used (after AT, if any) in the --normals-file format");
}

void check_normal_field_options(NormalFieldOptions& o, bool input_is_shape) {
    check_combinations(o, input_is_shape);
    if (o.radius && (!(*o.radius > 0) || !std::isfinite(*o.radius))) throw Error("--radius must be positive");
    if (o.kind == "at") {
        parse_epsilon_range(o.at_epsilon, o.at);
        validate_at_parameters(o.at);
        if (!(o.feature_threshold > 0 && o.feature_threshold <= 1))
            throw Error("--feature-threshold must be in (0, 1]");
    }
    check_paths(o);
}

NormalField compute_normal_field(const NormalFieldOptions& o, const LoadedVolume& loaded, const DigitalSurface& surface,
                                 StageClock& clock) {
    NormalField field;
    clock.start("normals");
    PointMatrix g = estimate_input_field(o, loaded, surface, field);
    clock.finish(field.description);
    if (o.kind != "at") {
        field.normals = std::move(g);
        return field;
    }
    clock.start("at");
    field.at = ambrosio_tortorelli_normals(surface, g, o.at);
    clock.finish(at_stage_detail(*field.at, o.feature_threshold));
    field.normals = field.at->normals;
    field.description = "Ambrosio-Tortorelli of " + field.description;
    return field;
}

void write_feature_lines(const NormalFieldOptions& o, const NormalField& field, const DigitalSurface& surface,
                         const PointMatrix& positions) {
    if (o.features_path.empty() || !field.at) return;
    const auto lines = feature_polylines(surface.quads, surface.vertex_count(), field.at->features, o.feature_threshold);
    write_polylines_obj(o.features_path, positions, lines);
}

nlohmann::json at_report(const NormalFieldOptions& o, const NormalField& field, const DigitalSurface& surface) {
    const AmbrosioTortorelliResult& r = *field.at;
    nlohmann::json levels = nlohmann::json::array();
    for (const AtLevelReport& level : r.levels)
        levels.push_back({{"epsilon", level.epsilon},
                          {"rounds", level.rounds},
                          {"v_change", level.v_change},
                          {"converged", level.converged},
                          {"energy", level.energy},
                          {"seconds", level.seconds},
                          {"factorizations", level.solves.factorizations},
                          {"refined_solves", level.solves.refined_solves}});
    const auto lines = feature_polylines(surface.quads, surface.vertex_count(), r.features, o.feature_threshold);
    std::size_t line_edges = 0;
    for (const auto& line : lines) line_edges += line.size() - 1;
    return {{"input", field.input},
            {"alpha", o.at.alpha},
            {"lambda", o.at.lambda},
            {"epsilon_start", o.at.epsilon_start},
            {"epsilon_end", o.at.epsilon_end},
            {"epsilon_ratio", o.at.epsilon_ratio},
            {"tolerance", o.at.tolerance},
            {"max_rounds", o.at.max_rounds},
            {"levels", levels},
            {"total_rounds", r.total_rounds()},
            {"seconds", r.seconds},
            {"max_u_residual", r.max_u_residual},
            {"max_v_residual", r.max_v_residual},
            {"factorizations", r.solves.factorizations},
            {"refined_solves", r.solves.refined_solves},
            {"refinement_iterations", r.solves.refinement_iterations},
            {"u_factor_nonzeros", r.u_factor_nonzeros},
            {"v_factor_nonzeros", r.v_factor_nonzeros},
            {"features", {{"threshold", o.feature_threshold},
                          {"v_min", r.features.minCoeff()},
                          {"v_max", r.features.maxCoeff()},
                          {"v_mean", r.features.mean()},
                          {"vertices_below_threshold", count_below(r.features, o.feature_threshold)},
                          {"edges", line_edges},
                          {"polylines", lines.size()}}}};
}

}  // namespace dsreg::cli
