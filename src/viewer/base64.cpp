#include "base64.hpp"

namespace dsreg {

std::string base64_encode(const unsigned char* data, std::size_t size) {
    static const char alphabet[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    std::string text;
    text.reserve((size + 2) / 3 * 4);
    std::size_t i = 0;
    for (; i + 3 <= size; i += 3) {  // 3 bytes = 24 bits = four 6-bit digits
        const unsigned group = unsigned(data[i]) << 16 | unsigned(data[i + 1]) << 8 | unsigned(data[i + 2]);
        text += alphabet[group >> 18];
        text += alphabet[(group >> 12) & 63];
        text += alphabet[(group >> 6) & 63];
        text += alphabet[group & 63];
    }
    if (i < size) {  // 1 or 2 bytes left: 2 or 3 digits, then '=' padding
        const bool two = i + 1 < size;
        const unsigned group = unsigned(data[i]) << 16 | (two ? unsigned(data[i + 1]) << 8 : 0u);
        text += alphabet[group >> 18];
        text += alphabet[(group >> 12) & 63];
        text += two ? alphabet[(group >> 6) & 63] : '=';
        text += '=';
    }
    return text;
}

}  // namespace dsreg
