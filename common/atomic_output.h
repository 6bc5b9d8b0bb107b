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
// pipe, anything under /dev, /proc or /sys: cablecal writes regular files only, by renaming a
// finished temporary into place; an output that is a symbolic link to a regular file is
// written through, the link kept); no
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

  // Forgets `final_path` and removes its temporary (a figure whose script failed).
  void Drop(const std::string& final_path);

  // Renames every temporary to its final path, holding a lock on each folder involved so that
  // concurrent runs' commits take turns. Throws InputError naming the file on failure.
  void Commit();

 private:
  struct Entry {
    std::string final_path, temp_path;
  };
  std::vector<Entry> entries_;
  bool committed_ = false;
};

// A command's output folder: a set of files (and subfolders) that belong together, committed
// as one. Everything is written into a staging folder inside `dir` (.cablecal-stage.<pid>);
// Commit, holding an exclusive lock on `dir` (flock), moves the previous run's entries of the
// owned names aside, moves the new ones in, and deletes the old. So:
// - a failed, interrupted or killed run leaves the folder as it was (a killed run leaves its
//   hidden staging folder, removed by the next run into the folder);
// - two runs into one folder never mix: their commits take turns, and the last one's set is
//   the folder's, whole;
// - a run killed inside Commit (between renames that take microseconds) leaves some owned
//   names missing, the previous set's files in .cablecal-old.<pid>, never files of two runs
//   side by side;
// - files in `dir` that the command does not own are left alone.
class OutputFolder {
 public:
  // `owned`: every top-level name the command may write into `dir` (also those it does not
  // write this time, such as figures, so that a previous run's do not stay beside the new
  // set); a trailing '/' marks a folder. An owned name that exists as the other kind (a
  // folder where a file goes) is refused: it is not an earlier run's. Checks that `dir` is a
  // folder, or that its parent is (throws InputError naming `flag` otherwise: a mistyped path
  // is refused, not created); creates `dir` and the staging folder when the first file is
  // written, and removes them if the run ends without a commit.
  OutputFolder(const std::string& flag, const std::string& dir, std::vector<std::string> owned);
  OutputFolder(const OutputFolder&) = delete;
  OutputFolder& operator=(const OutputFolder&) = delete;
  ~OutputFolder();

  // Refuses (InputError naming the input's flag) an input that is one of the owned names in
  // `dir`, or inside an owned subfolder: the commit would replace it.
  void RefuseInputs(const std::vector<PathArgument>& inputs) const;

  // Where to write `relative` (an owned name, or a path under an owned subfolder) before the
  // commit; its parent folders are created.
  std::string Path(const std::string& relative) const;
  // Writes `content` to Path(relative).
  void WriteText(const std::string& relative, const std::string& content) const;
  // The staging folder itself (for a script that writes several files into it).
  const std::string& staging() const;
  void Commit();

 private:
  void EnsureStaging() const;
  std::string flag_, dir_;
  std::vector<std::string> owned_;
  mutable std::string staging_;
  mutable std::vector<std::string> created_;  // folders this run created, innermost first
  bool committed_ = false;
};

// Test aid: CABLECAL_TEST_COMMIT=delay:MS sleeps MS milliseconds after each rename of a
// commit; CABLECAL_TEST_COMMIT=kill:K kills the process (SIGKILL) after K renames.

}  // namespace cablecal
