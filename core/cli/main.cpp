// The `tetiso` command: argument parsing and error reporting only; every
// stage lives in the library. Any error is one line on stderr and exit 2.
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <string>
#include <thread>

#include <unistd.h>

#include "commands.hpp"
#include "tetiso/detail/write_atomically.hpp"
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

// The exit status of a secondary rank for an error every rank meets, which
// rank 0 reports: given after a moment, since the launcher aborts the job at
// the first non-zero exit and would otherwise kill rank 0 before it has said
// what went wrong. (Where rank 0 has not met the error, its own checks end
// the job within seconds: the start-up barrier, the controller's.)
int secondary_rank_exit(int status) {
    std::this_thread::sleep_for(std::chrono::seconds(2));
    return status;
}

// A message on one line whatever it quotes: a newline, a carriage return or
// another control byte from a file (a VTP attribute, a table field) or an
// argument is written as an escape, \n or \xHH, never as itself.
std::string one_line(const std::string& message) {
    std::string out;
    out.reserve(message.size());
    for (const char c : message) {
        const auto byte = static_cast<unsigned char>(c);
        if (c == '\n') {
            out += "\\n";
        } else if (c == '\r') {
            out += "\\r";
        } else if (c == '\t') {
            out += "\\t";
        } else if (byte < 0x20 || byte == 0x7f) {
            static const char hex[] = "0123456789abcdef";
            out += "\\x";
            out += hex[byte >> 4];
            out += hex[byte & 15];
        } else {
            out += c;
        }
    }
    return out;
}
// libgomp's threads wait for work by spinning before they sleep (its default
// wait policy); on a machine whose cores other processes also use, a
// spinning thread holds a core the thread it waits for needs, and a job with
// --threads equal to the core count slows by several times. Waiting
// passively costs a little on an idle machine and bounds the loss on a
// shared one. libgomp reads OMP_WAIT_POLICY when it is loaded, before
// main(): the process sets it and executes itself again, once, where the
// user set neither it nor GOMP_SPINCOUNT (then their choice stands). If the
// exec fails, the process goes on as it is.
void wait_passively_by_default(char** argv) {
    if (std::getenv("OMP_WAIT_POLICY") || std::getenv("GOMP_SPINCOUNT")) return;
    if (::setenv("OMP_WAIT_POLICY", "passive", 1) != 0) return;
    ::execv("/proc/self/exe", argv);
}

} // namespace

int main(int argc, char** argv) {
    wait_passively_by_default(argv);
    // A file-size limit (ulimit -f) then fails the write with EFBIG, which
    // the writer reports and cleans up after, instead of killing the process
    // with SIGXFSZ and leaving its temporary file behind.
    std::signal(SIGXFSZ, SIG_IGN);
    // Ctrl-C, a job's end (SIGTERM) or a closed terminal (SIGHUP) during a
    // write removes the outputs' temporaries before the process ends.
    tetiso::detail::remove_temporaries_on_signals();
    CLI::App app{"tetiso: reduced isosurfaces of large tetrahedral meshes, in parallel"};
    app.require_subcommand(1);
    app.set_version_flag("--version", "tetiso 0.1.0");
    tetiso::cli::Command run;
    tetiso::cli::add_extract_command(app, run);
    tetiso::cli::add_check_command(app, run);
    tetiso::cli::add_run_command(app, run);
    tetiso::cli::add_reduce_command(app, run);
    tetiso::cli::add_split_command(app, run);
    tetiso::cli::require_decimal_integers(app);
    tetiso::cli::refuse_meaningless_combinations(app);
    try {
        app.parse(argc, argv);
    } catch (const CLI::CallForHelp& e) {
        return app.exit(e);
    } catch (const CLI::CallForAllHelp& e) {
        return app.exit(e);
    } catch (const CLI::CallForVersion& e) {
        return app.exit(e);
    } catch (const CLI::ParseError& e) {
        if (is_secondary_rank()) return secondary_rank_exit(2);
        std::cerr << "tetiso: " << one_line(e.what()) << " (see tetiso --help)\n";
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
        if (is_secondary_rank()) return secondary_rank_exit(2);
        std::cerr << "tetiso: " << one_line(e.what()) << '\n';
        return 2;
    } catch (const std::bad_alloc&) {
        std::cerr << "tetiso: out of memory\n";
        return 2;
    } catch (const std::exception& e) {
        std::cerr << "tetiso: internal error: " << one_line(e.what()) << '\n';
        return 3;
    }
    return 0;
}
