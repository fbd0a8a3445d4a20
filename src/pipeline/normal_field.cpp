#include <cerrno>
#include <cmath>
#include <cstdio>
#include <fstream>

#include "dsreg/error.hpp"
#include "dsreg/normals.hpp"
#include "dsreg/normals_file.hpp"
#include "dsreg/pipeline.hpp"
#include "dsreg/text.hpp"
#include "pipeline_stages.hpp"

namespace dsreg {

namespace {

/// A whole-string decimal number, or dsreg::Error naming --at-eps.
double parse_epsilon(const std::string& text, const std::string& whole) {
    if (const std::optional<double> value = parse_whole_number(text)) return *value;
    throw Error("--at-eps " + whole + ": '" + text + "' is not a number (expected EPS1:EPS2, e.g. 2:0.25)");
}

/// --normals as given, or its default: ii.
std::string field_kind(const NormalFieldOptions& o) { return o.kind.empty() ? "ii" : o.kind; }

/// The kind of the input field g: the file, --at-input for AT, or --normals itself.
std::string input_kind(const NormalFieldOptions& o) {
    if (!o.file.empty()) return "file";
    return field_kind(o) == "at" ? o.at_input.value_or("ii") : field_kind(o);
}

void check_combinations(const NormalFieldOptions& o, bool input_is_shape) {
    const bool at = field_kind(o) == "at";
    if (!o.file.empty() && !o.kind.empty() && !at)
        throw Error("--normals-file gives the field itself: do not combine it with --normals " + o.kind +
                    " (only with --normals at, to regularize the file's field)");
    if (o.at_input && !at) throw Error("--at-input only applies to --normals at");
    if (o.at_input && !o.file.empty())
        throw Error("--at-input and --normals-file both choose the field that --normals at regularizes: give one");
    if (input_kind(o) == "exact" && !input_is_shape)
        throw Error("--normals exact needs an implicit --shape (the true normals are unknown for a file)");
}

void check_choices(const NormalFieldOptions& o) {
    const std::string kind = field_kind(o);
    if (kind != "ii" && kind != "trivial" && kind != "ctrivial" && kind != "exact" && kind != "at")
        throw Error("--normals " + kind + ": unknown normal field (ii, trivial, ctrivial, exact or at)");
    if (o.at_input && *o.at_input != "ii" && *o.at_input != "trivial" && *o.at_input != "ctrivial" &&
        *o.at_input != "exact")
        throw Error("--at-input " + *o.at_input + ": unknown field (ii, trivial, ctrivial or exact)");
    parse_integral_invariant_kernel(o.ii_kernel);
}

/// On a label map's complex, the convolved trivial normals of the face's own interface near
/// junctions (within `radius`; docs/multi-label.md) in place of the integral invariants `u`.
void use_interface_normals(const LoadedVolume& loaded, const DigitalSurface& surface, double radius, PointMatrix& u,
                           NormalField& field) {
    if (!loaded.labels) return;
    field.interface_normal_faces = use_interface_normals_near_junctions(*loaded.labels, surface, radius, u);
    if (field.interface_normal_faces > 0)
        field.description += "; interface normals on the " + std::to_string(field.interface_normal_faces) +
                             " faces near junctions";
}

/// The adaptive field (adaptive_normals.hpp) of the object or of each face's inner label.
PointMatrix adaptive_field(const NormalFieldOptions& o, const LoadedVolume& loaded, const DigitalSurface& surface,
                           NormalField& field) {
    const AdaptiveNormalOptions adaptive = default_adaptive_options(o, loaded);
    field.ii_kernel = o.ii_kernel;
    field.adaptive = adaptive_integral_invariant_normals(loaded.voxel_labels(), surface, adaptive);
    const Eigen::VectorXd& r = field.adaptive->radius;
    field.description = "adaptive integral invariants (" + o.ii_kernel + " kernel), r = " + format("%g", r.minCoeff()) +
                        " to " + format("%g", r.maxCoeff()) + " (mean " + format("%.3g", r.mean()) + "), " +
                        format("%.1f", 100.0 * field.adaptive->extrapolated.mean()) + " % extrapolated";
    PointMatrix u = field.adaptive->normals;
    use_interface_normals(loaded, surface, default_field_radius(o, "ii", loaded), u, field);
    return u;
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
    if (kind == "ii" && !o.radius && !o.ii_extrapolate) return adaptive_field(o, loaded, surface, field);
    if (kind == "ii" || kind == "ctrivial") {
        field.radius = o.radius ? *o.radius : default_field_radius(o, kind, loaded);
        const std::string r = ", r = " + format("%g", *field.radius);
        if (kind == "ctrivial") {
            field.description = "convolved trivial normals" + r;
            return convolved_trivial_normals(surface, *field.radius);
        }
        field.ii_kernel = o.ii_kernel;
        field.ii_extrapolated = o.ii_extrapolate;
        const IntegralInvariantKernel kernel = parse_integral_invariant_kernel(o.ii_kernel);
        field.description = "integral invariants (" + o.ii_kernel + " kernel)" +
                            (o.ii_extrapolate ? ", extrapolated from r and r/sqrt(2)" : "") + r;
        PointMatrix u;
        if (loaded.labels)
            u = o.ii_extrapolate ? extrapolated_integral_invariant_normals(*loaded.labels, surface, *field.radius, kernel)
                                 : integral_invariant_normals(*loaded.labels, surface, *field.radius, kernel);
        else
            u = o.ii_extrapolate ? extrapolated_integral_invariant_normals(loaded.volume, surface, *field.radius, kernel)
                                 : integral_invariant_normals(loaded.volume, surface, *field.radius, kernel);
        use_interface_normals(loaded, surface, *field.radius, u, field);
        return u;
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

AdaptiveNormalOptions default_adaptive_options(const NormalFieldOptions& o, const LoadedVolume& loaded) {
    const double voxel = loaded.volume.grid.spacing.maxCoeff();
    AdaptiveNormalOptions adaptive;
    adaptive.max_radius = o.max_radius ? *o.max_radius : 14.0 * voxel;  // docs/accuracy.md: 14 beats 7 and 10
    // Every voxel is in a ball of its own kind of radius the smallest spacing: 2 of it is never
    // above the local thickness.
    adaptive.min_radius = std::min(2.0 * loaded.volume.grid.spacing.minCoeff(), adaptive.max_radius);
    adaptive.reach_factor = 1.5;
    adaptive.extrapolation_min_radius = 6.0 * voxel;
    // The thin-part weights measure the reach up to --alpha-reach + one voxel (thin_part_reach_cap):
    // with the default, the same cap, so they take these maps (keep_reach_maps) instead of their own.
    adaptive.reach_cap = thin_part_reach_cap(RegularizationExtensions{}, loaded.volume.grid);
    adaptive.keep_reach_maps = true;
    adaptive.smoothing_steps = 4;       // on thin parts, whose small balls are noisy
    adaptive.smoothing_below = 5.0 * voxel;
    adaptive.noisy_smoothing_steps = o.noisy_smoothing_steps.value_or(kDefaultNoisySmoothingSteps);
    adaptive.kernel = parse_integral_invariant_kernel(o.ii_kernel);
    adaptive.extrapolation_threshold_deg = o.extrapolation_threshold_deg.value_or(adaptive.extrapolation_threshold_deg);
    return adaptive;
}

double default_field_radius(const NormalFieldOptions& o, const std::string& kind, const LoadedVolume& loaded) {
    const bool ii = kind == "ii";
    const double voxel = loaded.volume.grid.spacing.maxCoeff();
    double radius = 3.0 * voxel;
    if (loaded.shape)
        radius = std::min(3.0 * std::cbrt(loaded.h), (loaded.shape->upper - loaded.shape->lower).maxCoeff() / 8.0);
    else if (ii && o.ii_kernel == "biweight")
        radius = 5.0 * voxel;
    return ii && o.ii_extrapolate ? 2.0 * radius : radius;
}

NormalFieldReach normal_field_reach(const NormalFieldOptions& o, const LoadedVolume& header) {
    if (field_kind(o) == "at")
        throw Error("--normals at cannot run block by block: its Ambrosio-Tortorelli solve couples the whole surface");
    if (!o.file.empty())
        throw Error("--normals-file cannot be read block by block: the file lists the field of the whole surface");
    NormalFieldReach reach;
    reach.options = o;
    const std::string kind = input_kind(o);
    if (kind != "ii" && kind != "ctrivial") return reach;
    const double radius = o.radius ? *o.radius : default_field_radius(o, kind, header);
    reach.options.radius = radius;
    (kind == "ii" ? reach.volume_radius : reach.surface_radius) = radius;
    return reach;
}

void parse_epsilon_range(const std::string& text, AmbrosioTortorelliParameters& at) {
    const std::size_t colon = text.find(':');
    if (colon == std::string::npos) {
        at.epsilon_start = at.epsilon_end = parse_epsilon(text, text);
        return;
    }
    at.epsilon_start = parse_epsilon(text.substr(0, colon), text);
    at.epsilon_end = parse_epsilon(text.substr(colon + 1), text);
}

void check_normal_field_options(const NormalFieldOptions& o, bool input_is_shape) {
    check_choices(o);
    check_combinations(o, input_is_shape);
    if (o.radius && (!(*o.radius > 0) || !std::isfinite(*o.radius))) throw Error("--radius must be positive");
    if (o.max_radius && (!(*o.max_radius > 0) || !std::isfinite(*o.max_radius)))
        throw Error("--ii-max-radius must be positive");
    if (o.max_radius && (o.radius || o.ii_extrapolate || input_kind(o) != "ii"))
        throw Error("--ii-max-radius applies to the adaptive integral invariants only (not with --radius, "
                    "--ii-extrapolate or another field)");
    if (o.noisy_smoothing_steps && (o.radius || o.ii_extrapolate || input_kind(o) != "ii"))
        throw Error("--ii-noise-smoothing applies to the adaptive integral invariants only (not with --radius, "
                    "--ii-extrapolate or another field)");
    if (o.noisy_smoothing_steps && *o.noisy_smoothing_steps < 0) throw Error("--ii-noise-smoothing must be zero or positive");
    const std::optional<double>& threshold = o.extrapolation_threshold_deg;
    if (threshold && (!(*threshold >= 0) || !std::isfinite(*threshold)))
        throw Error("--ii-extrapolation-threshold must be zero or positive (degrees)");
    if (threshold && (o.radius || o.ii_extrapolate || input_kind(o) != "ii"))
        throw Error("--ii-extrapolation-threshold applies to the adaptive integral invariants only (not with --radius, "
                    "--ii-extrapolate or another field)");
    if (field_kind(o) == "at") {
        validate_at_parameters(o.at);
        if (!(o.feature_threshold > 0 && o.feature_threshold <= 1))
            throw Error("--feature-threshold must be in (0, 1]");
    }
    errno = 0;
    if (!o.file.empty() && !std::ifstream(o.file))
        throw FileError("--normals-file " + o.file + ": cannot open the file", errno);
}

/// The lift of an estimated field into the surfels' half-spaces (not of the true normals of
/// --normals exact, nor of a file's field, which are the user's).
void lift_estimated_field(const NormalFieldOptions& o, const DigitalSurface& surface, NormalField& field) {
    if (!o.lift_margin || field_kind(o) == "exact" || (field_kind(o) != "at" && input_kind(o) == "file")) return;
    field.faces_against_surfels = faces_against_their_surfels(surface, field.normals);
    field.lifted_faces = lift_into_surfel_half_spaces(surface, field.normals, *o.lift_margin);
    if (field.lifted_faces > 0)
        field.description += "; " + std::to_string(field.lifted_faces) + " faces lifted to u.n >= " + format("%g", *o.lift_margin);
}

NormalField compute_normal_field(const NormalFieldOptions& o, const LoadedVolume& loaded, const DigitalSurface& surface,
                                 StageClock& clock) {
    NormalField field;
    clock.start("normals");
    PointMatrix g = estimate_input_field(o, loaded, surface, field);
    if (field_kind(o) != "at") {
        field.normals = std::move(g);
        lift_estimated_field(o, surface, field);
        clock.finish(field.description);
        return field;
    }
    clock.finish(field.description);
    clock.start("at");
    field.at = ambrosio_tortorelli_normals(surface, g, o.at);
    field.normals = field.at->normals;
    field.description = "Ambrosio-Tortorelli of " + field.description;
    lift_estimated_field(o, surface, field);
    clock.finish(at_stage_detail(*field.at, o.feature_threshold));
    return field;
}

void write_feature_lines(const std::string& path, const NormalFieldOptions& o, const NormalField& field,
                         const DigitalSurface& surface, const PointMatrix& positions) {
    if (path.empty() || !field.at) return;
    const auto lines = feature_polylines(surface.quads, surface.vertex_count(), field.at->features, o.feature_threshold);
    write_polylines_obj(path, positions, lines);
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

}  // namespace dsreg
