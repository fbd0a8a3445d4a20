// dsreg CLI — `dsreg regularize`: the flags of the pipeline (regularize_flags.hpp, shared with
// dsreg-mpi), its stage lines and its summary line. Everything else happens in the library.
#include "regularize_command.hpp"

#include <iostream>
#include <memory>

#include "dsreg/error.hpp"
#include "dsreg/pipeline.hpp"
#include "regularize_flags.hpp"

namespace dsreg::cli {

namespace {

void run(RegularizeFlags& c) {
    apply_regularize_flags(c);
    if (!c.outputs.fragments.empty() && !c.options.blocks.enabled())
        throw Error("--fragments needs a block-wise run: give --block-size (or run dsreg-mpi)");
    const ProgressCallback progress = stage_lines(stage_lines_shown(c), "dsreg: ");
    PipelineResult result = run_pipeline(c.source, c.options, progress);
    write_pipeline_outputs(result, c.options, c.outputs, c.source, progress);
    if (c.quiet) return;
    for (const std::string& warning : result.warnings) std::cerr << "dsreg: warning: " << c.source.input_path << ": " << warning << '\n';
    std::cerr << "dsreg: " << summary_line(result, c.options) << " -> " << c.outputs.mesh
              << (result.file.world_geometry ? " (" + output_space_name(c.outputs.space) + ")" : "") << '\n';
}

}  // namespace

void add_regularize_command(CLI::App& app) {
    auto c = std::make_shared<RegularizeFlags>();
    CLI::App* cmd = app.add_subcommand("regularize", "Regularize the digital surface of a volume into a smooth quad mesh");
    add_regularize_flags(*cmd, *c);
    cmd->callback([c] { run(*c); });
}

}  // namespace dsreg::cli
