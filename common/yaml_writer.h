// Every YAML output file is written with yaml-cpp's emitter (structure, quoting, escaping).
// Two scalar wrappers settle what the emitter leaves to its caller:
//   YamlNumber  the shortest decimal that reads back to the same double, with a '.' before
//               any exponent ("1.0e-05") and .inf / .nan spelled the YAML way, so that YAML
//               1.1 readers (PyYAML) read a float, never a string;
//   YamlString  always double-quoted, so that any robot name, path or message (": ", "#",
//               newlines, or a name such as "true" or "1.5") reads back as the same string.
#pragma once

#include <yaml-cpp/yaml.h>

#include <initializer_list>
#include <string>
#include <utility>
#include <vector>

#include "common/format.h"

namespace cablecal {

struct YamlNumber {
  double value;
};
struct YamlString {
  const std::string& value;
};

YAML::Emitter& operator<<(YAML::Emitter& out, YamlNumber number);
YAML::Emitter& operator<<(YAML::Emitter& out, YamlString text);

// `key: {a: 1.0, b: 2.0}`: a key whose value is a one-line map of numbers (YamlNumber), the
// robot files' `tension`, `encoder`, `tracker`.
void EmitNumberMap(YAML::Emitter& out, const char* key,
                   std::initializer_list<std::pair<const char*, double>> entries);

// The finished document, ending in a newline. A malformed emitter sequence is a bug (checked).
std::string YamlText(const YAML::Emitter& out);

// A long table (identify's per-pose and per-reading sections, validate's rows, a truth file's
// true poses: up to 100,000 rows) written without yaml-cpp's emitter, whose per-node cost made
// result.yaml of 100,000 poses take 8 s (issue 24). The text is byte for byte what the emitter
// writes for a block sequence of flow maps under a top-level key
//     key:  # comment
//       - {pose: 1, x: 2.6045, encoder_sigmas: [0.1, -0.2]}
// (keys plain, numbers as YamlNumber, integers in decimal, lists as flow sequences), or the
// same content as JSON (`"key": [{"pose": 1, ...}, ...]`, numbers as ToJson writes them:
// inf and nan as the strings "inf", "-inf", "nan"). Keys must be plain identifiers (checked).
// Use: BeginRow(), then Key() and a value (Int, Number, or BeginList, Number..., EndList) per
// entry, EndRow(); Finish() returns the section, ending in a newline for YAML.
class FlowRows {
 public:
  enum class Syntax { kYaml, kJson };
  explicit FlowRows(Syntax syntax) : json_(syntax == Syntax::kJson) {}
  void BeginRow();
  void Key(const char* key);
  void Int(long long value);
  void Number(double value);
  void BeginList();
  void EndList();
  void EndRow();
  // YAML: "key:[  # comment]\n" and the rows (an empty table: the emitter's "  []");
  // JSON: "\"key\": [rows]", a member for a JSON object (MergeJsonObjects, common/json.h).
  std::string Finish(const std::string& key, const std::string& comment = "") const;

 private:
  void Separate();  // ", " before every entry and list element but the first
  bool json_;
  bool first_ = true, pending_value_ = false, in_list_ = false, first_in_list_ = true;
  long long rows_ = 0;
  std::string text_;
};

// An n x n matrix as a block sequence of flow rows ([a, b, ...] per row), entry(a, b) each:
// the correlation and covariance matrices of the results.
template <typename EntryOf>
void EmitMatrixRows(YAML::Emitter& o, int n, const EntryOf& entry) {
  o << YAML::BeginSeq;
  for (int a = 0; a < n; ++a) {
    o << YAML::Flow << YAML::BeginSeq;
    for (int b = 0; b < n; ++b) o << YamlNumber{entry(a, b)};
    o << YAML::EndSeq;
  }
  o << YAML::EndSeq;
}

// A table of numbers with one row per pose, its first column the pose id (columns[0]) and the
// rest row(j)'s values: as CSV (after `provenance`, the '#' lines) or as the JSON member
// "rows" (FlowRows). The validation tables of both kinds of robot are written so.
template <typename RowOf>
std::string PoseTableCsv(const std::vector<std::string>& columns, const std::vector<int>& pose_ids, const RowOf& row,
                         const std::string& provenance) {
  std::string out = provenance;
  for (std::size_t k = 0; k < columns.size(); ++k) out += (k ? "," : "") + columns[k];
  out += "\n";
  for (std::size_t j = 0; j < pose_ids.size(); ++j) {
    out += std::to_string(pose_ids[j]);
    for (const double v : row(j)) out += "," + FormatDouble(v);
    out += "\n";
  }
  return out;
}
template <typename RowOf>
std::string PoseTableRowsJson(const std::vector<std::string>& columns, const std::vector<int>& pose_ids,
                              const RowOf& row) {
  FlowRows rows(FlowRows::Syntax::kJson);
  for (std::size_t j = 0; j < pose_ids.size(); ++j) {
    rows.BeginRow();
    rows.Key(columns[0].c_str());
    rows.Int(pose_ids[j]);
    const std::vector<double> values = row(j);
    for (std::size_t k = 0; k < values.size(); ++k) {
      rows.Key(columns[k + 1].c_str());
      rows.Number(values[k]);
    }
    rows.EndRow();
  }
  return rows.Finish("rows");
}

}  // namespace cablecal
