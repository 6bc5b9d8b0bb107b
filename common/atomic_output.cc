#include "common/atomic_output.h"

#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "common/error.h"

namespace cablecal {

AtomicOutput::~AtomicOutput() {
  if (committed_) return;
  for (const Entry& e : entries_) std::remove(e.temp_path.c_str());
}

std::string AtomicOutput::Add(const std::string& final_path) {
  if (final_path.empty()) throw InputError("", "output path", "is empty");
  namespace fs = std::filesystem;
  const fs::path parent = fs::path(final_path).parent_path();
  if (!parent.empty() && !fs::is_directory(parent)) {
    throw InputError(final_path, "", "cannot write: folder '" + parent.string() + "' does not exist");
  }
  if (fs::is_directory(final_path)) {
    throw InputError(final_path, "", "cannot write: it is a folder");
  }
  // The pid keeps concurrent runs writing the same path from clobbering each other's temporary.
  Entry e{final_path, final_path + ".tmp." + std::to_string(::getpid())};
  entries_.push_back(e);
  return e.temp_path;
}

std::string AtomicOutput::WriteText(const std::string& final_path, const std::string& content) {
  const std::string temp = Add(final_path);
  std::ofstream out(temp, std::ios::binary | std::ios::trunc);
  out << content;
  out.close();
  if (!out) throw InputError(final_path, "", std::string("cannot write: ") + std::strerror(errno));
  return temp;
}

void AtomicOutput::Commit() {
  for (const Entry& e : entries_) {
    if (std::rename(e.temp_path.c_str(), e.final_path.c_str()) != 0) {
      throw InputError(e.final_path, "", std::string("cannot rename into place: ") +
                                             std::strerror(errno));
    }
  }
  committed_ = true;
}

}  // namespace cablecal
