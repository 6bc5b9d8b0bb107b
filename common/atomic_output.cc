#include "common/atomic_output.h"

#include <signal.h>
#include <sys/file.h>
#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <thread>

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

// /dev, /proc and /sys hold devices and kernel files, as named or once links are followed
// (/dev/stdout is a link into /proc): never a place for cablecal's regular files.
bool IsSystemPath(const std::string& path) {
  for (const fs::path& p : {fs::absolute(path).lexically_normal(), Resolved(path)}) {
    const std::string s = p.string();
    for (const char* root : {"/dev", "/proc", "/sys"}) {
      const std::size_t n = std::strlen(root);
      if (s.compare(0, n, root) == 0 && (s.size() == n || s[n] == '/')) return true;
    }
  }
  return false;
}

bool IsLinkToNothing(const std::string& path) {
  std::error_code ec;
  return fs::is_symlink(fs::symlink_status(path, ec)) && !fs::exists(path, ec);
}

// Whether `pid_digits` names a process that no longer exists: what a killed run left behind
// (its temporaries, its staging folder) can then be removed.
bool LeftByGoneProcess(const std::string& pid_digits) {
  if (pid_digits.empty() || pid_digits.size() > 9 || pid_digits.find_first_not_of("0123456789") != std::string::npos) {
    return false;
  }
  const long pid = std::atol(pid_digits.c_str());
  return pid > 0 && pid != ::getpid() && ::kill(static_cast<pid_t>(pid), 0) != 0 && errno == ESRCH;
}

// An exclusive lock on a folder (flock), held until the returned descriptor is closed, also
// if the process dies: concurrent runs' commits into the folder take turns.
int LockFolder(const std::string& folder) {
  const int fd = ::open(folder.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0 || ::flock(fd, LOCK_EX) != 0) {
    const int error = errno;
    if (fd >= 0) ::close(fd);
    throw InputError(folder, "", std::string("cannot lock the folder: ") + std::strerror(error));
  }
  return fd;
}

// Closes the descriptors of LockFolder when a commit ends, however it ends.
struct FolderLocks {
  std::vector<int> fds;
  FolderLocks() = default;
  FolderLocks(const FolderLocks&) = delete;
  FolderLocks& operator=(const FolderLocks&) = delete;
  ~FolderLocks() {
    for (int fd : fds) ::close(fd);
  }
};

// Why `folder`, which is not a folder, cannot hold an output: the first of it and its parents
// that exists is a file ("'afile' is a file, not a folder"), or it does not exist.
std::string NoFolder(const fs::path& folder) {
  std::error_code ec;
  for (fs::path p = folder; !p.empty(); p = p.parent_path()) {
    if (fs::exists(p, ec)) {
      if (!fs::is_directory(p, ec)) return "'" + p.string() + "' is a file, not a folder";
      break;
    }
    if (p == p.parent_path()) break;
  }
  return "folder '" + folder.string() + "' does not exist";
}

void CheckWritable(const std::string& final_path) {
  if (final_path.empty()) throw InputError("", "output path", "is empty");
  if (IsSystemPath(final_path)) {
    throw InputError(final_path, "", "cannot write: a device or system path (/dev, /proc, /sys); cablecal writes "
                                     "regular files only, renamed into place when complete");
  }
  const fs::path parent = fs::path(final_path).parent_path();
  if (!parent.empty() && !fs::is_directory(parent)) {
    throw InputError(final_path, "", "cannot write: " + NoFolder(parent));
  }
  // The file is written beside its final path and renamed into place: the folder must take new
  // files. Checked here, before the work, not found when the result is ready.
  const std::string folder = parent.empty() ? "." : parent.string();
  if (::access(folder.c_str(), W_OK | X_OK) != 0) {
    throw InputError(final_path, "", "cannot write: no permission to create files in folder '" + folder + "' (" +
                                         std::strerror(errno) + ")");
  }
  std::error_code ec;
  if (IsLinkToNothing(final_path)) {
    throw InputError(final_path, "", "cannot write: a symbolic link to nothing (give the path it should lead to, or "
                                     "remove the link)");
  }
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
    try {
      CheckWritable(out.path);
    } catch (const InputError& e) {
      throw InputError(out.flag, "", e.what());
    }
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

namespace {

// Temporaries of `final_path` ("<name>.tmp.<pid>", "<name>.<what>.tmp.<pid>") that a killed run
// left: their process no longer exists.
void RemoveStaleTemporaries(const fs::path& final_path) {
  const fs::path folder = final_path.parent_path().empty() ? fs::path(".") : final_path.parent_path();
  const std::string prefix = final_path.filename().string() + ".";
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(folder, ec)) {
    const std::string name = entry.path().filename().string();
    const std::size_t tmp = name.rfind(".tmp.");
    if (name.rfind(prefix, 0) != 0 || tmp == std::string::npos) continue;
    if (LeftByGoneProcess(name.substr(tmp + 5))) {
      std::error_code ignored;
      fs::remove(entry.path(), ignored);
    }
  }
}

}  // namespace

std::string AtomicOutput::Add(const std::string& final_path) {
  CheckWritable(final_path);
  RemoveStaleTemporaries(final_path);
  for (const Entry& e : entries_) {
    if (Resolved(e.final_path) == Resolved(final_path)) {
      throw InputError(final_path, "", "cannot write: the same command already writes this file");
    }
  }
  // A symbolic link is written through: its target is replaced, the link kept.
  std::error_code ec;
  const std::string target = fs::is_symlink(fs::symlink_status(final_path, ec)) ? Resolved(final_path).string()
                                                                                  : final_path;
  // The pid keeps concurrent runs writing the same path from clobbering each other's temporary.
  Entry e{target, target + ".tmp." + std::to_string(::getpid())};
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

void AtomicOutput::Drop(const std::string& final_path) {
  for (auto it = entries_.begin(); it != entries_.end(); ++it) {
    if (Resolved(it->final_path) == Resolved(final_path)) {
      std::remove(it->temp_path.c_str());
      entries_.erase(it);
      return;
    }
  }
}

void AtomicOutput::Commit() {
  // Locks every folder written into, in one order (no deadlock between two runs); released when
  // the descriptors close.
  std::vector<std::string> folders;
  for (const Entry& e : entries_) {
    const std::string parent = Resolved(e.final_path).parent_path().string();
    if (std::find(folders.begin(), folders.end(), parent) == folders.end()) folders.push_back(parent);
  }
  std::sort(folders.begin(), folders.end());
  FolderLocks locks;
  for (const std::string& folder : folders) locks.fds.push_back(LockFolder(folder));
  for (const Entry& e : entries_) {
    if (std::rename(e.temp_path.c_str(), e.final_path.c_str()) != 0) {
      throw InputError(e.final_path, "", std::string("cannot rename into place: ") +
                                             std::strerror(errno));
    }
  }
  committed_ = true;
}

namespace {

constexpr const char* kStagePrefix = ".cablecal-stage.";
constexpr const char* kOldPrefix = ".cablecal-old.";

// After each rename of a commit: CABLECAL_TEST_COMMIT (atomic_output.h), for the tests that
// show a killed or concurrent commit never mixes two runs.
void AfterCommitRename(int renames_done) {
  static const char* hook = std::getenv("CABLECAL_TEST_COMMIT");
  if (!hook) return;
  const std::string h = hook;
  if (h.rfind("delay:", 0) == 0) {
    std::this_thread::sleep_for(std::chrono::milliseconds(std::atoi(h.c_str() + 6)));
  } else if (h.rfind("kill:", 0) == 0 && renames_done >= std::atoi(h.c_str() + 5)) {
    ::kill(::getpid(), SIGKILL);
  }
}

// Staging and aside folders of runs that were killed: their process no longer exists.
void RemoveStaleFolders(const fs::path& dir) {
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(dir, ec)) {
    const std::string name = entry.path().filename().string();
    for (const char* prefix : {kStagePrefix, kOldPrefix}) {
      if (name.rfind(prefix, 0) == 0 && LeftByGoneProcess(name.substr(std::strlen(prefix)))) {
        std::error_code ignored;
        fs::remove_all(entry.path(), ignored);
      }
    }
  }
}

}  // namespace

OutputFolder::OutputFolder(const std::string& flag, const std::string& dir, std::vector<std::string> owned)
    : flag_(flag), dir_(dir), owned_(std::move(owned)) {
  // Checked now, before any work; created only when the first file is written, so a run that
  // fails or is killed before that leaves nothing at all.
  std::error_code ec;
  if (dir_.empty()) throw InputError(flag_, "", "is empty");
  if (IsLinkToNothing(dir_)) {
    throw InputError(flag_, "", "'" + dir_ + "' is a symbolic link to nothing (give the folder it should lead to, or "
                                "remove the link)");
  }
  if (fs::exists(dir_, ec) && !fs::is_directory(dir_, ec)) {
    throw InputError(flag_, "", "'" + dir_ + "' exists and is not a folder");
  }
  if (IsSystemPath(dir_)) {
    throw InputError(flag_, "", "cannot write into '" + dir_ + "': a device or system path (/dev, /proc, /sys)");
  }
  // The folder may be new, its parent must exist (as for every output file): a mistyped path
  // is refused, not created.
  fs::path parent = fs::absolute(dir_).lexically_normal();
  if (parent.filename().empty()) parent = parent.parent_path();  // a trailing separator
  parent = parent.parent_path();
  if (!fs::is_directory(parent, ec)) {
    throw InputError(flag_, "", "cannot write into '" + dir_ + "': " + NoFolder(parent));
  }
  // An owned name that holds something of another kind (a folder where cablecal writes a file)
  // is not a previous run's: it would be deleted at the commit.
  for (std::string& name : owned_) {
    const bool folder = !name.empty() && name.back() == '/';
    if (folder) name.pop_back();
    const fs::path p = fs::path(dir_) / name;
    const fs::file_status st = fs::symlink_status(p, ec);
    if (fs::exists(st) && (folder ? !fs::is_directory(st) : !fs::is_regular_file(st))) {
      throw InputError(flag_, "", "'" + p.string() + "' is not a " + (folder ? "folder" : "file") +
                                      " of an earlier run: cablecal would replace it (move it away first)");
    }
  }
  const fs::path existing = fs::exists(dir_, ec) ? fs::path(dir_) : parent;
  if (::access(existing.c_str(), W_OK | X_OK) != 0) {
    throw InputError(flag_, "", "cannot write into '" + existing.string() + "': " + std::strerror(errno));
  }
}

void OutputFolder::RefuseInputs(const std::vector<PathArgument>& inputs) const {
  for (const PathArgument& in : inputs) {
    if (in.path.empty()) continue;
    const std::string input = Resolved(in.path).string();
    for (const std::string& name : owned_) {
      const std::string owned = Resolved((fs::path(dir_) / name).string()).string();
      if (input == owned || input.rfind(owned + "/", 0) == 0) {
        throw InputError(in.flag, "", "'" + in.path + "' is where " + flag_ + " writes its " + name +
                                          ": it would be overwritten (move it out of '" + dir_ + "')");
      }
    }
  }
}

void OutputFolder::EnsureStaging() const {
  if (!staging_.empty()) return;
  std::error_code ec;
  // The folders this creates are removed again if the run fails (and they are still empty).
  for (fs::path p = fs::absolute(dir_).lexically_normal(); !p.empty() && !fs::exists(p, ec); p = p.parent_path()) {
    if (p.filename().empty()) continue;  // a trailing separator
    created_.push_back(p.string());
  }
  fs::create_directories(dir_, ec);
  if (ec || !fs::is_directory(dir_)) {
    throw InputError(flag_, "", "cannot create the folder '" + dir_ + "': " + ec.message());
  }
  RemoveStaleFolders(dir_);
  const std::string staging = (fs::path(dir_) / (kStagePrefix + std::to_string(::getpid()))).string();
  fs::remove_all(staging, ec);
  if (!fs::create_directory(staging, ec) || ec) {
    throw InputError(flag_, "", "cannot write into the folder '" + dir_ + "': " + ec.message());
  }
  staging_ = staging;
}

OutputFolder::~OutputFolder() {
  if (committed_) return;
  std::error_code ignored;
  if (!staging_.empty()) fs::remove_all(staging_, ignored);
  for (const std::string& p : created_) fs::remove(p, ignored);  // innermost first; only if empty
}

const std::string& OutputFolder::staging() const {
  EnsureStaging();
  return staging_;
}

std::string OutputFolder::Path(const std::string& relative) const {
  EnsureStaging();
  const fs::path p = fs::path(staging_) / relative;
  std::error_code ec;
  fs::create_directories(p.parent_path(), ec);
  if (ec) throw InputError(flag_, "", "cannot create '" + p.parent_path().string() + "': " + ec.message());
  return p.string();
}

void OutputFolder::WriteText(const std::string& relative, const std::string& content) const {
  const std::string path = Path(relative);
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out << content;
  out.close();
  if (!out) throw InputError(flag_, "", "cannot write '" + path + "': " + std::strerror(errno));
}

void OutputFolder::Commit() {
  EnsureStaging();  // a set with no file still replaces the previous one
  FolderLocks lock;
  lock.fds.push_back(LockFolder(dir_));
  const fs::path dir(dir_), aside = dir / (kOldPrefix + std::to_string(::getpid()));
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(staging_)) {
    const std::string name = entry.path().filename().string();
    CABLECAL_CHECK(std::find(owned_.begin(), owned_.end(), name) != owned_.end(),
                   "every file of an output set is one of its owned names: " + name);
  }
  fs::remove_all(aside, ec);
  fs::create_directory(aside, ec);
  if (ec) throw InputError(flag_, "", "cannot write into the folder '" + dir_ + "': " + ec.message());
  int renames = 0;
  const auto move = [&](const fs::path& from, const fs::path& to) {
    if (std::rename(from.c_str(), to.c_str()) != 0) {
      throw InputError(flag_, "", "cannot move '" + from.string() + "' to '" + to.string() + "': " +
                                      std::strerror(errno));
    }
    AfterCommitRename(++renames);
  };
  for (const std::string& name : owned_) {
    if (fs::exists(fs::symlink_status(dir / name))) move(dir / name, aside / name);
  }
  for (const std::string& name : owned_) {
    if (fs::exists(fs::symlink_status(fs::path(staging_) / name))) move(fs::path(staging_) / name, dir / name);
  }
  committed_ = true;
  fs::remove_all(aside, ec);
  fs::remove_all(staging_, ec);
}

}  // namespace cablecal
