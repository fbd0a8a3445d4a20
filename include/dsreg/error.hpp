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

/// An Error of the file system rather than of the content: a file that cannot be found, opened,
/// read, created, written or renamed. `error_number` is the errno value when known (ENOENT,
/// EACCES, EISDIR, ...), else 0. The command-line tool prints it like any Error; the Python
/// module raises OSError (FileNotFoundError, PermissionError, ...) for it, ValueError for the rest.
class FileError : public Error {
public:
    explicit FileError(const std::string& message, int error_number = 0) : Error(message), error_number_(error_number) {}
    int error_number() const { return error_number_; }

private:
    int error_number_;
};

}  // namespace dsreg
