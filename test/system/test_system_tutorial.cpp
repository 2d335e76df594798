// End to end: the dataset program (tutorial-hslam-dataset) on a synthetic sequence: output files, statistics
// JSON, option errors, an empty input, and Ctrl-C (SIGINT) in the middle of a run.
// The program is found relative to this test executable (<build>/test/ -> <build>/tutorials/).
#include "HSlamTestData.h"
#include "HSlamTestPrograms.h"
#include "SystemTestUtils.h"

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>
#include <sys/stat.h>
#include <sys/wait.h>
#include <thread>
#include <unistd.h>

namespace
{
constexpr unsigned int kWidth = 640, kHeight = 480, kFrames = 100, kSeed = 3;

std::string tutorialPath()
{
  return hslam_test::builtTutorialPath("tutorial-hslam-dataset");
}

using RunResult = hslam_test::ProgramRun;

RunResult runTutorial(const std::string &arguments)
{
  return hslam_test::runProgram(tutorialPath(), arguments);
}

std::string readFile(const std::string &path)
{
  std::ifstream in(path.c_str());
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

//! Value of "key": <number> in a flat JSON object, NaN when absent.
double jsonValue(const std::string &json, const std::string &key)
{
  const size_t pos = json.find("\"" + key + "\":");
  if (pos == std::string::npos) {
    return std::nan("");
  }
  return std::strtod(json.c_str() + pos + key.size() + 3, nullptr);
}

size_t countPoseLines(const std::string &path)
{
  std::ifstream in(path.c_str());
  std::string line;
  size_t n = 0;
  while (std::getline(in, line)) {
    n += (!line.empty() && line[0] != '#') ? 1 : 0;
  }
  return n;
}

std::string scratch(const std::string &name)
{
  const char *tmp = std::getenv("TMPDIR");
  return std::string((tmp && *tmp) ? tmp : "/tmp") + "/hslam-test-tutorial-" + std::to_string(::getpid()) + "-" + name;
}

#define HSLAM_REQUIRE_DATASET_TUTORIAL()                                                                               \
  if (tutorialPath().empty()) {                                                                                        \
    GTEST_SKIP() << "tutorial-hslam-dataset is not built";                                                             \
  }

#define HSLAM_REQUIRE_SYNTHETIC(dir)                                                                                   \
  if (hslam_test::vispImagesDir().empty()) {                                                                           \
    GTEST_SKIP() << "ViSP image data (visp-images-data) not found: no texture for the synthetic scene";                \
  }                                                                                                                    \
  const std::string dir = hslam_test::syntheticSequence(kWidth, kHeight, kFrames, kSeed);
} // namespace

TEST(SystemTutorial, WritesTrajectoryKeyframesAndStatistics)
{
  HSLAM_REQUIRE_DATASET_TUTORIAL();
  HSLAM_REQUIRE_SYNTHETIC(dir);
  const std::string traj = scratch("traj.txt"), kf = scratch("kf.txt"), stats = scratch("stats.json");
  const RunResult r = runTutorial("--input " + dir + " --max-frames 40 --deterministic --no-display --quiet" +
                                  " --trajectory " + traj + " --keyframes " + kf + " --stats " + stats);
  ASSERT_EQ(r.exitCode, 0) << r.output;
  const std::string json = readFile(stats);
  for (const char *key : {"frames", "tracked_frames", "keyframes", "tracking_ms_median", "tracking_ms_p95",
                          "mapping_ms_per_keyframe_median", "peak_rss_mb", "memory_mb_per_keyframe", "wall_s"}) {
    EXPECT_NE(json.find(std::string("\"") + key + "\":"), std::string::npos) << key << " missing in " << json;
  }
  EXPECT_EQ(jsonValue(json, "frames"), 40.);
  EXPECT_GE(jsonValue(json, "tracked_frames"), 38.);
  EXPECT_GE(jsonValue(json, "keyframes"), 2.);
  EXPECT_GT(jsonValue(json, "tracking_ms_median"), 0.);
  EXPECT_GE(jsonValue(json, "tracking_ms_p95"), jsonValue(json, "tracking_ms_median"));
  EXPECT_GT(jsonValue(json, "peak_rss_mb"), 10.);
  EXPECT_GT(jsonValue(json, "memory_mb_per_keyframe"), 0.);
  EXPECT_GT(jsonValue(json, "wall_s"), 0.);
  EXPECT_EQ(static_cast<double>(countPoseLines(traj)), jsonValue(json, "tracked_frames"));
  EXPECT_EQ(static_cast<double>(countPoseLines(kf)), jsonValue(json, "keyframes"));
  // The trajectory is a valid TUM file against the ground truth.
  const vpHSlamTrajectory estimate = vpHSlamTrajectory::readTum(traj);
  EXPECT_LT(hslam_test::simAte(vpHSlamTrajectory::readTum(dir + "/groundtruth.txt"), estimate), 0.005);
  std::remove(traj.c_str());
  std::remove(kf.c_str());
  std::remove(stats.c_str());
}

TEST(SystemTutorial, RejectsModesNotImplementedYet)
{
  HSLAM_REQUIRE_DATASET_TUTORIAL();
  const RunResult r = runTutorial("--input /nonexistent --mode slam --no-display");
  EXPECT_NE(r.exitCode, 0);
  EXPECT_NE(r.output.find("not implemented yet"), std::string::npos) << r.output;
  const RunResult bad = runTutorial("--input /nonexistent --mode fast --no-display");
  EXPECT_NE(bad.exitCode, 0);
  EXPECT_NE(bad.output.find("fast"), std::string::npos) << bad.output;
}

TEST(SystemTutorial, EmptyInputFolderIsAClearError)
{
  HSLAM_REQUIRE_DATASET_TUTORIAL();
  const std::string empty = scratch("empty");
  ASSERT_EQ(::mkdir(empty.c_str(), 0700), 0);
  const RunResult r = runTutorial("--input " + empty + " --no-display --deterministic");
  EXPECT_NE(r.exitCode, 0);
  EXPECT_NE(r.output.find("error"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find(empty), std::string::npos) << r.output;
  ::rmdir(empty.c_str());
}

TEST(SystemTutorial, SourceErrorMidwayStillWritesFiles)
{
  HSLAM_REQUIRE_DATASET_TUTORIAL();
  HSLAM_REQUIRE_SYNTHETIC(dir);
  // The first 30 frames of the synthetic sequence, then an undecodable image.
  const std::string broken = scratch("broken");
  ASSERT_EQ(::mkdir(broken.c_str(), 0700), 0);
  ASSERT_EQ(::mkdir((broken + "/rgb").c_str(), 0700), 0);
  ASSERT_EQ(::symlink((dir + "/camera.txt").c_str(), (broken + "/camera.txt").c_str()), 0);
  std::ifstream in((dir + "/rgb.txt").c_str());
  std::ofstream list((broken + "/rgb.txt").c_str());
  std::string line;
  int frames = 0;
  double lastTime = 0.;
  while (std::getline(in, line) && frames < 30) {
    if (line.empty() || line[0] == '#') {
      continue;
    }
    std::istringstream fields(line);
    std::string name;
    fields >> lastTime >> name;
    ASSERT_EQ(::symlink((dir + "/" + name).c_str(), (broken + "/" + name).c_str()), 0);
    list << line << "\n";
    ++frames;
  }
  std::ofstream(broken + "/rgb/corrupt.png") << "not a png\n";
  list << (lastTime + 0.1) << " rgb/corrupt.png\n";
  list.close();
  const std::string traj = scratch("broken-traj.txt"), stats = scratch("broken-stats.json");
  const RunResult r = runTutorial("--input " + broken + " --deterministic --no-display --quiet --trajectory " + traj +
                                  " --stats " + stats);
  EXPECT_NE(r.exitCode, 0) << r.output;
  EXPECT_NE(r.output.find("corrupt.png"), std::string::npos) << r.output;
  const std::string json = readFile(stats);
  EXPECT_EQ(jsonValue(json, "frames"), 30.);
  EXPECT_NE(json.find("\"error\": \""), std::string::npos) << json;
  EXPECT_EQ(static_cast<double>(countPoseLines(traj)), jsonValue(json, "tracked_frames"));
  EXPECT_GE(jsonValue(json, "tracked_frames"), 28.);
  std::remove(traj.c_str());
  std::remove(stats.c_str());
  vpIoTools::remove(broken);
}

TEST(SystemTutorial, CtrlCStopsAndWritesWhatWasComputed)
{
  HSLAM_REQUIRE_DATASET_TUTORIAL();
  HSLAM_REQUIRE_SYNTHETIC(dir);
  const std::string traj = scratch("int-traj.txt"), stats = scratch("int-stats.json");
  const std::string program = tutorialPath();
  const pid_t pid = ::fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    // Real-time mode at the sequence's frame rate: 100 frames last 3.3 s, interrupted after 1.5 s.
    ::execl(program.c_str(), program.c_str(), "--input", dir.c_str(), "--no-display", "--quiet", "--trajectory",
            traj.c_str(), "--stats", stats.c_str(), static_cast<char *>(nullptr));
    ::_exit(127);
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(1500));
  ::kill(pid, SIGINT);
  int status = 0;
  ASSERT_EQ(::waitpid(pid, &status, 0), pid);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 0);
  const std::string json = readFile(stats);
  EXPECT_NE(json.find("\"interrupted\": true"), std::string::npos) << json;
  const double frames = jsonValue(json, "frames");
  EXPECT_GT(frames, 5.);
  EXPECT_LT(frames, static_cast<double>(kFrames));
  EXPECT_EQ(static_cast<double>(countPoseLines(traj)), jsonValue(json, "tracked_frames"));
  std::remove(traj.c_str());
  std::remove(stats.c_str());
}
