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

namespace {

namespace fs = std::filesystem;

// The same file whatever spelling: folders and links resolved, a missing file kept as named.
fs::path Resolved(const std::string& path) {
  std::error_code ec;
  const fs::path p = fs::weakly_canonical(fs::absolute(path), ec);
  return ec ? fs::absolute(path).lexically_normal() : p;
}

void CheckWritable(const std::string& final_path) {
  if (final_path.empty()) throw InputError("", "output path", "is empty");
  const fs::path parent = fs::path(final_path).parent_path();
  if (!parent.empty() && !fs::is_directory(parent)) {
    throw InputError(final_path, "", "cannot write: folder '" + parent.string() + "' does not exist");
  }
  std::error_code ec;
  const fs::file_status st = fs::status(final_path, ec);
  if (fs::is_directory(st)) throw InputError(final_path, "", "cannot write: it is a folder");
  if (fs::exists(st) && !fs::is_regular_file(st)) {
    throw InputError(final_path, "", "cannot write: not a regular file (a device or a pipe); cablecal writes "
                                     "regular files only, renamed into place when complete");
  }
}

}  // namespace

void CheckCommandPaths(const std::vector<PathArgument>& inputs, const std::vector<PathArgument>& outputs) {
  std::vector<std::pair<fs::path, std::string>> seen;  // resolved output path, its flag
  for (const PathArgument& out : outputs) {
    if (out.path.empty()) continue;
    CheckWritable(out.path);
    const fs::path p = Resolved(out.path);
    for (const auto& [other, flag] : seen) {
      if (other == p) throw InputError(out.flag, "", "writes the same file as " + flag + " ('" + out.path + "')");
    }
    for (const PathArgument& in : inputs) {
      if (!in.path.empty() && Resolved(in.path) == p) {
        throw InputError(out.flag, "", "would overwrite the input " + in.flag + " ('" + out.path + "')");
      }
    }
    seen.emplace_back(p, out.flag);
  }
}

std::string AtomicOutput::Add(const std::string& final_path) {
  CheckWritable(final_path);
  for (const Entry& e : entries_) {
    if (Resolved(e.final_path) == Resolved(final_path)) {
      throw InputError(final_path, "", "cannot write: the same command already writes this file");
    }
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
