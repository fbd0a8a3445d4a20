// dsreg CLI — the command line of `dsreg regularize`, shared with `dsreg-mpi` (apps/mpi/): the
// flags of the pipeline (include/dsreg/pipeline.hpp), their translation into the library's
// option structs, and the stage lines. Both executables compile this one definition.
#pragma once

#include <CLI/CLI.hpp>
#include <string>
#include <vector>

#include "dsreg/pipeline.hpp"
#include "dsreg/progress.hpp"

namespace dsreg::cli {

/// What `dsreg regularize` reads from its command line: the library's option structs, and the
/// flags the command line spells differently.
struct RegularizeFlags {
    VolumeSource source;
    PipelineOptions options;
    PipelineOutputs outputs;

    std::vector<CLI::Option*> at_only;  ///< flags that apply only to --normals at
    std::string at_epsilon = "2:0.25";  ///< --at-eps ε1:ε2 (or a single ε)
    std::vector<std::int64_t> raw_dims;
    std::string raw_type = "uint8";
    bool raw_big_endian = false;
    std::uint64_t raw_header_bytes = 0;
    std::vector<double> spacing;
    std::vector<std::int64_t> block_size;  ///< --block-size N or X,Y,Z
    std::string solver = "auto";
    int connectivity = 26;
    std::string space = "lps";  ///< --space
    bool quiet = false, verbose = false;
};

/// Registers every flag of `dsreg regularize` on `command`, storing into `flags`.
void add_regularize_flags(CLI::App& command, RegularizeFlags& flags);

/// Fills the library's structs from the flags spelled differently, and checks the options and
/// output paths (before any work). Throws dsreg::Error naming the flag.
void apply_regularize_flags(RegularizeFlags& flags);

/// The stage lines on stderr ("dsreg: surface    0.024 s  37590 surfels, …", as each stage ends)
/// if `shown`, else nothing. `prefix` starts each line (e.g. "dsreg: ").
ProgressCallback stage_lines(bool shown, const std::string& prefix);

/// Whether stage lines are shown: --verbose, or stderr is a terminal, unless --quiet.
bool stage_lines_shown(const RegularizeFlags& flags);

/// OpenMP workers that spin while waiting take the cores from the ones doing the work as soon as
/// anything else runs on the machine (measured: bunny-128 8 s instead of 2.3 s under load). The
/// OpenMP runtime reads OMP_WAIT_POLICY when it is loaded, before main, so when the user has not
/// chosen a policy, run this program again with the passive one (sleeping workers). Returns
/// only if that was not needed or not possible.
void restart_with_passive_openmp_waiting(char** argv);

}  // namespace dsreg::cli
