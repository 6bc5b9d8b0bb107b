// Internal to model/: what the robot-file loaders (robot_yaml.cc, planar; spatial_robot_yaml.cc,
// spatial) share, so that both read files, refuse them and word their messages the same way:
// the file's text (size and type checks), its one YAML document, and a Reader that walks the
// tree and turns every problem into one InputError "file:line: key: problem". Includes
// yaml-cpp, which cablecal_model links privately: for the loaders' .cc files only, never for
// a public header.
#pragma once

#include <yaml-cpp/yaml.h>

#include <Eigen/Core>
#include <optional>
#include <set>
#include <string>

#include "common/error.h"

namespace cablecal::internal {

// Walks the YAML tree and turns every problem into one InputError "file:line: key: problem".
class Reader {
 public:
  // `root`: the document, to name an empty value's key line (Fail).
  Reader(std::string source, YAML::Node root) : source_(std::move(source)), root_(std::move(root)) {}

  [[noreturn]] void Fail(const YAML::Node& node, const std::string& key, const std::string& problem) const;

  // A mapping with exactly the allowed keys (those in `required` must be present).
  void ExpectMap(const YAML::Node& node, const std::string& key, const std::set<std::string>& required,
                 const std::set<std::string>& optional) const;

  double Number(const YAML::Node& parent, const std::string& parent_key, const std::string& name) const;
  double NumberNode(const YAML::Node& node, const std::string& key) const;

  // [x, z]: a planar point.
  Eigen::Vector2d Vector2(const YAML::Node& node, const std::string& key) const;
  // [x, y, z]: a spatial point or direction.
  Eigen::Vector3d Vector3(const YAML::Node& node, const std::string& key) const;

  std::string String(const YAML::Node& node, const std::string& key) const;

  void Positive(const YAML::Node& node, const std::string& key, double v) const;
  // A bound far beyond any robot this tool is for: a value past it is a typo or a unit slip
  // (981 for 9.81, a frame in mm), and would overflow the statics silently.
  void AtMost(const YAML::Node& node, const std::string& key, double v, double most, const std::string& unit) const;
  void AtLeast(const YAML::Node& node, const std::string& key, double v, double least, const std::string& unit) const;
  void NonNegative(const YAML::Node& node, const std::string& key, double v) const;

  static std::string Join(const std::string& a, const std::string& b) { return a.empty() ? b : a + "." + b; }

  const std::string& source() const { return source_; }

 private:
  // The line (1-based) of the key that `key_path` ("platform.com", "cables[2].exit") names in
  // the document, or -1.
  int KeyLine(const std::string& key_path) const;
  std::string source_;
  YAML::Node root_;
};

// The text of a robot file. Refuses what is not a regular file (/dev/zero would be read
// forever) and anything over kMaxRobotFileBytes, before reading it.
std::string ReadRobotFileText(const std::string& path);

// The one YAML document of a robot file's text: refuses a second document (YAML::Load would
// silently ignore it), text that is not YAML and an empty file, each as an InputError naming
// `source` and the line.
YAML::Node LoadRobotDocument(const std::string& yaml_text, const std::string& source);

// `parse(root, reader)` on the robot file's document (LoadRobotDocument), with what yaml-cpp
// itself rejects while it reads (e.g. a key that is not a scalar) as an InputError at its line:
// every loader's one entry (the planar and spatial robots, the kind alone).
template <typename Parse>
auto ParseRobotText(const std::string& yaml_text, const std::string& source, Parse&& parse) {
  const YAML::Node root = LoadRobotDocument(yaml_text, source);
  const Reader rd(source, root);
  try {
    return parse(root, rd);
  } catch (const YAML::Exception& e) {
    throw InputError(source + ":" + std::to_string(e.mark.line + 1), "", e.msg);
  }
}

// Degrees for a file's *_deg key: the radians divided back, rounded to 12 significant digits
// so that a value typed as 60 is written as 60 and not 59.99999999999999.
double DegreesForFile(double rad);

// The file's `kind` as typed ("" when absent), refusing a non-scalar with file, line and key.
std::string KindOf(const YAML::Node& root, const Reader& rd);

// Reads a spatial robot's document, throwing what its loader would (model/spatial_robot_yaml.cc):
// the planar loader checks a spatial file this way before refusing it, so that a command that
// serves planar robots only still tells a user what is wrong in their spatial file.
void CheckSpatialRobotDocument(const YAML::Node& root, const Reader& rd);

// Whether a file without `kind` has keys only a spatial robot's file has (frame min/max,
// home_rpy_deg, a cable's swivel_axis): the planar loader then says to add `kind: spatial`
// rather than call the first such key unknown.
bool LooksSpatial(const YAML::Node& root);

// Both robot files' bound on a cable's optional `stiffness` (E*A, N): at least
// kMinStiffnessOverMaxTension x tension.max (model/robot.h); `cables` is the file's cable list.
void CheckCableStiffness(const Reader& rd, const YAML::Node& cables, std::size_t index,
                         const std::optional<double>& stiffness_N, double tension_max_N);

}  // namespace cablecal::internal
