// The one exception type of tetiso. Every failure a user can cause (bad
// arguments, unreadable or malformed files, impossible parameters) is reported
// through it, with a message that names the file, element or option at fault.
// The command-line front end prints the message on one line and exits with 2.
#pragma once

#include <stdexcept>
#include <string>

namespace tetiso {

class Error : public std::runtime_error {
public:
    explicit Error(const std::string& message) : std::runtime_error(message) {}
};

// A broken invariant of tetiso itself, never the input's fault (a bug to
// report): not a tetiso::Error, so that callers who handle bad input do not
// take it for one. The command-line front end prints it as an internal error
// and exits with 3.
class InternalError : public std::logic_error {
public:
    explicit InternalError(const std::string& message) : std::logic_error(message) {}
};

} // namespace tetiso
