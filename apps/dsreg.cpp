// dsreg — command-line tool: digital surface regularization by normal vector field alignment.
#include <CLI/CLI.hpp>
#include <cstdlib>
#include <iostream>

#include "dsreg/error.hpp"
#include "convergence_command.hpp"
#include "digitize_command.hpp"
#include "eval_command.hpp"
#include "regularize_command.hpp"
#include "view_command.hpp"

int main(int argc, char** argv) {
    dsreg::cli::restart_with_passive_openmp_waiting(argv);
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
