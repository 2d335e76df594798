// End to end: runs the built tutorial-hslam-evaluate and parses its key=value output.
// The program is found relative to this test executable (<build>/test/ -> <build>/tutorials/).
#include "HSlamTestData.h"
#include "HSlamTestPrograms.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>
#include <unistd.h>

namespace
{
std::string tutorialPath()
{
  return hslam_test::builtTutorialPath("tutorial-hslam-evaluate");
}

using RunResult = hslam_test::ProgramRun;

RunResult runTutorial(const std::string &arguments)
{
  return hslam_test::runProgram(tutorialPath(), arguments);
}

//! Value of "key=<number>" at the start of an output line, NaN when absent.
double valueOf(const std::string &output, const std::string &key)
{
  const std::string text = "\n" + output;
  const size_t pos = text.find("\n" + key + "=");
  if (pos == std::string::npos) {
    return std::nan("");
  }
  return std::strtod(text.c_str() + pos + key.size() + 2, nullptr);
}

#define HSLAM_REQUIRE_TUTORIAL()                                                                                       \
  if (tutorialPath().empty()) {                                                                                        \
    GTEST_SKIP() << "tutorial-hslam-evaluate not built next to this test (configure with HSLAM_BUILD_TUTORIALS=ON)";   \
  }
} // namespace

TEST(EvaluateTutorial, ReproducesReferenceAte)
{
  HSLAM_REQUIRE_TUTORIAL();
  HSLAM_REQUIRE_SHARED_DATA(estimatePath, "ate_reference/MH_04_estimate.txt");
  HSLAM_REQUIRE_SHARED_DATA(groundTruthPath, "ate_reference/MH_04_groundtruth.txt");
  const std::string plot = ::testing::TempDir() + "/hslam_evaluate_" + std::to_string(::getpid()) + ".png";
  const RunResult sim3 = runTutorial("--groundtruth " + groundTruthPath + " --estimate " + estimatePath +
                                     " --align sim3 --max-dt 0.02 --plot " + plot);
  ASSERT_EQ(sim3.exitCode, 0) << sim3.output;
  EXPECT_NEAR(valueOf(sim3.output, "ate_rmse_m"), 0.0869, 1e-4) << sim3.output;
  EXPECT_NEAR(valueOf(sim3.output, "scale"), 0.9934, 1e-4) << sim3.output;
  EXPECT_EQ(valueOf(sim3.output, "matched"), 187.) << sim3.output;
  EXPECT_GT(valueOf(sim3.output, "rpe_trans_rmse_m"), 0.) << sim3.output;
  std::ifstream png(plot, std::ios::binary | std::ios::ate);
  EXPECT_GT(png.tellg(), 1000) << "plot not written: " << plot;
  std::remove(plot.c_str());

  const RunResult se3 =
      runTutorial("--groundtruth " + groundTruthPath + " --estimate " + estimatePath + " --align se3");
  ASSERT_EQ(se3.exitCode, 0) << se3.output;
  EXPECT_NEAR(valueOf(se3.output, "ate_rmse_m"), 0.1030, 1e-4) << se3.output;
}

TEST(EvaluateTutorial, BadInputExitsNonZeroWithMessage)
{
  HSLAM_REQUIRE_TUTORIAL();
  const std::string dir = ::testing::TempDir();
  const std::string good = dir + "/hslam_eval_good_" + std::to_string(::getpid()) + ".txt";
  const std::string bad = dir + "/hslam_eval_bad_" + std::to_string(::getpid()) + ".txt";
  {
    std::ofstream g(good);
    for (int i = 0; i < 10; ++i) {
      g << i * 0.1 << " " << i << " " << i * i << " 0 0 0 0 1\n";
    }
    std::ofstream b(bad);
    b << "0 0 0 0 0 0 0 1\n0.1 0 0 0 0 0 0 2\n";
  }
  const RunResult self = runTutorial("--groundtruth " + good + " --estimate " + good + " --align se3");
  ASSERT_EQ(self.exitCode, 0) << self.output;
  EXPECT_NEAR(valueOf(self.output, "ate_rmse_m"), 0., 1e-9) << self.output;

  const RunResult quaternion = runTutorial("--groundtruth " + good + " --estimate " + bad);
  EXPECT_NE(quaternion.exitCode, 0);
  EXPECT_NE(quaternion.output.find(bad + ":2:"), std::string::npos) << quaternion.output;

  const RunResult missing = runTutorial("--groundtruth " + good + " --estimate " + dir + "/no_such_file.txt");
  EXPECT_NE(missing.exitCode, 0);
  EXPECT_NE(missing.output.find("no_such_file.txt"), std::string::npos) << missing.output;

  const RunResult option = runTutorial("--groundtruth " + good + " --estimate " + good + " --align affine");
  EXPECT_NE(option.exitCode, 0);
  EXPECT_NE(option.output.find("affine"), std::string::npos) << option.output;

  const RunResult usage = runTutorial("--estimate " + good);
  EXPECT_NE(usage.exitCode, 0);
  EXPECT_NE(usage.output.find("--groundtruth"), std::string::npos) << usage.output;

  // Timestamps that never meet (e.g. another clock): a clear error naming the cause, not a crash.
  const std::string far = dir + "/hslam_eval_far_" + std::to_string(::getpid()) + ".txt";
  {
    std::ofstream f(far);
    for (int i = 0; i < 10; ++i) {
      f << 1000. + i * 0.1 << " " << i << " 0 0 0 0 0 1\n";
    }
  }
  const RunResult apart = runTutorial("--groundtruth " + good + " --estimate " + far);
  EXPECT_NE(apart.exitCode, 0);
  EXPECT_NE(apart.output.find("0 of 10"), std::string::npos) << apart.output;
  std::remove(far.c_str());
  std::remove(good.c_str());
  std::remove(bad.c_str());
}

TEST(EvaluateTutorial, FromAndToEvaluateOnlyThePosesBetweenThem)
{
  HSLAM_REQUIRE_TUTORIAL();
  const std::string dir = ::testing::TempDir();
  const std::string truth = dir + "/hslam_eval_span_gt_" + std::to_string(::getpid()) + ".txt";
  const std::string estimate = dir + "/hslam_eval_span_est_" + std::to_string(::getpid()) + ".txt";
  {
    // A straight line; the estimate is exact from t = 1 s on and 0.5 m off sideways before it.
    std::ofstream g(truth);
    std::ofstream e(estimate);
    for (int i = 0; i < 20; ++i) {
      const double t = 0.1 * i;
      g << t << " " << i << " 0 0 0 0 0 1\n";
      e << t << " " << i << " " << (i < 10 ? 0.5 : 0.) << " 0 0 0 0 1\n";
    }
  }
  const std::string files = "--groundtruth " + truth + " --estimate " + estimate + " --align se3";
  const RunResult whole = runTutorial(files);
  ASSERT_EQ(whole.exitCode, 0) << whole.output;
  EXPECT_EQ(valueOf(whole.output, "matched"), 20.) << whole.output;
  EXPECT_GT(valueOf(whole.output, "ate_rmse_m"), 0.1) << whole.output;

  const RunResult late = runTutorial(files + " --from 0.95");
  ASSERT_EQ(late.exitCode, 0) << late.output;
  EXPECT_EQ(valueOf(late.output, "matched"), 10.) << late.output;
  EXPECT_NEAR(valueOf(late.output, "ate_rmse_m"), 0., 1e-6) << late.output;

  const RunResult early = runTutorial(files + " --to 0.45");
  ASSERT_EQ(early.exitCode, 0) << early.output;
  EXPECT_EQ(valueOf(early.output, "matched"), 5.) << early.output;
  EXPECT_NEAR(valueOf(early.output, "ate_rmse_m"), 0., 1e-6) << early.output; // offset alike: aligned away

  const RunResult reversed = runTutorial(files + " --from 1 --to 0.5");
  EXPECT_NE(reversed.exitCode, 0);
  EXPECT_NE(reversed.output.find("--from"), std::string::npos) << reversed.output;
  const RunResult empty = runTutorial(files + " --from 5");
  EXPECT_NE(empty.exitCode, 0);
  EXPECT_NE(empty.output.find("no estimated pose"), std::string::npos) << empty.output;
  std::remove(truth.c_str());
  std::remove(estimate.c_str());
}
