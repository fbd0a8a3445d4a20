// dsreg CLI — `dsreg regularize`: the whole pipeline, volume → mesh file.
#pragma once

#include <CLI/CLI.hpp>
#include <cstdint>
#include <string>
#include <vector>

#include "dsreg/pipeline.hpp"

namespace dsreg::cli {

/// What the command line holds beyond the library's option structs.
struct CliFlags {
    std::vector<CLI::Option*> at_only;  ///< flags that apply only to --normals at
    std::string at_epsilon = "2:0.25";  ///< --at-eps ε1:ε2 (or a single ε)
    std::vector<std::int64_t> raw_dims;
    std::string raw_type = "uint8";
    bool raw_big_endian = false;
    std::uint64_t raw_header_bytes = 0;
    std::vector<double> spacing;
    std::string solver = "auto";
    int connectivity = 26;
    std::string space = "lps";
    bool quiet = false, verbose = false;
    bool no_repair = false, no_check = false;
};

struct RegularizeCommand {
    VolumeSource source;
    PipelineOptions options;
    PipelineOutputs outputs;
    CliFlags flags;
};

/// Registers the flags of the pipeline on `command`, writing into `c`: the volume source (but
/// the input file), --space, --connectivity, the normal field, the regularization extensions, the
/// weights, --solver and the optional outputs (--input-mesh, --report, --export-normals,
/// --features, --triangulate); not -o, --quiet, --verbose. The one definition of these flags:
/// `dsreg regularize` and the Python module's keyword options (dsreg.regularize) both parse them.
void add_pipeline_flags(CLI::App& command, RegularizeCommand& c);

/// The library's structs from the flags that the command line spells differently (raw layout,
/// --spacing, --solver, --connectivity, --at-eps); refuses --at-* flags without --normals at.
/// Call after parsing. Throws dsreg::Error.
void apply_flags(RegularizeCommand& c);

/// Registers the `regularize` subcommand on `app`; running it executes the pipeline.
void add_regularize_command(CLI::App& app);

}  // namespace dsreg::cli
