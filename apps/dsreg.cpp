// dsreg — command-line tool: digital surface regularization by normal vector field alignment.
#include <CLI/CLI.hpp>
#include <cstdlib>
#include <iostream>
#include <unistd.h>

#include "dsreg/error.hpp"
#include "convergence_command.hpp"
#include "digitize_command.hpp"
#include "eval_command.hpp"
#include "regularize_command.hpp"
#include "view_command.hpp"

namespace {

/// OpenMP workers that spin while waiting take the cores from the ones doing the work as soon as
/// anything else runs on the machine (measured: bunny-128 8 s instead of 2.3 s under load). The
/// OpenMP runtime reads OMP_WAIT_POLICY when it is loaded, before main, so when the user has not
/// chosen a policy, run this program again with the passive one (sleeping workers). Returns
/// only if that was not needed or not possible.
void restart_with_passive_openmp_waiting(char** argv) {
    if (std::getenv("OMP_WAIT_POLICY") != nullptr) return;
    if (setenv("OMP_WAIT_POLICY", "passive", 1) != 0) return;
    execv("/proc/self/exe", argv);  // on failure, go on with the runtime's default policy
}

}  // namespace

int main(int argc, char** argv) {
    restart_with_passive_openmp_waiting(argv);
    CLI::App app{"dsreg: smooth quad meshes from 3D binary images (digital surface regularization, DGCI 2017)",
                 "dsreg"};
    app.require_subcommand(1);
    app.set_version_flag("--version", std::string("dsreg ") + DSREG_VERSION);
    dsreg::cli::add_regularize_command(app);
    dsreg::cli::add_eval_command(app);
    dsreg::cli::add_convergence_command(app);
    dsreg::cli::add_digitize_command(app);
    dsreg::cli::add_view_command(app);
    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
        if (e.get_exit_code() == static_cast<int>(CLI::ExitCodes::Success)) return app.exit(e);  // --help, --version
        std::cerr << "dsreg: error: " << e.what() << "\n(see 'dsreg --help' or 'dsreg COMMAND --help')\n";
        return 1;
    } catch (const dsreg::Error& e) {
        std::cerr << "dsreg: error: " << e.what() << '\n';
        return 1;
    } catch (const std::bad_alloc&) {
        std::cerr << "dsreg: error: out of memory\n";
        return 1;
    } catch (const std::exception& e) {
        std::cerr << "dsreg: error: " << e.what() << '\n';
        return 1;
    }
    return 0;
}
