// JSON for scripts (`--json` on identify and design): a YAML document cablecal wrote, as
// JSON with the same content. Quoted YAML scalars become strings; plain ones become numbers
// (the same shortest decimal), true/false, null, or strings. JSON has no infinity or NaN:
// those become the strings "inf", "-inf" and "nan".
#pragma once

#include <yaml-cpp/yaml.h>

#include <string>
#include <vector>

namespace cablecal {

std::string ToJson(const YAML::Node& node);  // one line, ends without a newline

// One JSON object from parts, in order: each part either a whole object ("{...}", as ToJson
// writes a map; its members are taken) or a bare member ("\"key\": value", as FlowRows::Finish
// writes a table). A document with a long table is written this way instead of parsing its
// YAML back (issue 24).
std::string MergeJsonObjects(const std::vector<std::string>& parts);

}  // namespace cablecal
