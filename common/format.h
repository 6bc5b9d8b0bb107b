// Text formatting of numbers for every output file: the shortest decimal that reads
// back to the same double (std::to_chars), so files are exact and byte-reproducible.
#pragma once

#include <string>

namespace cablecal {

// With a '.' before any exponent ("1.0e-05"), so that YAML 1.1 readers see a float.
std::string FormatDouble(double value);

// `text` with control characters escaped (\n, \r, \t, \xNN), for a terminal or a one-line
// heading: a file's bytes quoted in a message must not clear the screen or break a line.
std::string PrintableText(const std::string& text);

// Parses a whole string as a finite double; returns false on anything else
// (empty, trailing characters, nan, inf, out of range such as 1e400). Independent of the
// process's C locale.
bool ParseFiniteDouble(const std::string& text, double* value);

}  // namespace cablecal
