// Text formatting of numbers for every output file: the shortest decimal that reads
// back to the same double (std::to_chars), so files are exact and byte-reproducible.
#pragma once

#include <string>
#include <vector>

namespace cablecal {

// With a '.' before any exponent ("1.0e-05"), so that YAML 1.1 readers see a float.
std::string FormatDouble(double value);

// printf's "%.<digits>g": the rounding a reader compares in a message, a console line or a
// report, for numbers whose size varies (sigmas, singular values, ratios).
std::string Rounded(double value, int digits = 3);

// `text` with control characters escaped (\n, \r, \t, \xNN), for a terminal or a one-line
// heading: a file's bytes quoted in a message must not clear the screen or break a line.
std::string PrintableText(const std::string& text);

// "'a', 'b', 'c'": names for a message, each quoted and made printable (PrintableText).
std::string QuotedList(const std::vector<std::string>& names);

// Parses a whole string as a finite double; returns false on anything else
// (empty, trailing characters, nan, inf, out of range such as 1e400). Independent of the
// process's C locale.
bool ParseFiniteDouble(const std::string& text, double* value);

}  // namespace cablecal
