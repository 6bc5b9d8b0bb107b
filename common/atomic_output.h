// Outputs are never half-written: every file of a command is first written under a
// temporary name beside its final path, and all are renamed into place only after the
// whole command succeeded. If the command fails (or this object is destroyed without
// Commit), the temporaries are removed and no final path is touched.
#pragma once

#include <string>
#include <vector>

namespace cablecal {

// A command's file argument: the flag that named it and the path given.
struct PathArgument {
  std::string flag;
  std::string path;  // empty: not given
};

// Checks a command's files before any work is done: every output's folder exists; no output
// is an existing folder or a non-regular file (a device such as /dev/null or /dev/stdout, a
// pipe: cablecal writes regular files only, by renaming a finished temporary into place); no
// two outputs share a path and no output is one of the inputs (paths compared after resolving
// the folders and symbolic links). Throws InputError naming the flags otherwise.
void CheckCommandPaths(const std::vector<PathArgument>& inputs, const std::vector<PathArgument>& outputs);

class AtomicOutput {
 public:
  AtomicOutput() = default;
  AtomicOutput(const AtomicOutput&) = delete;
  AtomicOutput& operator=(const AtomicOutput&) = delete;
  ~AtomicOutput();

  // Registers `final_path` and returns the temporary path to write instead. Throws
  // InputError if the folder of `final_path` does not exist, if it is a folder or another
  // non-regular file, or if it was registered already.
  std::string Add(const std::string& final_path);

  // Writes `content` to the temporary path of `final_path` (registering it); returns that path.
  std::string WriteText(const std::string& final_path, const std::string& content);

  // Renames every temporary to its final path. Throws InputError naming the file on failure.
  void Commit();

 private:
  struct Entry {
    std::string final_path, temp_path;
  };
  std::vector<Entry> entries_;
  bool committed_ = false;
};

}  // namespace cablecal
