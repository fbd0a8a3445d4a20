// dsreg — base64 (RFC 4648, with '=' padding), to carry binary buffers inside an HTML page.
#pragma once

#include <cstddef>
#include <string>

namespace dsreg {

/// The base64 text of `size` bytes at `data`: 4 characters per 3 bytes, the last group padded.
std::string base64_encode(const unsigned char* data, std::size_t size);

}  // namespace dsreg
