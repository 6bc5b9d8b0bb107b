#include "common/format.h"

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>

namespace cablecal {

std::string FormatDouble(double value) {
  if (value == 0.0) return "0";  // also folds -0 so that outputs do not depend on its sign
  char buffer[64];
  const auto result = std::to_chars(buffer, buffer + sizeof(buffer), value);
  std::string text(buffer, result.ptr);
  // YAML 1.1 readers (PyYAML) take "1e-05" for a string: a float needs a '.' there. "1.0e-05"
  // is the same double for every reader.
  const std::size_t e = text.find('e');
  if (e != std::string::npos && text.find('.') == std::string::npos) text.insert(e, ".0");
  return text;
}

namespace {

// Length of the well-formed UTF-8 sequence at text[i] (1 to 4), or 0 if it is not one: a
// lead byte with its continuation bytes, no overlong form, no surrogate, at most U+10FFFF.
std::size_t Utf8SequenceAt(const std::string& text, std::size_t i) {
  const auto byte = [&](std::size_t k) { return k < text.size() ? static_cast<unsigned char>(text[k]) : 0u; };
  const unsigned lead = byte(i);
  const std::size_t length = lead >= 0xc2 && lead <= 0xdf ? 2 : lead >= 0xe0 && lead <= 0xef ? 3
                             : lead >= 0xf0 && lead <= 0xf4                                   ? 4
                                                                                              : 0;
  if (length == 0) return 0;
  for (std::size_t k = 1; k < length; ++k) {
    if ((byte(i + k) & 0xc0) != 0x80) return 0;
  }
  const unsigned second = byte(i + 1);
  if ((lead == 0xe0 && second < 0xa0) || (lead == 0xed && second > 0x9f) || (lead == 0xf0 && second < 0x90) ||
      (lead == 0xf4 && second > 0x8f)) {
    return 0;
  }
  return length;
}

}  // namespace

std::string Rounded(double value, int digits) {
  if (std::isinf(value)) return value > 0 ? "inf" : "-inf";  // C leaves "inf" or "infinity" to the library
  char text[64];
  std::snprintf(text, sizeof text, "%.*g", digits, value);
  return text;
}

std::string PrintableText(const std::string& text) {
  std::string out;
  out.reserve(text.size());
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    const unsigned char u = static_cast<unsigned char>(c);
    if (u >= 0x80) {  // a UTF-8 character passes whole; a byte that is not part of one is escaped
      const std::size_t length = Utf8SequenceAt(text, i);
      if (length > 0) {
        out.append(text, i, length);
        i += length - 1;
      } else {
        char buffer[8];
        std::snprintf(buffer, sizeof(buffer), "\\x%02x", u);
        out += buffer;
      }
      continue;
    }
    if (c == '\n') {
      out += "\\n";
    } else if (c == '\r') {
      out += "\\r";
    } else if (c == '\t') {
      out += "\\t";
    } else if (u < 0x20 || u == 0x7f) {
      char buffer[8];
      std::snprintf(buffer, sizeof(buffer), "\\x%02x", u);
      out += buffer;
    } else {
      out += c;
    }
  }
  return out;
}

std::string QuotedList(const std::vector<std::string>& names) {
  std::string list;
  for (const std::string& name : names) list += (list.empty() ? "'" : ", '") + PrintableText(name) + "'";
  return list;
}

bool ParseFiniteDouble(const std::string& text, double* value) {
  // std::from_chars, not strtod: the decimal point must not follow the C locale of the
  // process (a library user's may be "de_DE", where strtod expects a comma).
  const char* first = text.data();
  const char* last = text.data() + text.size();
  if (first != last && *first == '+') ++first;  // from_chars takes no '+'; hand-written files may
  if (first == last || std::isspace(static_cast<unsigned char>(*first)) || *first == '+' ||
      (first != text.data() && *first == '-')) {
    return false;
  }
  double v = 0.0;
  const auto result = std::from_chars(first, last, v);
  if (result.ptr != last) return false;
  if (result.ec == std::errc::result_out_of_range) {
    // Too small underflows to zero, which is fine; too large is refused. Out of range with a
    // negative exponent is taken as too small (a mantissa of hundreds of digits is not data).
    const char* exp = std::find_if(first, last, [](char c) { return c == 'e' || c == 'E'; });
    if (!(exp != last && exp + 1 != last && exp[1] == '-')) return false;
    v = 0.0;
  } else if (result.ec != std::errc()) {
    return false;
  }
  if (!std::isfinite(v)) return false;  // "inf", "nan"
  *value = v;
  return true;
}

}  // namespace cablecal
