// Text formatting of numbers for every output file: the shortest decimal that reads
// back to the same double (std::to_chars), so files are exact and byte-reproducible.
#pragma once

#include <string>

namespace cablecal {

std::string FormatDouble(double value);

// Parses a whole string as a finite double; returns false on anything else
// (empty, trailing characters, nan, inf, out of range such as 1e400).
bool ParseFiniteDouble(const std::string& text, double* value);

}  // namespace cablecal
