// JSON for scripts (`--json` on identify and design): a YAML document cablecal wrote, as
// JSON with the same content. Quoted YAML scalars become strings; plain ones become numbers
// (the same shortest decimal), true/false, null, or strings. JSON has no infinity or NaN:
// those become the strings "inf", "-inf" and "nan".
#pragma once

#include <yaml-cpp/yaml.h>

#include <string>

namespace cablecal {

std::string ToJson(const YAML::Node& node);  // one line, ends without a newline

}  // namespace cablecal
