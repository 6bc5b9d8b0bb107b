#include "montecarlo/mpi.h"

#include <mpi.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <stdexcept>
#include <string>

#include "common/error.h"

namespace cablecal {
namespace {

// Messages longer than this go in pieces: MPI counts are ints.
constexpr std::uint64_t kPieceBytes = std::uint64_t{1} << 28;
constexpr int kTagShare = 17;

// One rank's status: an exit code (0: fine), a message and a payload.
struct Status {
  int code = 0;
  std::string text;
  std::string payload;
};

std::string EncodeStatus(const Status& s) {
  std::string out;
  const std::int32_t code = s.code;
  const std::uint64_t size = s.text.size();
  out.append(reinterpret_cast<const char*>(&code), sizeof(code));
  out.append(reinterpret_cast<const char*>(&size), sizeof(size));
  return out + s.text + s.payload;
}

Status DecodeStatus(const std::string& bytes) {
  Status s;
  std::int32_t code = 0;
  std::uint64_t size = 0;
  if (bytes.size() < sizeof(code) + sizeof(size)) throw std::runtime_error("malformed Monte Carlo status");
  std::memcpy(&code, bytes.data(), sizeof(code));
  std::memcpy(&size, bytes.data() + sizeof(code), sizeof(size));
  const std::size_t at = sizeof(code) + sizeof(size);
  if (size > bytes.size() - at) throw std::runtime_error("malformed Monte Carlo status");
  s.code = code;
  s.text = bytes.substr(at, size);
  s.payload = bytes.substr(at + size);
  return s;
}

// The exit code and message of the exception being handled (error.h's tiers).
Status StatusOfCurrentException() {
  const ErrorOutcome error = OutcomeOf(std::current_exception());
  return {error.exit_code, error.message, ""};
}

[[noreturn]] void ThrowStatus(const Status& s) {
  switch (s.code) {
    case kExitBadInput: throw InputError("", "", s.text);
    case kExitSolverFailed: throw SolverFailure(s.text);
    case kExitRankFailed: throw RankFailure(s.text);
    case kExitInterrupted: throw Interrupted();
    default: throw std::runtime_error(s.text);
  }
}

void Broadcast(std::string* bytes, int root) {
  std::uint64_t size = bytes->size();
  MPI_Bcast(&size, 1, MPI_UINT64_T, root, MPI_COMM_WORLD);
  bytes->resize(size);
  for (std::uint64_t at = 0; at < size; at += kPieceBytes) {
    MPI_Bcast(bytes->data() + at, static_cast<int>(std::min(kPieceBytes, size - at)), MPI_BYTE, root, MPI_COMM_WORLD);
  }
}

void Send(const std::string& bytes, int to) {
  const std::uint64_t size = bytes.size();
  MPI_Send(&size, 1, MPI_UINT64_T, to, kTagShare, MPI_COMM_WORLD);
  for (std::uint64_t at = 0; at < size; at += kPieceBytes) {
    MPI_Send(bytes.data() + at, static_cast<int>(std::min(kPieceBytes, size - at)), MPI_BYTE, to, kTagShare,
             MPI_COMM_WORLD);
  }
}

std::string Receive(int from) {
  std::uint64_t size = 0;
  MPI_Recv(&size, 1, MPI_UINT64_T, from, kTagShare, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
  std::string bytes(size, '\0');
  for (std::uint64_t at = 0; at < size; at += kPieceBytes) {
    MPI_Recv(bytes.data() + at, static_cast<int>(std::min(kPieceBytes, size - at)), MPI_BYTE, from, kTagShare,
             MPI_COMM_WORLD, MPI_STATUS_IGNORE);
  }
  return bytes;
}

// A failure every rank knows of: rank 0 throws it (and main() prints it), the others
// AlreadyReported with its exit code.
[[noreturn]] void ThrowOnEveryRank(const MpiWorld& world, const Status& failure) {
  if (world.rank == 0) ThrowStatus(failure);
  throw AlreadyReported(failure.code);
}

// Rank 0 decides, every rank learns the verdict. Returns normally when the verdict is 0.
void Verdict(const MpiWorld& world, const Status& decided) {
  std::int32_t code = decided.code;
  MPI_Bcast(&code, 1, MPI_INT32_T, 0, MPI_COMM_WORLD);
  if (code == 0) return;
  ThrowOnEveryRank(world, Status{code, decided.text, ""});
}

// CABLECAL_TEST_FAIL_RANK: "k" fails rank k's share, "k:crash" aborts rank k.
void InjectTestFault(const MpiWorld& world) {
  const char* value = std::getenv(kTestFailRankVariable);
  if (!value || !*value) return;
  const std::string text = value;
  const std::string rank = text.substr(0, text.find(':'));
  if (rank != std::to_string(world.rank)) return;
  if (text.size() > rank.size() && text.substr(rank.size()) == ":crash") std::abort();
  throw std::runtime_error(std::string("test fault injected by ") + kTestFailRankVariable + "=" + text);
}

// Every rank makes its designed sets, then each is broadcast from the rank that made it.
DesignedSets MakeDesignedSets(const Robot& nominal, const MonteCarloOptions& o, const MpiWorld& world) {
  const std::vector<DesignedSetKey> keys = DesignedSetKeys(o);
  std::vector<std::string> messages(keys.size());
  std::atomic<bool> failed{false};
  ForEachDesignedSet(keys, [&](std::size_t i) {
    if (static_cast<int>(i % world.size) != world.rank) return;
    Status s;
    if (failed.load()) {
      s.code = -1;  // skipped after an earlier failure of this rank
    } else if (o.interrupted && o.interrupted->load()) {
      s.code = kExitInterrupted;
    } else {
      try {
        s.payload = EncodePoses(MakeDesignedSet(nominal, o, keys[i]));
      } catch (...) {
        s = StatusOfCurrentException();
        failed = true;
      }
    }
    messages[i] = EncodeStatus(s);
  });
  DesignedSets designed;
  Status first_failure, interrupted;
  for (std::size_t i = 0; i < keys.size(); ++i) {
    Broadcast(&messages[i], static_cast<int>(i % world.size));
    const Status s = DecodeStatus(messages[i]);
    if (s.code == kExitInterrupted) {
      interrupted = s;
    } else if (s.code != 0 && s.code != -1 && first_failure.code == 0) {
      first_failure = s;
    } else if (s.code == 0) {
      designed[{keys[i].n, static_cast<int>(keys[i].design)}] = DecodePoses(s.payload);
    }
  }
  // Every rank saw the same messages, so every rank reaches the same verdict.
  const Status& verdict = first_failure.code != 0 ? first_failure : interrupted;
  if (verdict.code != 0) ThrowOnEveryRank(world, verdict);
  return designed;
}

}  // namespace

MpiWorld WorldOf() {
  MpiWorld w;
  // PMPI_: Debian's sequential MUMPS (linked through Ipopt) exports stand-ins for
  // MPI_Comm_rank, MPI_Init, MPI_Finalize and MPI_Wtime that take precedence over Open
  // MPI's (its MPI_Comm_rank answers 0 on every rank); the profiling names, which every MPI
  // provides, always reach the real library.
  PMPI_Comm_rank(MPI_COMM_WORLD, &w.rank);
  MPI_Comm_size(MPI_COMM_WORLD, &w.size);
  return w;
}

MonteCarloResult RunMonteCarloMpi(const Robot& nominal, const MonteCarloOptions& options) {
  const auto t0 = std::chrono::steady_clock::now();
  const MpiWorld world = WorldOf();
  try {
    ValidateOptions(options, &nominal);
  } catch (const InputError&) {
    if (world.rank == 0) throw;
    throw AlreadyReported(kExitBadInput);  // every rank has the same options
  }
  MonteCarloOptions o = options;
  if (world.rank != 0) o.progress = nullptr;  // rank 0 shows its own share's progress
  // MPI implementations warn about, or break on, fork() in a rank (Open MPI with some
  // transports): with several ranks the designs' solves stay in-process (the ranks share them).
  if (world.size > 1) o.design_in_child_processes = false;

  const DesignedSets designed = MakeDesignedSets(nominal, o, world);

  ShareResult mine;
  try {
    InjectTestFault(world);
    mine = RunShare(nominal, o, designed, StudyShare{world.rank, world.size});
  } catch (const std::exception& e) {
    mine = ShareResult{};
    mine.failure = e.what();
  }
  Status status;
  if (!mine.failure.empty()) {
    status = {kExitRankFailed, mine.failure, ""};
  } else if (mine.interrupted) {
    status.code = kExitInterrupted;
  } else {
    status.payload = EncodeOutcomes(mine.outcomes);
  }
  mine.outcomes.clear();
  const std::string message = EncodeStatus(status);

  if (world.rank != 0) {
    Send(message, 0);
    Verdict(world, Status{});  // rank 0 decides; this throws unless every share arrived
    return MonteCarloResult{};
  }

  // Rank 0: gather every share (its own first), then decide.
  std::vector<ShareResult> shares(world.size);
  std::string lost;
  bool interrupted = false;
  for (int k = 0; k < world.size; ++k) {
    const StudyShare share{k, world.size};
    Status s;
    try {
      s = DecodeStatus(k == 0 ? message : Receive(k));
      if (s.code == 0) {
        shares[k].outcomes = DecodeOutcomes(s.payload);
        if (static_cast<long>(shares[k].outcomes.size()) != ItemsOwned(share, StudyItems(o))) {
          throw std::runtime_error("it holds " + std::to_string(shares[k].outcomes.size()) + " trials");
        }
      }
    } catch (const std::exception& e) {
      s = {kExitRankFailed, std::string("its share arrived damaged: ") + e.what(), ""};
    }
    if (s.code == kExitInterrupted) interrupted = true;
    if (s.code != 0 && s.code != kExitInterrupted) {
      lost += "\n  rank " + std::to_string(k) + " of " + std::to_string(world.size) + ": " + s.text +
              "; lost its trials of " + DescribeShareCells(o, share);
    }
  }
  if (!lost.empty()) Verdict(world, Status{kExitRankFailed, "the run is incomplete, nothing was written:" + lost, ""});
  if (interrupted) Verdict(world, Status{kExitInterrupted, "", ""});
  Verdict(world, Status{});
  MonteCarloResult result = AssembleShares(o, std::move(shares), PlanarStudyNames(nominal.num_cables()));
  result.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return result;
}

}  // namespace cablecal
