// dsreg-mpi — `dsreg regularize` over MPI: the same command line (apps/regularize_command.hpp),
// run under mpirun or srun; one block of the volume per rank, PETSc's CG + algebraic multigrid
// for the solve, one welded mesh written by rank 0 (include/dsreg/distributed.hpp,
// docs/scaling.md).
#include <CLI/CLI.hpp>
#include <iostream>

#include "dsreg/distributed.hpp"
#include "dsreg/error.hpp"
#include "regularize_command.hpp"

namespace {

void run(dsreg::cli::RegularizeCommand& command, const dsreg::DistributedSession& session) {
    dsreg::run_collectively(MPI_COMM_WORLD, [&] { dsreg::cli::apply_and_check_flags(command); });
    const bool root = session.rank() == 0;
    const dsreg::ProgressCallback progress =
        dsreg::cli::stage_lines(root && dsreg::cli::stage_lines_shown(command.flags), "dsreg-mpi: ");
    dsreg::PipelineResult result = dsreg::run_distributed_pipeline(MPI_COMM_WORLD, command.source, command.options, progress);
    dsreg::write_distributed_outputs(MPI_COMM_WORLD, result, command.options, command.outputs, command.source, progress);
    if (!root || command.flags.quiet) return;
    const auto& blocks = result.extension_report["blocks"];
    std::cerr << "dsreg-mpi: " << dsreg::summary_line(result, command.options) << "; " << session.size()
              << (session.size() == 1 ? " rank" : " ranks") << ", largest rank peak "
              << dsreg::human_bytes(double(blocks["largest_rank_peak_memory_bytes"].get<std::int64_t>())) << " -> "
              << command.outputs.mesh << '\n';
}

}  // namespace

int main(int argc, char** argv) {
    dsreg::cli::restart_with_passive_openmp_waiting(argv);
    dsreg::DistributedSession session(&argc, &argv);
    const bool root = session.rank() == 0;
    CLI::App app{"dsreg-mpi: dsreg regularize over MPI (mpirun -np N dsreg-mpi INPUT -o OUT ...): one block of the "
                 "volume per rank, PETSc CG + algebraic multigrid, one mesh written by rank 0",
                 "dsreg-mpi"};
    app.set_version_flag("--version", std::string("dsreg-mpi ") + DSREG_VERSION);
    dsreg::cli::RegularizeCommand command;
    dsreg::cli::add_regularize_flags(app, command);
    try {
        app.parse(argc, argv);
        run(command, session);
    } catch (const CLI::ParseError& e) {
        if (e.get_exit_code() == static_cast<int>(CLI::ExitCodes::Success)) return root ? app.exit(e) : 0;  // --help
        if (root) std::cerr << "dsreg-mpi: error: " << e.what() << "\n(see 'dsreg-mpi --help')\n";
        return 1;
    } catch (const std::exception& e) {  // dsreg::Error: the same on every rank (run_collectively)
        if (root) std::cerr << "dsreg-mpi: error: " << e.what() << '\n';
        return 1;
    }
    return 0;
}
