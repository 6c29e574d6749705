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

} // namespace tetiso
