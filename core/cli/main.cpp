// The `tetiso` command: argument parsing and error reporting only; every
// stage lives in the library. Any error is one line on stderr and exit 2.
#include <cstdio>
#include <cstdlib>
#include <iostream>

#include "commands.hpp"
#include "tetiso/error.hpp"
#include "tetiso/schedule.hpp"

namespace {
// Under an MPI launcher every rank parses the same arguments and meets the
// same errors; only rank 0 says so.
bool is_secondary_rank() {
    for (const char* variable : {"OMPI_COMM_WORLD_RANK", "PMI_RANK", "PMIX_RANK"})
        if (const char* value = std::getenv(variable)) return std::atoi(value) != 0;
    return false;
}
} // namespace

int main(int argc, char** argv) {
    CLI::App app{"tetiso: reduced isosurfaces of large tetrahedral meshes, in parallel"};
    app.require_subcommand(1);
    app.set_version_flag("--version", "tetiso 0.1.0");
    tetiso::cli::Command run;
    tetiso::cli::add_extract_command(app, run);
    tetiso::cli::add_check_command(app, run);
    tetiso::cli::add_run_command(app, run);
    tetiso::cli::add_reduce_command(app, run);
    tetiso::cli::add_split_command(app, run);
    try {
        app.parse(argc, argv);
    } catch (const CLI::CallForHelp& e) {
        return app.exit(e);
    } catch (const CLI::CallForAllHelp& e) {
        return app.exit(e);
    } catch (const CLI::CallForVersion& e) {
        return app.exit(e);
    } catch (const CLI::ParseError& e) {
        if (!is_secondary_rank()) std::cerr << "tetiso: " << e.what() << " (see tetiso --help)\n";
        return 2;
    }
    try {
        run();
    } catch (const tetiso::JobStopped&) {
        // Rank 0 reports the failure and exits non-zero, which fails the job.
        // A worker that exited non-zero first would make the launcher kill
        // rank 0 before it could say which task failed, and why.
        return 0;
    } catch (const tetiso::Error& e) {
        if (!is_secondary_rank()) std::cerr << "tetiso: " << e.what() << '\n';
        return 2;
    } catch (const std::bad_alloc&) {
        std::cerr << "tetiso: out of memory\n";
        return 2;
    } catch (const std::exception& e) {
        std::cerr << "tetiso: internal error: " << e.what() << '\n';
        return 3;
    }
    return 0;
}
