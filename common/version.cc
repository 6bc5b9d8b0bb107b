#include "common/version.h"

#include <fstream>

#include "common/version_info.h"  // generated at build time: kVersion, kGitCommit

namespace cablecal {

const char* Version() { return kVersion; }
const char* GitCommit() { return kGitCommit; }

std::string CommandLine(const std::vector<std::string>& argv) {
  std::string line;
  for (const std::string& arg : argv) {
    if (!line.empty()) line += ' ';
    const bool plain = !arg.empty() && arg.find_first_not_of(
        "abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_-+=.,/:@%") ==
        std::string::npos;
    if (plain) {
      line += arg;
    } else {
      line += '\'';
      for (char c : arg) line += (c == '\'') ? std::string("'\\''") : std::string(1, c);
      line += '\'';
    }
  }
  return line;
}

std::string ProvenanceComment(const std::string& command_line) {
  // A newline in an argument (a path) would end the comment and start a data line.
  std::string one_line;
  for (const char c : command_line) one_line += c == '\n' ? "\\n" : c == '\r' ? "\\r" : std::string(1, c);
  return std::string("# cablecal ") + Version() + " (commit " + GitCommit() + ")\n# command: " + one_line + "\n";
}

std::string LoadedLibraryPath(const std::string& name) {
  std::ifstream maps("/proc/self/maps");
  std::string line;
  while (std::getline(maps, line)) {
    const std::size_t slash = line.rfind('/');
    const std::size_t path = line.find('/');
    if (slash == std::string::npos || line.compare(slash + 1, name.size(), name) != 0) continue;
    return line.substr(path);
  }
  return "not loaded";
}

}  // namespace cablecal
