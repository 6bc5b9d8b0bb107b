#include "common/yaml_writer.h"

#include <cctype>
#include <cmath>

#include "common/error.h"
#include "common/format.h"

namespace cablecal {

YAML::Emitter& operator<<(YAML::Emitter& out, YamlNumber number) {
  const double v = number.value;
  if (std::isnan(v)) return out << ".nan";
  if (std::isinf(v)) return out << (v > 0 ? ".inf" : "-.inf");
  return out << FormatDouble(v);  // a plain scalar: the emitter does not quote it
}

YAML::Emitter& operator<<(YAML::Emitter& out, YamlString text) { return out << YAML::DoubleQuoted << text.value; }

void EmitNumberMap(YAML::Emitter& out, const char* key,
                   std::initializer_list<std::pair<const char*, double>> entries) {
  out << YAML::Key << key << YAML::Value << YAML::Flow << YAML::BeginMap;
  for (const auto& [name, value] : entries) out << YAML::Key << name << YAML::Value << YamlNumber{value};
  out << YAML::EndMap;
}

std::string YamlText(const YAML::Emitter& out) {
  CABLECAL_CHECK(out.good(), "the YAML emitter was given a malformed sequence: " + out.GetLastError());
  return std::string(out.c_str()) + "\n";
}

void FlowRows::Separate() {
  if (pending_value_) {  // the value of the key just written
    pending_value_ = false;
    return;
  }
  bool& first = in_list_ ? first_in_list_ : first_;
  if (!first) text_ += ", ";
  first = false;
}

void FlowRows::BeginRow() {
  text_ += json_ ? (rows_ ? ", {" : "{") : "  - {";
  first_ = true;
  pending_value_ = false;
}

void FlowRows::Key(const char* key) {
  CABLECAL_CHECK(!in_list_ && !pending_value_ && *key, "a table's key outside a row's entry");
  for (const char* c = key; *c; ++c) {
    CABLECAL_CHECK(std::isalnum(static_cast<unsigned char>(*c)) || *c == '_', "a table's keys are plain identifiers");
  }
  Separate();
  if (json_) {
    text_ += '"';
    text_ += key;
    text_ += "\": ";
  } else {
    text_ += key;
    text_ += ": ";
  }
  pending_value_ = true;
}

void FlowRows::Int(long long value) {
  Separate();
  text_ += std::to_string(value);
}

void FlowRows::Number(double value) {
  Separate();
  if (std::isnan(value)) {
    text_ += json_ ? "\"nan\"" : ".nan";
  } else if (std::isinf(value)) {
    text_ += json_ ? (value > 0 ? "\"inf\"" : "\"-inf\"") : (value > 0 ? ".inf" : "-.inf");
  } else {
    text_ += FormatDouble(value);
  }
}

void FlowRows::BeginList() {
  Separate();
  text_ += '[';
  in_list_ = true;
  first_in_list_ = true;
}

void FlowRows::EndList() {
  CABLECAL_CHECK(in_list_, "a table's list ended twice");
  text_ += ']';
  in_list_ = false;
}

void FlowRows::EndRow() {
  CABLECAL_CHECK(!in_list_ && !pending_value_, "a table's row ended inside an entry");
  text_ += json_ ? "}" : "}\n";
  ++rows_;
}

std::string FlowRows::Finish(const std::string& key, const std::string& comment) const {
  if (json_) return "\"" + key + "\": [" + text_ + "]";
  const std::string head = key + ":" + (comment.empty() ? "" : "  # " + comment) + "\n";
  return head + (rows_ ? text_ : "  []\n");
}

}  // namespace cablecal
