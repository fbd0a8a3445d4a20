// dsreg CLI — `dsreg regularize`: the whole pipeline, volume → mesh file. Its command line is
// also dsreg-mpi's (apps/mpi/) and, but for the block-wise flags, the Python module's keywords.
#pragma once

#include <CLI/CLI.hpp>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "dsreg/pipeline.hpp"
#include "dsreg/progress.hpp"

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
    std::vector<std::int64_t> block_size;  ///< --block-size N or X,Y,Z
    std::optional<std::int64_t> coarse_spacing;  ///< --coarse-spacing (unset: BlockOptions' default)
    std::string coarse_space = "normals";        ///< --coarse-space normals|xyz
    std::string solver = "auto";
    int connectivity = 26;
    std::string space = "lps";
    bool quiet = false, verbose = false, progress = false;
    bool no_repair = false, no_check = false;
    bool keep_voxels = false, no_keep_voxels = false;
};

struct RegularizeCommand {
    VolumeSource source;
    PipelineOptions options;
    PipelineOutputs outputs;
    CliFlags flags;
};

/// Registers the flags of the pipeline on `command`, writing into `c`: the volume source (but
/// the input file), --space, --connectivity, the normal field, the regularization extensions, the
/// weights, --solver, --max-error and the optional outputs (--input-mesh, --report, --export-normals,
/// --features, --triangulate); not -o, --quiet, --verbose. The one definition of these flags:
/// `dsreg regularize` and the Python module's keyword options (dsreg.regularize) both parse them.
void add_pipeline_flags(CLI::App& command, RegularizeCommand& c);

/// Registers the flags of block-wise runs (--block-size, --block-halo, --schwarz-sweeps, --coarse-spacing,
/// --fragments; include/dsreg/block_pipeline.hpp, docs/scaling.md) on `command`, writing into
/// `c`. Not keyword options of the Python module: block-wise runs stream a volume file, and its
/// arrays are in memory already.
void add_block_flags(CLI::App& command, RegularizeCommand& c);

/// Registers the whole command line of `dsreg regularize` on `command`: the input file, -o,
/// add_pipeline_flags, add_block_flags, --quiet and --verbose. dsreg-mpi registers the same.
void add_regularize_flags(CLI::App& command, RegularizeCommand& c);

/// The library's structs from the flags that the command line spells differently (raw layout,
/// --spacing, --solver, --connectivity, --at-eps, --block-size); refuses --at-* flags without
/// --normals at, and --block-halo or --schwarz-sweeps without --block-size. Call after parsing.
/// Throws dsreg::Error.
void apply_flags(RegularizeCommand& c);

/// apply_flags, then the library's checks of the options and output paths (before any work).
/// Throws dsreg::Error.
void apply_and_check_flags(RegularizeCommand& c);

/// The stage lines on stderr ("dsreg: surface    0.024 s  37590 surfels, …", as each stage ends)
/// if `shown`, else nothing. `prefix` starts each line (e.g. "dsreg: ").
ProgressCallback stage_lines(bool shown, const std::string& prefix);

/// Whether stage lines are shown: --verbose, or stderr is a terminal, unless --quiet.
bool stage_lines_shown(const CliFlags& flags);

/// OpenMP workers that spin while waiting take the cores from the ones doing the work as soon as
/// anything else runs on the machine (measured: bunny-128 8 s instead of 2.3 s under load). The
/// OpenMP runtime reads OMP_WAIT_POLICY when it is loaded, before main, so when the user has not
/// chosen a policy, run this program again with the passive one (sleeping workers). Returns
/// only if that was not needed or not possible. Called first by dsreg and dsreg-mpi.
void restart_with_passive_openmp_waiting(char** argv);

/// Registers the `regularize` subcommand on `app`; running it executes the pipeline.
void add_regularize_command(CLI::App& app);

}  // namespace dsreg::cli
