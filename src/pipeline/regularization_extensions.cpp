#include <algorithm>
#include <cmath>
#include <iostream>

#include "dsreg/clamped_regularization.hpp"
#include "dsreg/error.hpp"
#include "dsreg/label_surface.hpp"
#include "dsreg/local_weights.hpp"
#include "dsreg/regularization_metrics.hpp"
#include "dsreg/shrink_correction.hpp"
#include "dsreg/volume_io.hpp"
#include "pipeline_stages.hpp"

namespace dsreg {

namespace {

/// --noise-fairness when unset, the share of faces against their surfels that gets it in full,
/// and the rings of the neighbourhoods (docs/accuracy.md, "Noisy voxels"): a larger gain slows
/// the multigrid down (lobster.vol: 22 iterations without, 39 with 12, 42 with 15).
constexpr double kDefaultNoiseFairness = 12;
constexpr double kNoiseFullShare = 0.02;
constexpr int kNoiseRings = 3;
/// --keep-voxels leaves the voxels around a vertex as noise from this share of faces against
/// their surfel on (docs/validity.md, "Voxel centres": 0.05 keeps the noisy cases' normals and
/// puts bunny-64 and Al.100 over 99 % of their voxels; 0.1 costs the noisy thin torus 0.6°).
constexpr double kNoisyVoxelShare = 0.05;
/// Where the noise share ρ of a face reaches this, its thin-part weight takes the reach over
/// kNoisyReachRings rings instead of the adaptive field's 3 (docs/accuracy.md, "Thin parts or
/// noise"): noise makes every reach short, and a thin part's weight there pinned the mesh to the
/// flipped voxels (noisy sphere9: 12.4° → 8.2°).
constexpr double kThinPartNoiseShare = 0.2;

/// --junction-turn-share and --junction-turn-weight when unset (docs/multi-label.md, "Turns of
/// junction curves"): a turn held 0.39 voxel outside its chord (0.55 of the staircase's 0.71),
/// its fairness weighing at least 0.3 β (10 γ with the default weights).
constexpr double kDefaultJunctionTurnShare = 0.55;
constexpr double kDefaultJunctionTurnWeight = 0.3;

/// The faces' reach for the thin-part weights: the reach over kNoisyReachRings rings where the
/// surface is noisy, blended in as the noise share ρ of the face (mean of its vertices') rises to
/// kThinPartNoiseShare: a part thin only because of its flipped voxels is thick over a wider
/// neighbourhood, a thin part stays thin.
Eigen::VectorXd reach_beyond_noise(const DigitalSurface& surface, const ThinParts& parts, const Eigen::VectorXd& share) {
    Eigen::VectorXd reach = parts.reach;
    if (share.size() == 0 || parts.wide_reach.size() != reach.size()) return reach;
    const Eigen::VectorXd face_share = face_means(surface.quads, share);
    for (Eigen::Index f = 0; f < reach.size(); ++f)
        reach[f] += (parts.wide_reach[f] - reach[f]) * std::min(1.0, face_share[f] / kThinPartNoiseShare);
    return reach;
}

/// Where one local multiplier comes from.
struct WeightSource {
    const char* name;          ///< "alpha", "beta", "gamma"
    const std::string& map;    ///< scalar volume, or empty
    const std::string& file;   ///< text file, or empty
    bool per_face;             ///< beta: one value per face
};

std::vector<WeightSource> weight_sources(const RegularizationExtensions& o) {
    return {{"alpha", o.alpha_map, o.alpha_file, false},
            {"beta", o.beta_map, o.beta_file, true},
            {"gamma", o.gamma_map, o.gamma_file, false}};
}

Eigen::VectorXd read_multipliers(const WeightSource& w, const RegularizationExtensions& o, const DigitalSurface& surface) {
    if (!w.file.empty())
        return read_values_file(w.file, w.per_face ? surface.face_count() : surface.vertex_count(),
                                std::string(w.per_face ? "per-face " : "per-vertex ") + w.name);
    VolumeLimits limits;
    limits.max_voxels = o.max_voxels;
    RawVolumeLayout layout = o.map_raw_layout;  // a .raw map: the input's value type, on the surface's grid
    layout.dims = surface.grid.dims;
    const ScalarVolume map = read_volume_values(w.map, &layout, limits);
    const Eigen::VectorXd at_vertices = sample_at_vertices(map, surface);
    return w.per_face ? face_means(surface.quads, at_vertices) : at_vertices;
}

Eigen::VectorXd& multiplier_slot(RegularizationWeights& weights, const std::string& name) {
    if (name == "alpha") return weights.vertex_alpha;
    if (name == "beta") return weights.face_beta;
    return weights.vertex_gamma;
}

const Eigen::VectorXd& multiplier_of(const RegularizationWeights& weights, const std::string& name) {
    if (name == "alpha") return weights.vertex_alpha;
    if (name == "beta") return weights.face_beta;
    return weights.vertex_gamma;
}

nlohmann::json local_weights_json(const RegularizationExtensions& o, const RegularizationWeights& weights) {
    nlohmann::json json = nlohmann::json::object();
    for (const WeightSource& w : weight_sources(o)) {
        const Eigen::VectorXd& values = multiplier_of(weights, w.name);
        if (values.size() == 0 || (w.map.empty() && w.file.empty())) {  // none, or only the thin-part or noise weights
            json[w.name] = nullptr;
            continue;
        }
        json[w.name] = {{"source", w.file.empty() ? "map" : "file"},
                        {"path", w.file.empty() ? w.map : w.file},
                        {"min", values.minCoeff()},
                        {"max", values.maxCoeff()},
                        {"mean", values.mean()}};
    }
    return json;
}

nlohmann::json clamp_json(const RegularizationExtensions& o, const ClampedRegularizationResult& r, const RegularizationWeights& w,
                          const VoxelAgreement& clamped, const VoxelAgreement& unclamped) {
    const BoxQpReport& q = r.clamp.qp;
    return {{"half_width_voxels", o.clamp_half_width},
            {"tolerance", o.clamp_tolerance},
            {"converged", q.converged},
            {"kkt_residual", q.kkt_residual},
            {"stationarity", q.stationarity},
            {"multiplier_sign", q.multiplier_sign},
            {"constraint_violation", q.constraint_violation},
            {"coordinates_at_lower", q.at_lower},
            {"coordinates_at_upper", q.at_upper},
            {"clamped_vertices", r.clamp.clamped_vertices},
            {"admm_iterations", q.admm_iterations},
            {"admm_rho", q.admm_rho},
            {"active_set_iterations", q.active_set_iterations},
            {"active_set_cycled", q.active_set_cycled},
            {"newton_iterations", q.newton_iterations},
            {"factorizations", q.factorizations},
            {"cg_iterations", q.cg_iterations},
            {"factor_nonzeros", q.factor_nonzeros},
            {"seconds", {{"unclamped_solve", q.unconstrained_seconds},
                         {"admm", q.admm_seconds},
                         {"active_set", q.active_set_seconds}}},
            {"unclamped", {{"relative_residual", q.unconstrained_residual},
                           {"vertices_outside_box", r.clamp.unclamped_vertices_outside},
                           {"max_excess_voxels", r.clamp.unclamped_max_excess},
                           {"energy", energy_json(r.clamp.unclamped_energy, w)},
                           {"voxel_centres_wrong", unclamped.wrong()}}},
            {"voxel_centres", {{"total", clamped.total},
                               {"correct", clamped.correct},
                               {"object_outside", clamped.object_outside},
                               {"background_inside", clamped.background_inside}}}};
}

/// The share ρ of the faces within kNoiseRings rings of each vertex whose estimated normal points
/// into the object (the noise fairness's, uncapped); empty when no face does.
Eigen::VectorXd noise_share(const DigitalSurface& surface, const NormalField& field) {
    if (field.faces_against_surfels.empty()) return {};
    // With gain 1 and full share 1 the multiplier is 1 + ρ².
    const Eigen::VectorXd multiplier = noise_fairness_gamma(surface, field.faces_against_surfels, 1.0, 1.0, kNoiseRings);
    return (multiplier.array() - 1).max(0.0).sqrt().matrix();
}

}  // namespace

double noise_fairness(const RegularizationExtensions& o) {
    return o.noise_fairness ? *o.noise_fairness : kDefaultNoiseFairness;
}

Eigen::VectorXd noise_multipliers(const RegularizationExtensions& o, const DigitalSurface& surface, const NormalField& field) {
    if (!(noise_fairness(o) > 0) || field.faces_against_surfels.empty()) return Eigen::VectorXd();
    return noise_fairness_gamma(surface, field.faces_against_surfels, noise_fairness(o), kNoiseFullShare, kNoiseRings);
}

std::vector<char> noisy_voxel_vertices(const DigitalSurface& surface, const NormalField& field) {
    const Eigen::VectorXd share = noise_share(surface, field);
    std::vector<char> noisy(std::size_t(share.size()), 0);
    for (Eigen::Index v = 0; v < share.size(); ++v) noisy[std::size_t(v)] = share[v] >= kNoisyVoxelShare;
    return noisy;
}

double alpha_reach(const RegularizationExtensions& o, const VoxelGrid& grid) {
    return o.alpha_reach ? *o.alpha_reach : 12.0 * grid.spacing.maxCoeff();
}

double thin_part_reach_cap(const RegularizationExtensions& o, const VoxelGrid& grid) {
    return alpha_reach(o, grid) + grid.spacing.maxCoeff();
}

double sheet_alpha_reach(const RegularizationExtensions& o, const VoxelGrid& grid) {
    return o.alpha_reach_sheet ? *o.alpha_reach_sheet : 2.0 * grid.spacing.maxCoeff();
}

nlohmann::json energy_json(const EnergyTerms& e, const RegularizationWeights& w) {
    return {{"data", e.data}, {"alignment", e.alignment}, {"fairness", e.fairness}, {"total", e.total(w)}};
}

void check_regularization_extensions(const RegularizationExtensions& o) {
    if (o.alpha_reach && (!(*o.alpha_reach >= 0) || !std::isfinite(*o.alpha_reach)))
        throw Error("--alpha-reach must be zero (off) or positive");
    if (o.alpha_reach_sheet && (!(*o.alpha_reach_sheet >= 0) || !std::isfinite(*o.alpha_reach_sheet)))
        throw Error("--alpha-reach-sheet must be zero (no weight on sheets) or positive");
    if (o.noise_fairness && (!(*o.noise_fairness >= 0) || !std::isfinite(*o.noise_fairness)))
        throw Error("--noise-fairness must be zero (off) or positive");
    if (o.junction_turn_share && (!(*o.junction_turn_share >= 0) || !(*o.junction_turn_share <= 1)))
        throw Error("--junction-turn-share must be between 0 (off: the chord) and 1 (the staircase's corner)");
    if (o.junction_turn_weight && (!(*o.junction_turn_weight >= 0) || !std::isfinite(*o.junction_turn_weight)))
        throw Error("--junction-turn-weight must be zero or positive");
    if (o.shrink_correction && *o.shrink_correction < 0) throw Error("--shrink-correction must be 0 (off) or positive");
    if (o.shrink_local_steps && *o.shrink_local_steps < 0) throw Error("--shrink-local-steps must be 0 (off) or positive");
    if (o.shrink_wide_steps && *o.shrink_wide_steps < 0) throw Error("--shrink-wide-steps must be 0 (off) or positive");
    if (o.shrink_wide_tolerance && !(*o.shrink_wide_tolerance >= 0 && std::isfinite(*o.shrink_wide_tolerance)))
        throw Error("--shrink-wide-tolerance must be zero or positive and finite");
    if (o.shrink_correction && *o.shrink_correction > 0 && o.clamp)
        throw Error("--shrink-correction moves vertices out of the --clamp boxes: do not combine them");
    if (!(o.clamp_tolerance > 0) || !std::isfinite(o.clamp_tolerance)) throw Error("--clamp-tolerance must be positive");
    if (!(o.clamp_half_width > 0) || !std::isfinite(o.clamp_half_width)) throw Error("--clamp-half-width must be positive");
    parse_metric_kind(o.metric);
    for (const WeightSource& w : weight_sources(o))
        if (!w.map.empty() && !w.file.empty())
            throw Error(std::string("give either --") + w.name + "-map or --" + w.name + "-file, not both");
}

Eigen::VectorXd local_shrink_share(const DigitalSurface& surface, const Eigen::VectorXd& thin_alpha,
                                   const Eigen::VectorXd& noise_gamma) {
    if (thin_alpha.size() == 0) return {};
    constexpr double kThinTubeAlpha = 9;  // (R/ρ)² > 9: ρ < R/3, 4 voxels with the default R
    Eigen::VectorXd share = Eigen::VectorXd::Zero(surface.face_count());
    for (std::int64_t f = 0; f < surface.face_count(); ++f) {
        bool thin = false, noisy = false;
        for (int k = 0; k < 4; ++k) {
            const std::int32_t v = surface.quads(f, k);
            thin |= thin_alpha[v] > kThinTubeAlpha;
            noisy |= noise_gamma.size() > 0 && noise_gamma[v] > 1;
        }
        share[f] = thin && !noisy ? 1.0 : 0.0;
    }
    return share;
}

namespace {

/// The fairness targets and multipliers of the turns of junction curves (label maps only).
void hold_junction_turns(const RegularizationExtensions& o, const DigitalSurface& surface, RegularizationWeights& weights) {
    const double share = o.junction_turn_share.value_or(kDefaultJunctionTurnShare);
    // Without fairness (γ = 0) there is no term to offset.
    if (share == 0 || !(weights.gamma > 0) || !may_have_junctions(surface)) return;
    const ComplexEdges edges = complex_edges(surface);
    weights.fairness_targets = junction_turn_targets(surface, edges, fairness_links(surface, edges), share);
    if (weights.fairness_targets.rows() == 0) return;
    // The offset competes with the alignment of the sheets meeting there (β), not with the
    // fairness elsewhere: at γ alone a turn would move about γ·δ/(2β), nothing.
    const double least = o.junction_turn_weight.value_or(kDefaultJunctionTurnWeight) * weights.beta / weights.gamma;
    if (weights.vertex_gamma.size() == 0) weights.vertex_gamma = Eigen::VectorXd::Ones(surface.vertex_count());
    for (std::int64_t v = 0; v < surface.vertex_count(); ++v)
        if (!weights.fairness_targets.row(v).isZero(0.0)) weights.vertex_gamma[v] = std::max(weights.vertex_gamma[v], least);
}

}  // namespace

Eigen::VectorXd apply_regularization_extensions(const RegularizationExtensions& o, const DigitalSurface& surface,
                                                const NormalField& field, const ThinParts& thin_parts,
                                                RegularizationWeights& weights) {
    check_regularization_extensions(o);
    apply_metric(parse_metric_kind(o.metric), surface, field.normals, weights);
    for (const WeightSource& w : weight_sources(o))
        if (!w.map.empty() || !w.file.empty()) multiplier_slot(weights, w.name) = read_multipliers(w, o, surface);
    const Eigen::VectorXd noisy = noise_multipliers(o, surface, field);
    if (noisy.size() > 0)
        weights.vertex_gamma = weights.vertex_gamma.size() > 0 ? Eigen::VectorXd(weights.vertex_gamma.cwiseProduct(noisy)) : noisy;
    hold_junction_turns(o, surface, weights);
    Eigen::VectorXd thin;
    if (thin_parts.reach.size() > 0) {
        thin = thin_part_alpha(surface, reach_beyond_noise(surface, thin_parts, noise_share(surface, field)),
                               alpha_reach(o, surface.grid), thin_parts.sheetness, sheet_alpha_reach(o, surface.grid));
        weights.vertex_alpha = weights.vertex_alpha.size() > 0 ? Eigen::VectorXd(weights.vertex_alpha.cwiseProduct(thin)) : thin;
    }
    validate_weights(weights, surface.vertex_count(), surface.face_count());
    return local_shrink_share(surface, thin, noisy);
}

RegularizationResult run_regularization(const RegularizationExtensions& o, const BinaryVolume& volume, const DigitalSurface& surface,
                                        const PointMatrix& normals, const RegularizationWeights& weights,
                                        const Eigen::VectorXd& local_shrink, const SolverOptions& solver,
                                        nlohmann::json& report) {
    report["metric"] = o.metric;
    report["local_weights"] = local_weights_json(o, weights);
    if (weights.fairness_targets.rows() > 0)
        report["junction_turns"] = {{"vertices", (weights.fairness_targets.rowwise().squaredNorm().array() > 0).count()},
                                    {"share", o.junction_turn_share.value_or(kDefaultJunctionTurnShare)},
                                    {"weight", o.junction_turn_weight.value_or(kDefaultJunctionTurnWeight)}};
    if (!o.clamp) {
        RegularizationResult result = regularize(surface, normals, weights, solver);
        ShrinkAveraging averaging;
        averaging.steps = o.shrink_correction.value_or(averaging.steps);
        if (averaging.steps == 0) return result;
        averaging.wide_steps = o.shrink_wide_steps.value_or(averaging.wide_steps);
        averaging.wide_tolerance = o.shrink_wide_tolerance.value_or(averaging.wide_tolerance);
        averaging.local_steps = o.shrink_local_steps.value_or(10);
        if (averaging.local_steps > 0) averaging.local_share = local_shrink;
        const ShrinkCorrection correction = correct_shrink(surface, result.positions, normals, averaging);
        const EnergyTerms solved = result.energy_after;
        result.positions = correction.positions;
        result.energy_after = regularization_energy(result.positions, surface.vertices, surface.quads,
                                                    fairness_links(surface), normals, weights);
        const Eigen::VectorXd& local = averaging.local_share;
        report["shrink_correction"] = {{"steps", averaging.steps},
                                       {"wide_steps", averaging.wide_steps > averaging.steps ? averaging.wide_steps : 0},
                                       {"wide_tolerance_voxels", averaging.wide_tolerance},
                                       {"local_steps", averaging.local_steps},
                                       {"local_faces", local.size() > 0 ? (local.array() > 0).count() : 0},
                                       {"mean_shift", correction.mean_shift},
                                       {"max_shift", correction.max_shift},
                                       {"energy_of_the_solve", solved.total(weights)}};
        return result;
    }

    ClampOptions clamp;
    clamp.qp.tolerance = o.clamp_tolerance;
    clamp.qp.progress = solver.progress;
    clamp.half_width = o.clamp_half_width;
    clamp.solver = solver;
    const ClampedRegularizationResult result = regularize_clamped(surface, normals, weights, clamp);
    const VoxelAgreement clamped = classify_voxel_centres(volume, result.positions, surface.quads);
    const VoxelAgreement unclamped = classify_voxel_centres(volume, result.unclamped_positions, surface.quads);
    report["clamp"] = clamp_json(o, result, weights, clamped, unclamped);
    if (!result.clamp.qp.converged)
        std::cerr << "dsreg: warning: the clamped solve stopped at a relative KKT residual of " << result.clamp.qp.kkt_residual
                  << ", above --clamp-tolerance " << o.clamp_tolerance << '\n';
    return result;
}

}  // namespace dsreg
