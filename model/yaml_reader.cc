// The robot-file loaders' shared reading (model/yaml_reader.h). Moved here from
// robot_yaml.cc unchanged, so that the planar loader's messages stay as they were.
#include "model/yaml_reader.h"

#include <cctype>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <vector>
#include <sstream>

#include "common/format.h"
#include "model/robot.h"

namespace cablecal::internal {

void Reader::Fail(const YAML::Node& node, const std::string& key, const std::string& problem) const {
  std::string where = source_;
  // A key with nothing after it (`com:` alone): yaml-cpp marks the empty value at the next
  // token, a line or more below, so the key's own line is named.
  const int key_line = node && node.IsNull() ? KeyLine(key) : -1;
  if (key_line > 0) {
    where += ":" + std::to_string(key_line);
  } else if (node && node.Mark().line >= 0) {
    where += ":" + std::to_string(node.Mark().line + 1);
  }
  throw InputError(where, key, problem);
}

int Reader::KeyLine(const std::string& key_path) const {
  YAML::Node at = root_;
  int line = -1;
  std::size_t begin = 0;
  while (begin <= key_path.size() && at) {
    const std::size_t dot = key_path.find('.', begin);
    std::string part = key_path.substr(begin, dot == std::string::npos ? std::string::npos : dot - begin);
    begin = dot == std::string::npos ? key_path.size() + 1 : dot + 1;
    std::vector<std::size_t> indices;
    for (std::size_t open = part.find('['); open != std::string::npos; open = part.find('[')) {
      const std::size_t close = part.find(']', open);
      if (close == std::string::npos) return -1;
      try {
        indices.push_back(std::stoul(part.substr(open + 1, close - open - 1)));
      } catch (const std::exception&) {
        return -1;
      }
      part.erase(open, close - open + 1);
    }
    if (!part.empty()) {
      if (!at.IsMap()) return -1;
      bool found = false;
      YAML::Node value;
      for (const auto& kv : at) {
        if (kv.first.IsScalar() && kv.first.Scalar() == part) {
          found = true;
          line = kv.first.Mark().line + 1;
          value.reset(kv.second);
        }
      }
      if (!found) return -1;
      at.reset(value);
    }
    for (const std::size_t i : indices) {
      if (!at.IsSequence() || i >= at.size()) return -1;
      at.reset(at[i]);
      if (!at.IsNull()) line = at.Mark().line + 1;
    }
  }
  return line;
}

void Reader::ExpectMap(const YAML::Node& node, const std::string& key, const std::set<std::string>& required,
                       const std::set<std::string>& optional) const {
  if (!node.IsMap()) Fail(node, key, "must be a mapping");
  std::map<std::string, int> seen_line;  // a repeated key would silently lose one value
  for (const auto& kv : node) {
    const std::string name = kv.first.as<std::string>();
    const auto [it, fresh] = seen_line.emplace(name, kv.first.Mark().line + 1);
    if (!fresh) Fail(kv.first, Join(key, name), "given twice (first at line " + std::to_string(it->second) + ")");
    if (!required.count(name) && !optional.count(name)) {
      // Quoted at most 40 characters long: a file that is not a robot file at all (a
      // password file given by mistake) is not echoed into the message.
      const std::string shown = name.size() > 40 ? name.substr(0, 40) + "..." : name;
      Fail(kv.first, Join(key, shown), "unknown key (misspelt?)");
    }
  }
  for (const std::string& name : required) {
    if (!node[name]) Fail(node, Join(key, name), "missing");
  }
}

double Reader::Number(const YAML::Node& parent, const std::string& parent_key, const std::string& name) const {
  return NumberNode(parent[name], Join(parent_key, name));
}

double Reader::NumberNode(const YAML::Node& node, const std::string& key) const {
  if (!node.IsScalar()) {
    Fail(node, key, std::string("must be a number (got ") +
                        (node.IsSequence() ? "a list" : node.IsMap() ? "a mapping" : "nothing") + ")");
  }
  double value = 0.0;
  const std::string text = node.Scalar();
  // A quoted scalar is YAML's string (its tag "!"): "0.12" would be a number to us and text to
  // every other YAML reader of the file, so it is refused rather than read.
  if (node.Tag() == "!") Fail(node, key, "must be a number, not a quoted string (got \"" + text + "\")");
  if (!ParseFiniteDouble(text, &value)) {
    Fail(node, key, "must be a finite number (got '" + text + "')");
  }
  return value;
}

Eigen::Vector2d Reader::Vector2(const YAML::Node& node, const std::string& key) const {
  if (!node.IsSequence() || node.size() != 2) Fail(node, key, "must be a list of two numbers [x, z]");
  return Eigen::Vector2d(NumberNode(node[0], key + "[0]"), NumberNode(node[1], key + "[1]"));
}

Eigen::Vector3d Reader::Vector3(const YAML::Node& node, const std::string& key) const {
  if (!node.IsSequence() || node.size() != 3) Fail(node, key, "must be a list of three numbers [x, y, z]");
  return Eigen::Vector3d(NumberNode(node[0], key + "[0]"), NumberNode(node[1], key + "[1]"),
                         NumberNode(node[2], key + "[2]"));
}

std::string Reader::String(const YAML::Node& node, const std::string& key) const {
  if (!node.IsScalar()) Fail(node, key, "must be a string");
  return node.Scalar();
}

void Reader::Positive(const YAML::Node& node, const std::string& key, double v) const {
  if (!(v > 0.0)) Fail(node, key, "must be > 0 (got " + FormatDouble(v) + ")");
}

void Reader::AtMost(const YAML::Node& node, const std::string& key, double v, double most,
                    const std::string& unit) const {
  if (!(v <= most)) {
    Fail(node, key, "must be at most " + FormatDouble(most) + " " + unit + " (got " + FormatDouble(v) + "): units?");
  }
}

void Reader::AtLeast(const YAML::Node& node, const std::string& key, double v, double least,
                     const std::string& unit) const {
  if (!(v >= least)) Fail(node, key, "must be at least " + FormatDouble(least) + " " + unit + " (got " + FormatDouble(v) + ")");
}

void Reader::NonNegative(const YAML::Node& node, const std::string& key, double v) const {
  if (!(v >= 0.0)) Fail(node, key, "must be >= 0 (got " + FormatDouble(v) + ")");
}

std::string ReadRobotFileText(const std::string& path) {
  std::error_code ec;
  const std::filesystem::file_status st = std::filesystem::status(path, ec);
  if (std::filesystem::exists(st) && !std::filesystem::is_regular_file(st)) {
    throw InputError(path, "", "is not a regular file (a folder, a device or a pipe)");
  }
  if (std::filesystem::exists(st) && std::filesystem::file_size(path, ec) > kMaxRobotFileBytes) {
    throw InputError(path, "", "is larger than " + std::to_string(kMaxRobotFileBytes / 1024) +
                                   " KiB: not a robot file");
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, "", "cannot open the robot file");
  std::stringstream buffer;
  buffer << in.rdbuf();
  if (in.bad()) throw InputError(path, "", "cannot read the robot file");
  return buffer.str();
}

YAML::Node LoadRobotDocument(const std::string& yaml_text, const std::string& source) {
  // A second document would be silently ignored by YAML::Load. Found from the text: a line
  // starting with a document marker ("---" or "...") after content. (yaml-cpp 0.7's LoadAll
  // loops forever on some malformed inputs, which the fuzzer found.)
  {
    std::istringstream lines(yaml_text);
    std::string line;
    bool content = false;
    for (int number = 1; std::getline(lines, line); ++number) {
      const bool marker = (line.rfind("---", 0) == 0 || line.rfind("...", 0) == 0) &&
                          (line.size() == 3 || std::isspace(static_cast<unsigned char>(line[3])));
      if (marker && content) {
        throw InputError(source + ":" + std::to_string(number), "",
                         "a second YAML document ('" + line.substr(0, 3) + "'): a robot file holds one robot");
      }
      const std::size_t first = line.find_first_not_of(" \t\r");
      if (!marker && first != std::string::npos && line[first] != '#') content = true;
    }
  }
  YAML::Node root;
  try {
    root = YAML::Load(yaml_text);
  } catch (const YAML::ParserException& e) {
    throw InputError(source + ":" + std::to_string(e.mark.line + 1), "", "not valid YAML: " + e.msg);
  }
  if (!root || root.IsNull()) throw InputError(source, "", "the robot file is empty");
  return root;
}

double DegreesForFile(double rad) {
  char buffer[32];
  std::snprintf(buffer, sizeof(buffer), "%.12g", rad / kDegToRad);
  double degrees = 0.0;
  CABLECAL_CHECK(ParseFiniteDouble(buffer, &degrees), "a finite angle formats and parses back");
  return degrees;
}

std::string KindOf(const YAML::Node& root, const Reader& rd) {
  if (!root.IsMap() || !root["kind"]) return "";
  return rd.String(root["kind"], "kind");
}

void CheckCableStiffness(const Reader& rd, const YAML::Node& cables, std::size_t index,
                         const std::optional<double>& stiffness_N, double tension_max_N) {
  if (!stiffness_N || *stiffness_N >= kMinStiffnessOverMaxTension * tension_max_N) return;
  const std::string key = "cables[" + std::to_string(index) + "].stiffness";
  rd.Fail(cables[index]["stiffness"], key,
          FormatDouble(*stiffness_N) + " N (E*A) would stretch the cable by more than " +
              FormatDouble(100.0 / kMinStiffnessOverMaxTension) + " % at tension.max: units? (E*A is in N)");
}

}  // namespace cablecal::internal
