// dsreg CLI — the normal field of `dsreg regularize`: its options (--normals, --radius,
// --normals-file, --at-*, --export-normals, --features), its computation and its report.
#pragma once

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "dsreg/ambrosio_tortorelli.hpp"
#include "dsreg/digital_surface.hpp"
#include "stage_clock.hpp"
#include "volume_source.hpp"

namespace dsreg::cli {

struct NormalFieldOptions {
    std::string kind = "ii";      ///< --normals: ii trivial ctrivial exact at
    std::string at_input = "ii";  ///< --at-input: the field g that AT regularizes
    std::optional<double> radius;
    std::string ii_kernel = "biweight";  ///< --ii-kernel: ball or biweight
    bool ii_extrapolate = false;         ///< --ii-extrapolate: 2·n(r/√2) − n(r)
    std::string file;             ///< --normals-file: g (with --normals at) or the field itself
    AmbrosioTortorelliParameters at;
    std::string at_epsilon = "2:0.25";  ///< --at-eps ε1:ε2 (or a single ε)
    std::string export_path;            ///< --export-normals
    std::string features_path;          ///< --features (OBJ polylines)
    double feature_threshold = 0.5;
    /// Options given on the command line, for the consistency checks.
    CLI::Option *normals_option = nullptr, *at_input_option = nullptr;
    std::vector<CLI::Option*> at_only_options;
};

/// Registers the options above on `command`.
void add_normal_field_options(CLI::App& command, NormalFieldOptions& options);

/// Checks the options against each other and parses --at-eps into options.at (before any long
/// computation). Throws dsreg::Error naming the option.
void check_normal_field_options(NormalFieldOptions& options, bool input_is_shape);

struct NormalField {
    PointMatrix normals;                          ///< the field the regularization uses
    std::string description;                      ///< e.g. "integral invariants, r = 3"
    std::string input;                            ///< ii, trivial, ctrivial, exact or file (g for AT)
    std::optional<double> radius;                 ///< radius used, if any
    std::optional<std::string> ii_kernel;         ///< kernel of the integral invariants, if used
    bool ii_extrapolated = false;                 ///< Richardson-extrapolated integral invariants
    std::optional<AmbrosioTortorelliResult> at;  ///< set for --normals at
};

/// Estimates (or reads) the input field and, for --normals at, regularizes it; stages "normals"
/// and "at" on `clock`. Writes --export-normals.
NormalField compute_normal_field(const NormalFieldOptions& options, const LoadedVolume& loaded,
                                 const DigitalSurface& surface, StageClock& clock);

/// Writes --features (the edges where v < threshold, as polylines over `positions`) if asked.
void write_feature_lines(const NormalFieldOptions& options, const NormalField& field, const DigitalSurface& surface,
                         const PointMatrix& positions);

/// The report's "at" object: parameters, per-ε rounds, change of v, energy, time, solves.
nlohmann::json at_report(const NormalFieldOptions& options, const NormalField& field, const DigitalSurface& surface);

}  // namespace dsreg::cli
