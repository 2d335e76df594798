// End to end: the dataset program's stress options. --stride K feeds every K-th frame of the source (large motion),
// --blackout A:B feeds black frames (a covered lens), --tracking-mode overrides the configuration; malformed values
// are refused with an error naming the option, before the source is opened. Runs on the first frames of a shared
// sequence (skipped when ../shared/data is absent).
#include "HSlamTestData.h"
#include "HSlamTestPrograms.h"

#include <visp3/hslam/vpHSlamTrajectory.h>
#include <visp3/hslam/vpHSlamTrajectoryEvaluator.h>

#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>
#include <iostream>
#include <string>
#include <unistd.h>

namespace
{
const char *const kSequence = "tsukuba_cg_000-149";

std::string tutorialPath()
{
  return hslam_test::builtTutorialPath("tutorial-hslam-dataset");
}

hslam_test::ProgramRun runTutorial(const std::string &arguments)
{
  return hslam_test::runProgram(tutorialPath(), arguments);
}

std::string scratch(const std::string &name)
{
  const char *tmp = std::getenv("TMPDIR");
  return std::string((tmp && *tmp) ? tmp : "/tmp") + "/hslam-test-stress-" + std::to_string(::getpid()) + "-" + name;
}

#define HSLAM_REQUIRE_DATASET_TUTORIAL()                                                                               \
  if (tutorialPath().empty()) {                                                                                        \
    GTEST_SKIP() << "tutorial-hslam-dataset is not built";                                                             \
  }

//! The run fails, and its output names the option and the value refused.
void expectRefused(const std::string &options, const std::string &option, const std::string &value)
{
  const hslam_test::ProgramRun r = runTutorial("--input /nonexistent --no-display " + options);
  EXPECT_NE(r.exitCode, 0) << options << "\n" << r.output;
  EXPECT_NE(r.output.find("error: " + option), std::string::npos) << options << "\n" << r.output;
  EXPECT_NE(r.output.find("'" + value + "'"), std::string::npos) << options << "\n" << r.output;
  // Refused while parsing: the missing input is never reached.
  EXPECT_EQ(r.output.find("does not exist"), std::string::npos) << options << "\n" << r.output;
}
} // namespace

TEST(DatasetStressOptions, MalformedStrideIsAClearError)
{
  HSLAM_REQUIRE_DATASET_TUTORIAL();
  for (const char *value : {"0", "-3", "x", "2.5", "3x", "", "+2", "99999999999"}) {
    expectRefused(std::string("--stride '") + value + "'", "--stride", value);
  }
}

TEST(DatasetStressOptions, MalformedBlackoutIsAClearError)
{
  HSLAM_REQUIRE_DATASET_TUTORIAL();
  for (const char *value : {"5", "5:", ":5", "9:3", "-1:4", "a:b", "1:2:3", "1-4", ""}) {
    expectRefused(std::string("--blackout '") + value + "'", "--blackout", value);
  }
}

TEST(DatasetStressOptions, UnknownTrackingModeIsAClearError)
{
  HSLAM_REQUIRE_DATASET_TUTORIAL();
  for (const char *value : {"fast", "Hybrid", ""}) {
    expectRefused(std::string("--tracking-mode '") + value + "'", "--tracking-mode", value);
  }
}

TEST(DatasetStressOptions, TrackingModeOverridesTheConfiguration)
{
  HSLAM_REQUIRE_DATASET_TUTORIAL();
  const std::string config = scratch("indirect.yaml"), saved = scratch("saved.yaml");
  std::ofstream(config) << "%YAML:1.0\ntracking:\n  mode: indirect\n";
  // The settings are saved before the source is opened: a missing input still shows which mode was chosen.
  runTutorial("--input /nonexistent --no-display --config " + config + " --save-config " + saved);
  EXPECT_NE(hslam_test::readTextFile(saved).find("  mode: indirect\n"), std::string::npos);
  std::remove(saved.c_str());
  runTutorial("--input /nonexistent --no-display --config " + config + " --tracking-mode direct --save-config " +
              saved);
  const std::string yaml = hslam_test::readTextFile(saved);
  EXPECT_NE(yaml.find("  mode: direct\n"), std::string::npos) << yaml;
  EXPECT_EQ(yaml.find("  mode: indirect\n"), std::string::npos) << yaml;
  std::remove(config.c_str());
  std::remove(saved.c_str());
}

TEST(DatasetStressOptions, SetChangesOneSettingAfterTheConfiguration)
{
  HSLAM_REQUIRE_DATASET_TUTORIAL();
  const std::string config = scratch("set.yaml"), saved = scratch("set-saved.yaml");
  std::ofstream(config) << "%YAML:1.0\ntracking:\n  mode: indirect\nfeatures:\n  maxCorners: 300\n";
  runTutorial("--input /nonexistent --no-display --config " + config +
              " --set tracking.mode=hybrid --set features.desiredImmatureDensity=490 --save-config " + saved);
  const std::string yaml = hslam_test::readTextFile(saved);
  EXPECT_NE(yaml.find("  mode: hybrid\n"), std::string::npos) << yaml;
  EXPECT_NE(yaml.find("  desiredImmatureDensity: 490\n"), std::string::npos) << yaml;
  EXPECT_NE(yaml.find("  maxCorners: 300\n"), std::string::npos) << "the rest of --config is kept\n" << yaml;
  std::remove(config.c_str());
  std::remove(saved.c_str());
  // Malformed: refused while parsing; unknown key or bad value: the loader's message, naming the key.
  expectRefused("--set tracking", "--set", "tracking");
  const hslam_test::ProgramRun r = runTutorial("--input /nonexistent --no-display --set tracking.nope=1");
  EXPECT_NE(r.exitCode, 0);
  EXPECT_NE(r.output.find("unknown key 'nope'"), std::string::npos) << r.output;
  const hslam_test::ProgramRun range = runTutorial("--input /nonexistent --no-display --set mapper.windowSize=1");
  EXPECT_NE(range.exitCode, 0);
  EXPECT_NE(range.output.find("mapper.windowSize"), std::string::npos) << range.output;
}

TEST(DatasetStressOptions, StrideFeedsEveryKthFrame)
{
  HSLAM_REQUIRE_DATASET_TUTORIAL();
  HSLAM_REQUIRE_SHARED_DATA(dir, kSequence);
  const std::string traj = scratch("stride-traj.txt"), stats = scratch("stride-stats.json");
  const hslam_test::ProgramRun r =
      runTutorial("--input " + dir + " --max-frames 20 --stride 3 --tracking-mode direct" +
                  " --deterministic --no-display --quiet --trajectory " + traj + " --stats " + stats);
  ASSERT_EQ(r.exitCode, 0) << r.output;
  const std::string json = hslam_test::readTextFile(stats);
  EXPECT_EQ(hslam_test::jsonNumber(json, "frames"), 7.) << json; // frames 0, 3, ..., 18 of the 20 read: ceil(20 / 3)
  EXPECT_EQ(hslam_test::jsonNumber(json, "frames_read"), 20.) << json;
  EXPECT_EQ(hslam_test::jsonNumber(json, "stride"), 3.) << json;
  EXPECT_EQ(hslam_test::jsonString(json, "blackout"), "") << json;
  EXPECT_EQ(hslam_test::jsonString(json, "tracking_mode"), "direct") << json;
  EXPECT_LE(hslam_test::jsonNumber(json, "tracked_frames"), 7.) << json;
  EXPECT_EQ(static_cast<double>(hslam_test::countTumPoses(traj)), hslam_test::jsonNumber(json, "tracked_frames"));
  // The hybrid-tracking fields are written whatever the mode (zero in direct mode).
  for (const char *key : {"orb_matches_median", "orb_inliers_median", "geometric_weight_median",
                          "relocalizations_attempted", "relocalizations_succeeded", "descriptor_kb_per_keyframe"}) {
    EXPECT_GE(hslam_test::jsonNumber(json, key), 0.) << key << " missing in " << json;
  }
  std::remove(traj.c_str());
  std::remove(stats.c_str());
}

// Issue 8's large-motion bar on a car: KITTI 06 0-50 fed every 3rd frame (3.6 m between frames) is tracked in full,
// in one segment, under 1 m ATE, by direct and hybrid tracking (0.082 m measured for both). Before the first frames
// after the initialisation started from its velocity, and with 80 initialisation matches required, no frame was.
TEST(DatasetStressOptions, CarEveryThirdFrameIsTrackedInFull)
{
  HSLAM_REQUIRE_DATASET_TUTORIAL();
  HSLAM_REQUIRE_SHARED_DATA(dir, "kitti06_000-050");
  for (const char *mode : {"direct", "hybrid"}) {
    const std::string traj = scratch(std::string("car-") + mode + ".txt"), stats = scratch("car-stats.json");
    const hslam_test::ProgramRun r =
        runTutorial("--input " + dir + " --stride 3 --tracking-mode " + mode +
                    " --deterministic --no-display --quiet --trajectory " + traj + " --stats " + stats);
    ASSERT_EQ(r.exitCode, 0) << r.output;
    const std::string json = hslam_test::readTextFile(stats);
    EXPECT_EQ(hslam_test::jsonNumber(json, "frames"), 17.) << json;
    EXPECT_EQ(hslam_test::jsonNumber(json, "tracked_frames"), 17.) << mode << " " << json;
    EXPECT_EQ(hslam_test::jsonNumber(json, "segments"), 1.) << mode << " " << json;
    const vpHSlamTrajectory gt = vpHSlamTrajectory::readTum(dir + "/groundtruth_tum.txt");
    const vpHSlamTrajectory est = vpHSlamTrajectory::readTum(traj);
    const double ate = vpHSlamTrajectoryEvaluator(gt, est, 0.02).computeAte().error.rmse;
    std::cout << "KITTI 06 every 3rd frame, " << mode << " tracking: ATE " << ate << " m" << std::endl;
    EXPECT_LT(ate, 1.) << mode;
    std::remove(traj.c_str());
    std::remove(stats.c_str());
  }
}

// Issue 52's large motion at the start: KITTI 06 0-50 fed every 4th frame (4.8 m between frames), defaults. Before,
// the first map came from frames 9 and 10 (30-70 brute-force ORB matches a pair), or, made from frames 0 and 1, was
// refused by DSO's residual bound although right: 4 of 13 frames were tracked. With the epipolar matching of the
// two-view initializer and the two-view check of that bound, all 13 are (0.028 m ATE measured).
TEST(DatasetStressOptions, CarEveryFourthFrameIsTrackedFromItsFirstFrame)
{
  HSLAM_REQUIRE_DATASET_TUTORIAL();
  HSLAM_REQUIRE_SHARED_DATA(dir, "kitti06_000-050");
  const std::string traj = scratch("car-4.txt"), stats = scratch("car-4-stats.json");
  const hslam_test::ProgramRun r = runTutorial("--input " + dir + " --stride 4 --deterministic --no-display --quiet " +
                                               "--trajectory " + traj + " --stats " + stats);
  ASSERT_EQ(r.exitCode, 0) << r.output;
  const std::string json = hslam_test::readTextFile(stats);
  EXPECT_EQ(hslam_test::jsonNumber(json, "frames"), 13.) << json;
  EXPECT_EQ(hslam_test::jsonNumber(json, "tracked_frames"), 13.) << json;
  EXPECT_EQ(hslam_test::jsonNumber(json, "segments"), 1.) << json;
  const vpHSlamTrajectory gt = vpHSlamTrajectory::readTum(dir + "/groundtruth_tum.txt");
  const vpHSlamTrajectory est = vpHSlamTrajectory::readTum(traj);
  const double ate = vpHSlamTrajectoryEvaluator(gt, est, 0.02).computeAte().error.rmse;
  std::cout << "KITTI 06 every 4th frame, defaults: ATE " << ate << " m" << std::endl;
  EXPECT_LT(ate, 0.1);
  std::remove(traj.c_str());
  std::remove(stats.c_str());
}

TEST(DatasetStressOptions, StrideAndBlackoutNumberTheFramesAfterStartFrame)
{
  HSLAM_REQUIRE_DATASET_TUTORIAL();
  HSLAM_REQUIRE_SHARED_DATA(dir, kSequence);
  const std::string stats = scratch("numbering-stats.json");
  // Source frames 5..24 are read as 0..19; 0, 3, 6, ..., 18 are fed; of those, 6 and 9 lie in 4:9.
  const hslam_test::ProgramRun r = runTutorial("--input " + dir + " --start-frame 5 --max-frames 20 --stride 3" +
                                               " --blackout 4:9 --deterministic --no-display --quiet --stats " + stats);
  ASSERT_EQ(r.exitCode, 0) << r.output;
  const std::string json = hslam_test::readTextFile(stats);
  EXPECT_EQ(hslam_test::jsonNumber(json, "frames"), 7.) << json;
  EXPECT_EQ(hslam_test::jsonNumber(json, "frames_read"), 20.) << json;
  EXPECT_EQ(hslam_test::jsonNumber(json, "blacked_out_frames"), 2.) << json;
  EXPECT_EQ(hslam_test::jsonString(json, "blackout"), "4:9") << json;
  std::remove(stats.c_str());
}

TEST(DatasetStressOptions, BlackoutRunCompletesWithConsistentOutputs)
{
  HSLAM_REQUIRE_DATASET_TUTORIAL();
  HSLAM_REQUIRE_SHARED_DATA(dir, kSequence);
  const std::string traj = scratch("blackout-traj.txt"), kf = scratch("blackout-kf.txt"),
                    stats = scratch("blackout-stats.json");
  const hslam_test::ProgramRun r =
      runTutorial("--input " + dir + " --max-frames 36 --blackout 18:22 --deterministic" +
                  " --no-display --quiet --trajectory " + traj + " --keyframes " + kf + " --stats " + stats);
  ASSERT_EQ(r.exitCode, 0) << r.output;
  EXPECT_NE(r.output.find("blackout: frames 18:22"), std::string::npos) << r.output;
  const std::string json = hslam_test::readTextFile(stats);
  EXPECT_NE(json.find("\"error\": null"), std::string::npos) << json;
  EXPECT_EQ(hslam_test::jsonNumber(json, "frames"), 36.) << json;
  EXPECT_EQ(hslam_test::jsonNumber(json, "blacked_out_frames"), 5.) << json;
  EXPECT_EQ(hslam_test::jsonString(json, "blackout"), "18:22") << json;
  const double tracked = hslam_test::jsonNumber(json, "tracked_frames");
  // Tracked before the lens is covered (Tsukuba initialises within its first 15 frames), and no more than the
  // frames fed.
  EXPECT_GE(tracked, 15.) << json;
  EXPECT_LE(tracked, 36.) << json;
  EXPECT_EQ(static_cast<double>(hslam_test::countTumPoses(traj)), tracked);
  EXPECT_EQ(static_cast<double>(hslam_test::countTumPoses(kf)), hslam_test::jsonNumber(json, "keyframes"));
  const double segments = hslam_test::jsonNumber(json, "segments");
  EXPECT_GE(segments, 1.) << json;
  if (segments > 1.) {
    // After a loss, the per-segment files together hold every pose of the whole trajectory.
    std::size_t inSegments = 0;
    for (int k = 0; k < static_cast<int>(segments); ++k) {
      const std::string path = traj + ".seg" + std::to_string(k) + ".txt";
      inSegments += hslam_test::countTumPoses(path);
      std::remove(path.c_str());
    }
    EXPECT_EQ(static_cast<double>(inSegments), tracked);
  }
  std::remove(traj.c_str());
  std::remove(kf.c_str());
  std::remove(stats.c_str());
}
