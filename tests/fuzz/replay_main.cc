// Replays a fuzz target's corpus without libFuzzer: each file named on the command line (a
// folder: each regular file in it, in name order) is given once to LLVMFuzzerTestOneInput.
// The Release suite builds the targets so (GCC has no libFuzzer), which keeps every seed and
// every crash found so far a regression test of each CI run; the exploring fuzzers run with
// `scripts/test.sh --sanitize` (README, "Reliability"). A target reports a bug by aborting
// or by an exception other than cablecal's InputError, either of which fails the test here.
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <iterator>
#include <string>
#include <system_error>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size);

namespace {

// One message and exit 2 for what cannot be replayed (a missing path, a symbolic-link loop, a
// name too long, a device), never an exception out of main.
int Refuse(const std::string& what) {
  std::cerr << "fuzz replay: " << what << "\n";
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  namespace fs = std::filesystem;
  if (argc < 2) return Refuse("usage: " + std::string(argv[0]) + " FILE_OR_FOLDER... (each file given once to the target)");
  std::vector<fs::path> inputs;
  for (int i = 1; i < argc; ++i) {
    const fs::path arg(argv[i]);
    std::error_code error;
    const fs::file_status status = fs::status(arg, error);
    if (error) return Refuse(arg.string() + ": " + error.message());
    if (fs::is_directory(status)) {
      const std::size_t before = inputs.size();
      for (fs::directory_iterator it(arg, error), end; !error && it != end; it.increment(error)) {
        std::error_code entry_error;
        if (it->is_regular_file(entry_error)) inputs.push_back(it->path());  // subfolders, links to nowhere: skipped
      }
      if (error) return Refuse(arg.string() + ": " + error.message());
      if (inputs.size() == before) return Refuse(arg.string() + ": no regular files in this folder");
    } else if (fs::is_regular_file(status)) {
      inputs.push_back(arg);
    } else {
      return Refuse(arg.string() + ": neither a regular file nor a folder");
    }
  }
  std::sort(inputs.begin(), inputs.end());
  for (const fs::path& path : inputs) {
    std::ifstream in(path, std::ios::binary);
    if (!in) return Refuse(path.string() + ": cannot be read");
    const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    std::cout << "replaying " << path.string() << " (" << bytes.size() << " bytes)\n" << std::flush;
    LLVMFuzzerTestOneInput(reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size());
  }
  std::cout << "replayed " << inputs.size() << (inputs.size() == 1 ? " input" : " inputs") << "\n";
  return 0;
}
