#pragma once

#include <filesystem>
#include <string>
#include <system_error>
#include <utility>
#include <vector>

#include "tetiso/error.hpp"

namespace tetiso {

namespace detail {
// Where an output named `path` is written: `path` itself, or the file a
// symbolic link there points to (the link is kept). Throws tetiso::Error
// naming `path` when something other than a regular file or a directory is
// there: a device, a pipe or a socket is never replaced by a file.
std::filesystem::path output_target(const std::filesystem::path& path);
// A new temporary name beside `target`: TARGET.tmp.PID.N.
std::filesystem::path temporary_sibling(const std::filesystem::path& target);
// Creates a new temporary beside `target` (temporary_sibling), exclusively:
// a file with O_EXCL, or an empty directory; remembers it for
// remove_temporaries_on_signals until forget_temporary. Throws
// tetiso::Error naming `path` (the output asked for) when it cannot.
std::filesystem::path create_temporary(const std::filesystem::path& target, bool directory,
                                       const std::filesystem::path& path);
// After the temporary was renamed into place or removed.
void forget_temporary(const std::filesystem::path& temporary);
// Installs handlers of SIGINT, SIGTERM and SIGHUP (those not ignored) that
// remove every temporary under way, then end the process by the same signal
// (its default action). For a program's main(); a library never installs it.
void remove_temporaries_on_signals();
// Removes the temporaries beside `target` whose writing process is gone
// (killed by SIGKILL or SIGXFSZ, say, before it could remove them).
void remove_stale_temporaries(const std::filesystem::path& target);
// Whether `a` and `b` name one file: the same device and inode where both
// exist (through links, hard links, "./" and ".."), else the same path once
// made absolute with every link resolved.
bool same_file(const std::filesystem::path& a, const std::filesystem::path& b);
// The message of an error a writer raised naming its temporary file, with
// the output's path in its place.
std::string name_output_in(std::string message, const std::filesystem::path& temporary,
                           const std::filesystem::path& path);
} // namespace detail

// The files one command writes, which succeed or fail together: each is
// written under a temporary name beside it as it comes (add), and all are
// renamed into place by commit(). Until then nothing is at the outputs'
// paths; an OutputFiles destroyed before commit() (a later output failed,
// or the work after it) removes its temporaries, leaving earlier files at
// those paths as they were.
class OutputFiles {
public:
    OutputFiles() = default;
    OutputFiles(const OutputFiles&) = delete;
    OutputFiles& operator=(const OutputFiles&) = delete;
    ~OutputFiles() { discard(); }

    // Runs `write` with the temporary path of `path`. An Error it throws
    // names `path`, not the temporary. Throws tetiso::Error when `path` is
    // the same file as an earlier output: the later rename would replace it.
    // With `directory`, the temporary is a new empty directory for `write`
    // to fill (with files only), otherwise a new empty file.
    template <class WriteFunction>
    void add(const std::filesystem::path& path, WriteFunction&& write, bool directory = false) {
        const std::filesystem::path target = detail::output_target(path);
        for (const Pending& p : pending_)
            if (detail::same_file(p.target, target))
                throw Error(path.string() + ": cannot write: it is the same file as the output " + p.path.string());
        detail::remove_stale_temporaries(target);
        const std::filesystem::path created = detail::create_temporary(target, directory, path);
        try {
            pending_.push_back({path, target, created});
        } catch (...) {
            std::error_code ignored;
            std::filesystem::remove_all(created, ignored);
            detail::forget_temporary(created);
            throw;
        }
        const std::filesystem::path& temporary = pending_.back().temporary;
        try {
            write(temporary);
        } catch (const Error& e) {
            throw Error(detail::name_output_in(e.what(), temporary, path));
        }
    }

    // Renames every output into place, in the order they were added.
    void commit() {
        while (!pending_.empty()) {
            const Pending& p = pending_.front();
            std::error_code ec;
            std::filesystem::rename(p.temporary, p.target, ec);
            if (ec) throw Error(p.path.string() + ": cannot write: " + ec.message());
            detail::forget_temporary(p.temporary);
            pending_.erase(pending_.begin());
        }
    }

private:
    void discard() noexcept {
        for (const Pending& p : pending_) {
            std::error_code ignored;
            std::filesystem::remove_all(p.temporary, ignored); // a file, or a directory `write` filled
            detail::forget_temporary(p.temporary);
        }
        pending_.clear();
    }

    struct Pending {
        std::filesystem::path path, target, temporary;
    };
    std::vector<Pending> pending_;
};

// One output, alone; `directory` as in OutputFiles::add.
template <class WriteFunction>
void write_atomically(const std::filesystem::path& path, WriteFunction&& write, bool directory = false) {
    OutputFiles output;
    output.add(path, std::forward<WriteFunction>(write), directory);
    output.commit();
}

} // namespace tetiso
