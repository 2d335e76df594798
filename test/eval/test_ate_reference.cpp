// ATE against the reference values of ../shared/data/README.md (EuRoC MH_04 estimate from
// rpg_trajectory_evaluation, evaluated by positions with Umeyama alignment, pairs within 0.02 s).
#include "HSlamTestData.h"

#include <visp3/hslam/vpHSlamTrajectory.h>
#include <visp3/hslam/vpHSlamTrajectoryEvaluator.h>

namespace
{
constexpr double kReferenceTolerance = 1e-4; // metres: the README prints 4 decimals
}

TEST(AteReference, MH04MatchesPublishedNumbers)
{
  HSLAM_REQUIRE_SHARED_DATA(estimatePath, "ate_reference/MH_04_estimate.txt");
  HSLAM_REQUIRE_SHARED_DATA(groundTruthPath, "ate_reference/MH_04_groundtruth.txt");
  const vpHSlamTrajectory estimate = vpHSlamTrajectory::readTum(estimatePath);
  const vpHSlamTrajectory groundTruth = vpHSlamTrajectory::readTum(groundTruthPath);
  ASSERT_EQ(estimate.size(), 187u);
  ASSERT_EQ(groundTruth.size(), 19753u);

  const vpHSlamTrajectoryEvaluator evaluator(groundTruth, estimate, 0.02);
  EXPECT_EQ(evaluator.getMatchedCount(), 187u);

  const vpHSlamTrajectoryEvaluator::AteResult se3 = evaluator.computeAte(vpHSlamTrajectoryEvaluator::alignSE3);
  EXPECT_EQ(se3.error.count, 187u);
  EXPECT_NEAR(se3.error.rmse, 0.1030, kReferenceTolerance);
  EXPECT_DOUBLE_EQ(se3.scale, 1.);

  const vpHSlamTrajectoryEvaluator::AteResult sim3 = evaluator.computeAte(vpHSlamTrajectoryEvaluator::alignSim3);
  EXPECT_NEAR(sim3.error.rmse, 0.0869, kReferenceTolerance);
  EXPECT_NEAR(sim3.scale, 0.9934, kReferenceTolerance);

  // Consistency of the statistics on real data.
  EXPECT_LE(sim3.error.min, sim3.error.median);
  EXPECT_LE(sim3.error.median, sim3.error.max);
  EXPECT_LE(sim3.error.mean, sim3.error.rmse);
  EXPECT_NEAR(sim3.error.rmse * sim3.error.rmse, sim3.error.mean * sim3.error.mean + sim3.error.std * sim3.error.std,
              1e-12);
  // Sim(3) has one more degree of freedom than SE(3): never worse.
  EXPECT_LE(sim3.error.rmse, se3.error.rmse);
}
