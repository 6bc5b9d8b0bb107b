#include "common/json.h"

#include <cmath>
#include <cstdio>

#include "common/error.h"
#include "common/format.h"

namespace cablecal {
namespace {

std::string Quoted(const std::string& s) {
  std::string out = "\"";
  for (const unsigned char c : s) {
    switch (c) {
      case '"': out += "\\\""; break;
      case '\\': out += "\\\\"; break;
      case '\n': out += "\\n"; break;
      case '\r': out += "\\r"; break;
      case '\t': out += "\\t"; break;
      default:
        if (c < 0x20) {
          char buffer[8];
          std::snprintf(buffer, sizeof buffer, "\\u%04x", c);
          out += buffer;
        } else {
          out += static_cast<char>(c);
        }
    }
  }
  return out + "\"";
}

std::string Scalar(const YAML::Node& node) {
  const std::string& text = node.Scalar();
  if (node.Tag() == "!") return Quoted(text);  // quoted in the YAML: a string whatever it reads like
  if (text == "true" || text == "false") return text;
  if (text == "~" || text == "null") return "null";
  if (text == ".inf" || text == "+.inf") return "\"inf\"";
  if (text == "-.inf") return "\"-inf\"";
  if (text == ".nan") return "\"nan\"";
  // Whole numbers as written (a 64-bit seed does not survive a double).
  const std::size_t digits = text.find_first_not_of("0123456789", text[0] == '-' ? 1 : 0);
  if (digits == std::string::npos && text.size() > (text[0] == '-' ? 1u : 0u) && (text.size() == 1 || text[0] != '0')) {
    return text;
  }
  double value = 0.0;
  if (ParseFiniteDouble(text, &value)) return FormatDouble(value);
  return Quoted(text);
}

void Emit(const YAML::Node& node, std::string* out) {
  switch (node.Type()) {
    case YAML::NodeType::Map: {
      *out += '{';
      bool first = true;
      for (const auto& kv : node) {
        if (!first) *out += ", ";
        first = false;
        *out += Quoted(kv.first.Scalar()) + ": ";
        Emit(kv.second, out);
      }
      *out += '}';
      break;
    }
    case YAML::NodeType::Sequence: {
      *out += '[';
      bool first = true;
      for (const auto& e : node) {
        if (!first) *out += ", ";
        first = false;
        Emit(e, out);
      }
      *out += ']';
      break;
    }
    case YAML::NodeType::Scalar: *out += Scalar(node); break;
    case YAML::NodeType::Null:
    case YAML::NodeType::Undefined: *out += "null"; break;
  }
}

}  // namespace

std::string MergeJsonObjects(const std::vector<std::string>& parts) {
  std::string out = "{";
  for (const std::string& part : parts) {
    CABLECAL_CHECK(!part.empty(), "an empty part of a JSON object");
    const std::string members = part.front() == '{' ? part.substr(1, part.size() - 2) : part;
    if (members.empty()) continue;
    if (out.size() > 1) out += ", ";
    out += members;
  }
  return out + "}";
}

std::string ToJson(const YAML::Node& node) {
  std::string out;
  Emit(node, &out);
  return out;
}

}  // namespace cablecal
