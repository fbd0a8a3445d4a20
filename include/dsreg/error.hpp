// dsreg — error type shared by every stage.
#pragma once

#include <stdexcept>
#include <string>

namespace dsreg {

/// Thrown for every user-facing failure: unreadable or malformed input, bad parameter values,
/// failed solves. The message is complete and readable on its own (it names the file or the
/// option and the problem), so the command-line tool prints it verbatim.
class Error : public std::runtime_error {
public:
    explicit Error(const std::string& message) : std::runtime_error(message) {}
};

}  // namespace dsreg
