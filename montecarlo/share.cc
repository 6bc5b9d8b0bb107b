// Splitting a Monte Carlo study into shares, assembling them, and the byte encodings the
// shares travel in (montecarlo.h, "Splitting a study into shares").
#include <cstdint>
#include <cstring>
#include <stdexcept>

#include "common/error.h"
#include "model/geometry.h"
#include "model/kind.h"
#include "montecarlo/montecarlo.h"

namespace cablecal {

long StudyItems(const MonteCarloOptions& o) {
  return static_cast<long>(o.pose_counts.size()) * static_cast<long>(o.designs.size()) * o.trials;
}

namespace {
// The index of the share that owns `item` when a study is split into `count` shares.
int OwnerOf(long item, int count) { return static_cast<int>((item / kChunkTrials) % count); }
}  // namespace

bool OwnsItem(const StudyShare& share, long item) { return OwnerOf(item, share.count) == share.index; }

long ItemsOwned(const StudyShare& share, long items) {
  const long chunks = (items + kChunkTrials - 1) / kChunkTrials;
  // This share's chunks are all full but the study's last one, which may be short.
  const long mine = chunks / share.count + (chunks % share.count > share.index ? 1 : 0);
  long owned = mine * kChunkTrials;
  if (chunks > 0 && (chunks - 1) % share.count == share.index) owned -= chunks * kChunkTrials - items;
  return owned;
}

std::vector<DesignedSetKey> DesignedSetKeys(const MonteCarloOptions& o) {
  std::vector<DesignedSetKey> keys;
  for (int n : o.pose_counts) {
    for (PoseSetDesign d : o.designs) {
      if (d != PoseSetDesign::kRandom) keys.push_back({n, d});
    }
  }
  return keys;
}

StudyNames PlanarStudyNames(int num_cables) {
  StudyNames names;
  names.geometry = GeometryNames(num_cables);
  names.held = {names.geometry[0]};  // a1x: every planar gauge holds it
  return names;
}

MonteCarloResult AssembleShares(const MonteCarloOptions& o, std::vector<ShareResult>&& shares, const StudyNames& names) {
  const int count = static_cast<int>(shares.size());
  CABLECAL_CHECK(count >= 1, "no shares");
  const long total = StudyItems(o);
  for (int k = 0; k < count; ++k) {
    CABLECAL_CHECK(shares[k].failure.empty() && !shares[k].interrupted, "share " + std::to_string(k) + " did not finish");
    CABLECAL_CHECK(static_cast<long>(shares[k].outcomes.size()) == ItemsOwned(StudyShare{k, count}, total),
                   "share " + std::to_string(k) + " has " + std::to_string(shares[k].outcomes.size()) + " outcomes");
  }
  MonteCarloResult result;
  result.geometry_names = names.geometry;
  result.held_names = names.held;
  result.geometry_sigma_m = o.geometry_sigma_m;
  result.geometry_prior = o.geometry_prior;
  for (int n : o.pose_counts) {
    for (PoseSetDesign d : o.designs) {
      MonteCarloCell cell;
      cell.n = n;
      cell.design = d;
      cell.trials.resize(o.trials);
      result.cells.push_back(std::move(cell));
    }
  }
  std::vector<std::size_t> next(count, 0);
  for (long item = 0; item < total; ++item) {
    const int k = OwnerOf(item, count);
    result.cells[item / o.trials].trials[item % o.trials] = std::move(shares[k].outcomes[next[k]++]);
  }
  return result;
}

std::string DescribeShareCells(const MonteCarloOptions& o, const StudyShare& share, int max_cells) {
  std::string out;
  int named = 0, cells_hit = 0;
  const long cells = static_cast<long>(o.pose_counts.size() * o.designs.size());
  const int designs = static_cast<int>(o.designs.size());
  for (long c = 0; c < cells; ++c) {
    int lost = 0;
    for (long t = 0; t < o.trials; ++t) lost += OwnsItem(share, c * o.trials + t);
    if (lost == 0) continue;
    ++cells_hit;
    if (named == max_cells) continue;
    ++named;
    out += (out.empty() ? "" : ", ") + std::string("n=") + std::to_string(o.pose_counts[c / designs]) + " " +
           ToString(o.designs[c % designs]) + " (" + std::to_string(lost) + " of " + std::to_string(o.trials) +
           " trials)";
  }
  if (cells_hit > named) out += " and " + std::to_string(cells_hit - named) + " more cells";
  return out.empty() ? "no cells" : out;
}

namespace {

// Fixed-width little helpers: the processes of one MPI job share an architecture, so
// values are copied as they are in memory.
template <class T>
void Put(std::string* out, const T& v) {
  out->append(reinterpret_cast<const char*>(&v), sizeof(T));
}

class Reader {
 public:
  explicit Reader(const std::string& bytes) : bytes_(bytes) {}
  template <class T>
  T Get() {
    Need(sizeof(T));
    T v;
    std::memcpy(&v, bytes_.data() + at_, sizeof(T));
    at_ += sizeof(T);
    return v;
  }
  std::string GetString(std::size_t size) {
    Need(size);
    std::string s = bytes_.substr(at_, size);
    at_ += size;
    return s;
  }
  // A count of items of `item_size` bytes each that must fit in what is left.
  std::uint64_t GetCount(std::size_t item_size) {
    const auto count = Get<std::uint64_t>();
    if (item_size > 0 && count > (bytes_.size() - at_) / item_size) Fail();
    return count;
  }
  bool AtEnd() const { return at_ == bytes_.size(); }

 private:
  void Need(std::size_t size) const {
    if (size > bytes_.size() - at_) Fail();
  }
  [[noreturn]] static void Fail() { throw std::runtime_error("malformed Monte Carlo message"); }
  const std::string& bytes_;
  std::size_t at_ = 0;
};

void PutVector(std::string* out, const Eigen::VectorXd& v) {
  Put<std::uint64_t>(out, static_cast<std::uint64_t>(v.size()));
  for (Eigen::Index i = 0; i < v.size(); ++i) Put(out, v(i));
}

Eigen::VectorXd GetVector(Reader* in) {
  Eigen::VectorXd v(static_cast<Eigen::Index>(in->GetCount(sizeof(double))));
  for (Eigen::Index i = 0; i < v.size(); ++i) v(i) = in->Get<double>();
  return v;
}

}  // namespace

std::string EncodeOutcomes(const std::vector<TrialOutcome>& outcomes) {
  std::string out;
  Put<std::uint64_t>(&out, outcomes.size());
  for (const TrialOutcome& t : outcomes) {
    Put<std::uint8_t>(&out, t.ok ? 1 : 0);
    Put<std::uint64_t>(&out, t.failure.size());
    out += t.failure;
    Put<std::uint64_t>(&out, t.errors_m.size());
    for (double e : t.errors_m) Put(&out, e);
  }
  return out;
}

std::vector<TrialOutcome> DecodeOutcomes(const std::string& bytes) {
  Reader in(bytes);
  std::vector<TrialOutcome> outcomes(in.GetCount(1 + 2 * sizeof(std::uint64_t)));
  for (TrialOutcome& t : outcomes) {
    const auto ok = in.Get<std::uint8_t>();
    if (ok > 1) throw std::runtime_error("malformed Monte Carlo message");
    t.ok = ok == 1;
    t.failure = in.GetString(in.GetCount(1));
    t.errors_m.resize(in.GetCount(sizeof(double)));
    for (double& e : t.errors_m) e = in.Get<double>();
  }
  if (!in.AtEnd()) throw std::runtime_error("malformed Monte Carlo message");
  return outcomes;
}

std::string EncodePoses(const std::vector<PlanPose>& poses) {
  std::string out;
  Put<std::uint64_t>(&out, poses.size());
  for (const PlanPose& p : poses) {
    for (int i = 0; i < PlanarKind::kPoseDim; ++i) Put(&out, p.q(i));
    PutVector(&out, p.tensions_N);
    PutVector(&out, p.lengths_m);
    PutVector(&out, p.length_change_m);
  }
  return out;
}

std::vector<PlanPose> DecodePoses(const std::string& bytes) {
  Reader in(bytes);
  std::vector<PlanPose> poses(in.GetCount(PlanarKind::kPoseDim * sizeof(double) + 3 * sizeof(std::uint64_t)));
  for (PlanPose& p : poses) {
    for (int i = 0; i < PlanarKind::kPoseDim; ++i) p.q(i) = in.Get<double>();
    p.tensions_N = GetVector(&in);
    p.lengths_m = GetVector(&in);
    p.length_change_m = GetVector(&in);
  }
  if (!in.AtEnd()) throw std::runtime_error("malformed Monte Carlo message");
  return poses;
}

}  // namespace cablecal
