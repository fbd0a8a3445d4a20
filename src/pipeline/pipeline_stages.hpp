// dsreg pipeline — the stages of run_pipeline (include/dsreg/pipeline.hpp), one file each:
// normal_field.cpp, regularization_extensions.cpp; volume_source.cpp holds stage 1, result_page.cpp
// the --html page.
#pragma once

#include <nlohmann/json.hpp>
#include <string>

#include "dsreg/pipeline.hpp"
#include "stage_clock.hpp"

namespace dsreg {

/// The sum of the stage times of `result` (seconds).
double total_seconds(const PipelineResult& result);

/// Estimates (or reads) the input field and, for --normals at, regularizes it; stages "normals"
/// and "at" on `clock`.
NormalField compute_normal_field(const NormalFieldOptions& options, const LoadedVolume& loaded,
                                 const DigitalSurface& surface, StageClock& clock);

/// Writes the edges where v < threshold (AT feature lines) as OBJ polylines over `positions` to
/// `path`, if it is set and the field is an AT field.
void write_feature_lines(const std::string& path, const NormalFieldOptions& options, const NormalField& field,
                         const DigitalSurface& surface, const PointMatrix& positions);

/// The report's "at" object: parameters, per-ε rounds, change of v, energy, time, solves.
nlohmann::json at_report(const NormalFieldOptions& options, const NormalField& field, const DigitalSurface& surface);

/// The reference reach of --alpha-reach in physical units (its default: 12 voxels); 0 = off.
double alpha_reach(const RegularizationExtensions& options, const VoxelGrid& grid);

/// How far the thin-part weights measure the reach (physical units): alpha_reach + one voxel.
double thin_part_reach_cap(const RegularizationExtensions& options, const VoxelGrid& grid);

/// The reference reach of the thin sheets, --alpha-reach-sheet, in physical units (its default: 2
/// voxels).
double sheet_alpha_reach(const RegularizationExtensions& options, const VoxelGrid& grid);

/// Rings over which ThinParts::wide_reach takes the largest reach (8 by the accuracy suite's noisy
/// cases: 16 gave the same, docs/accuracy.md "Thin parts or noise").
constexpr int kNoisyReachRings = 8;

/// What the thin-part data weights are made from: the faces' reach (empty: no thin-part
/// weights) and, where the sheets get their own reference, the faces' sheetness (else empty).
struct ThinParts {
    Eigen::VectorXd reach, sheetness;
    /// The reach over a wider neighbourhood, taken where the surface is noisy (noise shortens
    /// every reach around it: apply_regularization_extensions).
    Eigen::VectorXd wide_reach;
};

/// The report's energy object: the three terms of eq. (1) without their weights, and the total.
nlohmann::json energy_json(const EnergyTerms& terms, const RegularizationWeights& weights);

/// The gain of --noise-fairness in use: the option's, or its default when unset (docs/accuracy.md, "Noisy voxels").
double noise_fairness(const RegularizationExtensions& options);

/// The fairness multipliers of the noise fairness for this surface and field (noise_fairness_gamma,
/// local_weights.hpp); empty when it is off or no face points against its surfel.
Eigen::VectorXd noise_multipliers(const RegularizationExtensions& options, const DigitalSurface& surface, const NormalField& field);

/// The vertices around which the voxels are noise for --keep-voxels (ValidityRepairOptions::
/// noisy_voxels): at least 5 % of the faces within about three rings point against their surfel
/// (the share ρ of noise_fairness_gamma, uncapped; docs/validity.md, "Voxel centres"). Empty
/// when no face does.
std::vector<char> noisy_voxel_vertices(const DigitalSurface& surface, const NormalField& field);

/// Fills the metric (W0, W2) and the local multipliers of `weights` for this surface and normal
/// field, reading the maps or files, the noise fairness multipliers (from the field's faces
/// against their surfels) and, given the thin parts' reach (empty: none), the thin-part data
/// weights; then validates the weights. Returns the faces whose shrink is corrected locally
/// (local_shrink_share; empty without thin-part weights). Throws dsreg::Error.
Eigen::VectorXd apply_regularization_extensions(const RegularizationExtensions& options, const DigitalSurface& surface,
                                                const NormalField& field, const ThinParts& thin_parts,
                                                RegularizationWeights& weights);

/// correct_shrink's local share: 1 on the faces that touch a vertex whose thin-part multiplier
/// exceeds 9 (a tube whose reach is below a third of its reference) unless they touch a vertex
/// whose fairness the noise fairness raised (there the local drift is the noise's), else 0.
/// Empty if `thin_alpha` is.
Eigen::VectorXd local_shrink_share(const DigitalSurface& surface, const Eigen::VectorXd& thin_alpha,
                                   const Eigen::VectorXd& noise_gamma);

/// regularize() with `solver` then correct_shrink() (--shrink-correction; the energy after is that
/// of the corrected positions), or with --clamp regularize_clamped() with the same solver choice.
/// `report` receives the JSON fields of the extensions: "metric",
/// "local_weights" and, with --clamp, "clamp" (KKT residual, constraint violation, iterations,
/// unclamped comparison, voxel-centre classification of `volume`).
RegularizationResult run_regularization(const RegularizationExtensions& options, const BinaryVolume& volume,
                                        const DigitalSurface& surface, const PointMatrix& normals,
                                        const RegularizationWeights& weights, const Eigen::VectorXd& local_shrink,
                                        const SolverOptions& solver, nlohmann::json& report);

}  // namespace dsreg
