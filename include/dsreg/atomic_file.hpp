// dsreg — write a file atomically: a temporary sibling file is written, then renamed over the
// destination, so a failure never leaves a partial file and never truncates an existing one.
#pragma once

#include <functional>
#include <ostream>
#include <string>

namespace dsreg {

/// Calls `write(stream)` on a binary stream opened on a temporary file next to `path`, flushes
/// it, and renames it to `path`. If `write` throws or any I/O fails, the temporary file is
/// removed, `path` is left untouched, and dsreg::Error (naming `path`) is thrown.
void write_file_atomically(const std::string& path, const std::function<void(std::ostream&)>& write);

/// Lower-case extension of `path` without the dot ("obj" for "a/b.OBJ"); empty if none.
std::string file_extension(const std::string& path);

}  // namespace dsreg
