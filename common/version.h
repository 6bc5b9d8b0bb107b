// Version and provenance written into every output: the version, the git commit the
// binary was built from, and the command line that made the output.
#pragma once

#include <string>
#include <vector>

namespace cablecal {

const char* Version();    // e.g. "0.1.0"
const char* GitCommit();  // e.g. "3f2a1c9" or "3f2a1c9-dirty"; "unknown" outside git

// The command line as typed, shell-quoted where needed.
std::string CommandLine(const std::vector<std::string>& argv);

// Lines "# cablecal <version> (commit <c>)" and "# command: <line>" for CSV heads.
std::string ProvenanceComment(const std::string& command_line);

// Where this process loaded a shared library from (its first mapping in /proc/self/maps
// whose file name starts with `name`, e.g. "libblas.so"), or "not loaded". Designs are
// bit-reproducible only with the reference BLAS (CMakeLists.txt); outputs record it.
std::string LoadedLibraryPath(const std::string& name);

}  // namespace cablecal
