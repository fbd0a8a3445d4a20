// dsreg — small text helpers: numbers in messages, reports and command lines.
#pragma once

#include <optional>
#include <string>

namespace dsreg {

/// One number formatted with a printf pattern, e.g. format("%.2e", 1.5e-9) == "1.50e-09".
std::string format(const char* pattern, double value);

/// The number the whole of `text` spells (std::stod syntax), or nothing if any character is
/// left over or there is no number at all.
std::optional<double> parse_whole_number(const std::string& text);

}  // namespace dsreg
