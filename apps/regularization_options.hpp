// dsreg CLI — options of `dsreg regularize` beyond the paper: clamped ("reversible") mode,
// area metrics, and local weights α_i, β_f, γ_i from volumes or text files.
//
//   --clamp                    minimize under the boxes |p̂ − p| ≤ half-width · spacing per axis
//   --clamp-tolerance T        relative KKT residual to reach (default 1e-10)
//   --clamp-half-width W       box half-width in voxels (default 0.499; < 0.5 keeps every voxel
//                              centre strictly off the surface, see docs/clamped.md)
//   --metric identity|area     W0, W2 of §3.4 (default identity)
//   --alpha-map / --beta-map / --gamma-map VOLUME
//                              local multipliers sampled from a scalar volume on the same grid
//                              (mean of the 8 voxels around each vertex; faces: mean of their 4
//                              vertices). A .raw map uses --raw-type/--raw-big-endian/
//                              --raw-header-bytes and the input's dimensions.
//   --alpha-file / --beta-file / --gamma-file FILE
//                              one value per vertex (alpha, gamma) or per face (beta), in mesh order
#pragma once

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>
#include <string>

#include "dsreg/digital_surface.hpp"
#include "dsreg/mesh.hpp"
#include "dsreg/regularization.hpp"
#include "dsreg/solvers.hpp"
#include "dsreg/volume.hpp"
#include "volume_source.hpp"

namespace dsreg::cli {

struct ExtensionOptions {
    bool clamp = false;
    double clamp_tolerance = 1e-10;
    double clamp_half_width = 0.499;
    std::string metric = "identity";
    std::string alpha_map, beta_map, gamma_map;     ///< scalar volumes
    std::string alpha_file, beta_file, gamma_file;  ///< text files, mesh order
};

/// Registers the options above on `command`.
void add_regularization_extension_options(CLI::App& command, ExtensionOptions& options);

/// Checks what can be checked before any work (values in range, a map and a file given for the
/// same weight). Throws dsreg::Error naming the option.
void check_regularization_extension_options(const ExtensionOptions& options);

/// Fills the metric (W0, W2) and the local multipliers of `weights` for this surface and normal
/// field, reading the maps or files, then validates the weights. Throws dsreg::Error.
void apply_regularization_extensions(const ExtensionOptions& options, const VolumeSourceOptions& source,
                                     const DigitalSurface& surface, const PointMatrix& normals,
                                     RegularizationWeights& weights);

/// regularize() with `solver`, or with --clamp regularize_clamped() (CHOLMOD throughout, whatever
/// the --solver choice). `report` receives the JSON fields of the
/// extensions: "metric", "local_weights" and, with --clamp, "clamp" (KKT residual, constraint
/// violation, iterations, unclamped comparison, voxel-centre classification of `volume`).
RegularizationResult run_regularization(const ExtensionOptions& options, const BinaryVolume& volume,
                                        const DigitalSurface& surface, const PointMatrix& normals,
                                        const RegularizationWeights& weights, const SolverOptions& solver,
                                        nlohmann::json& report);

}  // namespace dsreg::cli
