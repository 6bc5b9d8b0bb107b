// The README's YAML examples, for tests that load them as they are (a README example that no
// longer loads is a defect a user meets first).
#pragma once

#include <fstream>
#include <sstream>
#include <string>

namespace cablecal::testing {

// The first ```yaml block after the text `heading` in README.md; "" if either is missing.
inline std::string ReadmeYamlAfter(const std::string& heading) {
  std::ifstream in(std::string(CABLECAL_SOURCE_DIR) + "/README.md");
  std::stringstream readme;
  readme << in.rdbuf();
  const std::string text = readme.str();
  const std::size_t at = text.find(heading);
  if (at == std::string::npos) return "";
  const std::size_t begin = text.find("```yaml\n", at);
  if (begin == std::string::npos) return "";
  const std::size_t end = text.find("```\n", begin + 8);
  if (end == std::string::npos) return "";
  return text.substr(begin + 8, end - begin - 8);
}

}  // namespace cablecal::testing
