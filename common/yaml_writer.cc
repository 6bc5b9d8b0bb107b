#include "common/yaml_writer.h"

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

std::string YamlText(const YAML::Emitter& out) {
  CABLECAL_CHECK(out.good(), "the YAML emitter was given a malformed sequence: " + out.GetLastError());
  return std::string(out.c_str()) + "\n";
}

}  // namespace cablecal
