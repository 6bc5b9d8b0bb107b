#include "common/format.h"

#include <cerrno>
#include <charconv>
#include <cctype>
#include <cmath>
#include <cstdlib>

namespace cablecal {

std::string FormatDouble(double value) {
  if (value == 0.0) return "0";  // also folds -0 so that outputs do not depend on its sign
  char buffer[64];
  const auto result = std::to_chars(buffer, buffer + sizeof(buffer), value);
  return std::string(buffer, result.ptr);
}

bool ParseFiniteDouble(const std::string& text, double* value) {
  // strtod would skip leading blanks; a cell or scalar with them is not a plain number.
  if (text.empty() || std::isspace(static_cast<unsigned char>(text[0]))) return false;
  errno = 0;
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  if (end != text.c_str() + text.size()) return false;
  if (errno == ERANGE && std::fabs(v) > 1.0) return false;  // overflow; underflow to 0 is fine
  if (!std::isfinite(v)) return false;
  *value = v;
  return true;
}

}  // namespace cablecal
