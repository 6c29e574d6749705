// The temporaries of the outputs under way, created exclusively and removed
// when the process is interrupted (SIGINT, SIGTERM, SIGHUP) before it could
// rename or discard them. A signal handler may call only async-signal-safe
// functions: it cannot walk a std::vector, allocate or take a lock, so the
// temporaries live in a fixed table of C strings, each slot claimed with an
// atomic flag, and the handler removes them with unlink(), unlinkat() and
// rmdir() on raw directory entries (getdents64) alone. SIGKILL cannot be
// caught: remove_stale_temporaries removes what such a process left.
#include <fcntl.h>
#include <signal.h>
#include <sys/stat.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <climits>
#include <cstring>
#include <filesystem>
#include <string>

#include "tetiso/detail/write_atomically.hpp"
#include "tetiso/error.hpp"

namespace tetiso::detail {

namespace {

enum SlotState : int { kFree = 0, kClaimed = 1, kFile = 2, kDirectory = 3 };

struct Slot {
    std::atomic<int> state{kFree};
    char path[PATH_MAX];
};

// More outputs at once than any command writes; a temporary that finds no
// slot is still removed on every other path, and by the next write of its
// output if a signal comes.
constexpr int kSlots = 32;
Slot slots[kSlots];

void remember(const std::filesystem::path& temporary, bool directory) {
    const std::string& text = temporary.native();
    if (text.size() >= PATH_MAX) return;
    for (Slot& slot : slots) {
        int expected = kFree;
        if (!slot.state.compare_exchange_strong(expected, kClaimed)) continue;
        std::memcpy(slot.path, text.c_str(), text.size() + 1);
        slot.state.store(directory ? kDirectory : kFile);
        return;
    }
}

// A split's temporary directory holds files only: empty it, then remove it.
void remove_flat_directory(const char* path) {
    const int fd = ::open(path, O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    if (fd < 0) return;
    alignas(8) char buffer[4096];
    for (;;) {
        const long got = ::syscall(SYS_getdents64, fd, buffer, sizeof buffer);
        if (got <= 0) break;
        for (long at = 0; at < got;) {
            // struct linux_dirent64: ino (8), off (8), reclen (2), type (1), name.
            unsigned short length = 0;
            std::memcpy(&length, buffer + at + 16, sizeof length);
            const char* name = buffer + at + 19;
            if (std::strcmp(name, ".") != 0 && std::strcmp(name, "..") != 0) ::unlinkat(fd, name, 0);
            at += length;
        }
    }
    ::close(fd);
    ::rmdir(path);
}

void remove_and_reraise(int signal) {
    const int saved_errno = errno;
    for (Slot& slot : slots) {
        const int state = slot.state.load();
        if (state == kFile) ::unlink(slot.path);
        if (state == kDirectory) remove_flat_directory(slot.path);
    }
    errno = saved_errno;
    // The default action, so that the parent sees the process end by this
    // signal, as it would have without the handler.
    struct sigaction action {};
    action.sa_handler = SIG_DFL;
    ::sigemptyset(&action.sa_mask);
    ::sigaction(signal, &action, nullptr);
    ::raise(signal);
}

} // namespace

std::filesystem::path create_temporary(const std::filesystem::path& target, bool directory,
                                       const std::filesystem::path& path) {
    // Exclusive: a file or link someone put at the name is never written
    // through, and two writers never share a temporary.
    constexpr int kAttempts = 100;
    for (int attempt = 0; attempt < kAttempts; ++attempt) {
        const std::filesystem::path temporary = temporary_sibling(target);
        // Remembered first: a signal between the creation and the table
        // would leave it behind (unlinking a name not yet made is harmless).
        remember(temporary, directory);
        int made = 0;
        if (directory) {
            made = ::mkdir(temporary.c_str(), 0777);
        } else {
            const int fd = ::open(temporary.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
            made = fd < 0 ? -1 : ::close(fd);
        }
        if (made == 0) return temporary;
        const int error = errno;
        forget_temporary(temporary);
        if (error != EEXIST) throw Error(path.string() + ": cannot write: " + std::strerror(error));
    }
    throw Error(path.string() + ": cannot write: no free temporary name beside it");
}

void forget_temporary(const std::filesystem::path& temporary) {
    for (Slot& slot : slots) {
        const int state = slot.state.load();
        if ((state == kFile || state == kDirectory) && temporary.native() == slot.path) {
            slot.state.store(kFree);
            return;
        }
    }
}

void remove_temporaries_on_signals() {
    struct sigaction action {};
    action.sa_handler = remove_and_reraise;
    ::sigemptyset(&action.sa_mask);
    for (const int signal : {SIGINT, SIGTERM, SIGHUP}) ::sigaddset(&action.sa_mask, signal);
    for (const int signal : {SIGINT, SIGTERM, SIGHUP}) {
        struct sigaction previous {};
        // A signal the caller's parent ignores (nohup's SIGHUP) stays ignored.
        if (::sigaction(signal, nullptr, &previous) == 0 && previous.sa_handler == SIG_IGN) continue;
        ::sigaction(signal, &action, nullptr);
    }
}

} // namespace tetiso::detail
