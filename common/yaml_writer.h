// Every YAML output file is written with yaml-cpp's emitter (structure, quoting, escaping).
// Two scalar wrappers settle what the emitter leaves to its caller:
//   YamlNumber  the shortest decimal that reads back to the same double, with a '.' before
//               any exponent ("1.0e-05") and .inf / .nan spelled the YAML way, so that YAML
//               1.1 readers (PyYAML) read a float, never a string;
//   YamlString  always double-quoted, so that any robot name, path or message (": ", "#",
//               newlines, or a name such as "true" or "1.5") reads back as the same string.
#pragma once

#include <yaml-cpp/yaml.h>

#include <string>

namespace cablecal {

struct YamlNumber {
  double value;
};
struct YamlString {
  const std::string& value;
};

YAML::Emitter& operator<<(YAML::Emitter& out, YamlNumber number);
YAML::Emitter& operator<<(YAML::Emitter& out, YamlString text);

// The finished document, ending in a newline. A malformed emitter sequence is a bug (checked).
std::string YamlText(const YAML::Emitter& out);

}  // namespace cablecal
