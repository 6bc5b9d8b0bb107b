// Splitting a study into shares (what the MPI run does, without MPI): the partition, the
// assembly and the byte encodings.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <set>

#include "montecarlo/montecarlo.h"

namespace cablecal {
namespace {

MonteCarloOptions Study(int trials) {
  MonteCarloOptions o;
  o.pose_counts = {6, 7, 9};
  o.designs = {PoseSetDesign::kRandom, PoseSetDesign::kOptimized};
  o.trials = trials;
  o.seed = 31;
  o.design_starts = 1;
  return o;
}

TEST(StudyShares, EveryItemBelongsToExactlyOneShare) {
  for (long items : {0L, 1L, 3L, 4L, 5L, 17L, 64L, 101L}) {
    for (int count = 1; count <= 5; ++count) {
      long owned_sum = 0;
      for (int k = 0; k < count; ++k) {
        long counted = 0;
        for (long item = 0; item < items; ++item) counted += OwnsItem(StudyShare{k, count}, item);
        EXPECT_EQ(ItemsOwned(StudyShare{k, count}, items), counted) << items << " items, share " << k << "/" << count;
        owned_sum += counted;
      }
      EXPECT_EQ(owned_sum, items);
      for (long item = 0; item < items; ++item) {
        int owners = 0;
        for (int k = 0; k < count; ++k) owners += OwnsItem(StudyShare{k, count}, item);
        EXPECT_EQ(owners, 1) << "item " << item << " of " << items << ", " << count << " shares";
      }
    }
  }
}

TEST(StudyShares, ChunksAreDealtRoundRobin) {
  // Consecutive chunks go to consecutive shares, so costly cells (large n) are spread.
  const StudyShare second{1, 3};
  for (long item = 0; item < 40; ++item) {
    EXPECT_EQ(OwnsItem(second, item), (item / kChunkTrials) % 3 == 1) << item;
  }
}

TEST(StudyShares, AssembledSharesEqualTheWholeRunToTheBit) {
  const Robot& robot = BuiltinRobot();
  const MonteCarloOptions o = Study(7);  // 42 items: chunks cross cell boundaries
  const MonteCarloResult whole = RunMonteCarlo(robot, o);

  DesignedSets designed;
  const std::vector<DesignedSetKey> keys = DesignedSetKeys(o);
  ASSERT_EQ(keys.size(), 3u);
  for (const DesignedSetKey& key : keys) {
    // Through the byte encoding, as between MPI ranks.
    designed[{key.n, static_cast<int>(key.design)}] = DecodePoses(EncodePoses(MakeDesignedSet(robot, o, key)));
  }
  for (int count : {2, 3, 5}) {
    std::vector<ShareResult> shares(count);
    for (int k = 0; k < count; ++k) {
      ShareResult s = RunShare(robot, o, designed, StudyShare{k, count});
      ASSERT_TRUE(s.failure.empty()) << s.failure;
      shares[k].outcomes = DecodeOutcomes(EncodeOutcomes(s.outcomes));
    }
    const MonteCarloResult assembled = AssembleShares(o, std::move(shares), PlanarStudyNames(robot.num_cables()));
    EXPECT_EQ(ErrorsCsv(assembled), ErrorsCsv(whole)) << count << " shares";
    EXPECT_EQ(SummaryCsv(assembled), SummaryCsv(whole)) << count << " shares";
    EXPECT_EQ(SummaryMarkdown(assembled, "t"), SummaryMarkdown(whole, "t")) << count << " shares";
  }
  EXPECT_GT(ErrorsCsv(whole).size(), 2000u);
}

TEST(StudyShares, DescribesTheCellsAShareHolds) {
  MonteCarloOptions o = Study(10);
  // 6 cells of 10 trials. Share 1 of 3 owns items 4-7, 16-19, 28-31, 40-43, 52-55: 4 in
  // cell 0 (items 0-9), 4 in cell 1 (10-19), 2 in cell 2 (20-29), 2 in cell 3, ...
  const std::string text = DescribeShareCells(o, StudyShare{1, 3});
  EXPECT_EQ(text.rfind("n=6 random (4 of 10 trials), n=6 optimized (4 of 10 trials), n=7 random (2 of 10 trials)", 0), 0u)
      << text;
  const std::string short_text = DescribeShareCells(o, StudyShare{1, 3}, 2);
  EXPECT_NE(short_text.find(" more cells"), std::string::npos) << short_text;
  EXPECT_EQ(DescribeShareCells(o, StudyShare{15, 16}), "no cells");  // 60 items: chunks 0..14
}

TEST(StudyShares, EncodingsKeepEveryBit) {
  std::vector<TrialOutcome> outcomes(3);
  outcomes[0].ok = true;
  outcomes[0].errors_m = {1e-300, -0.0, 0.1 + 0.2, std::numeric_limits<double>::denorm_min()};
  outcomes[1].failure = "simulation: the true robot cannot hold pose 3";
  outcomes[2].ok = true;
  const std::vector<TrialOutcome> back = DecodeOutcomes(EncodeOutcomes(outcomes));
  ASSERT_EQ(back.size(), 3u);
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(back[i].ok, outcomes[i].ok);
    EXPECT_EQ(back[i].failure, outcomes[i].failure);
    ASSERT_EQ(back[i].errors_m.size(), outcomes[i].errors_m.size());
    for (std::size_t k = 0; k < back[i].errors_m.size(); ++k) {
      EXPECT_EQ(std::signbit(back[i].errors_m[k]), std::signbit(outcomes[i].errors_m[k]));
      EXPECT_EQ(back[i].errors_m[k], outcomes[i].errors_m[k]);
    }
  }
  const std::vector<PlanPose> poses = SampleFeasiblePoses(BuiltinRobot(), 4, 3);
  const std::vector<PlanPose> poses_back = DecodePoses(EncodePoses(poses));
  ASSERT_EQ(poses_back.size(), poses.size());
  for (std::size_t j = 0; j < poses.size(); ++j) {
    EXPECT_EQ(poses_back[j].q, poses[j].q);
    EXPECT_EQ(poses_back[j].tensions_N, poses[j].tensions_N);
    EXPECT_EQ(poses_back[j].lengths_m, poses[j].lengths_m);
    EXPECT_EQ(poses_back[j].length_change_m, poses[j].length_change_m);
  }
}

TEST(StudyShares, MalformedMessagesAreRejected) {
  std::vector<TrialOutcome> outcomes(2);
  outcomes[0].ok = true;
  outcomes[0].errors_m = {1.0, 2.0};
  const std::string bytes = EncodeOutcomes(outcomes);
  for (std::size_t cut = 0; cut < bytes.size(); ++cut) {
    EXPECT_THROW(DecodeOutcomes(bytes.substr(0, cut)), std::runtime_error) << "cut at " << cut;
  }
  EXPECT_THROW(DecodeOutcomes(bytes + "x"), std::runtime_error);
  std::string huge = bytes;
  huge[0] = '\xff';  // a count far beyond the bytes that follow
  EXPECT_THROW(DecodeOutcomes(huge), std::runtime_error);
  const std::string poses = EncodePoses(SampleFeasiblePoses(BuiltinRobot(), 2, 5));
  for (std::size_t cut = 0; cut < poses.size(); cut += 7) {
    EXPECT_THROW(DecodePoses(poses.substr(0, cut)), std::runtime_error) << "cut at " << cut;
  }
}

}  // namespace
}  // namespace cablecal
