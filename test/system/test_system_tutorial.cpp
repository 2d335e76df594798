// End to end: the dataset program (tutorial-hslam-dataset) on a synthetic sequence: output files, statistics
// JSON, option errors, an empty input, unreadable images (stop, or skip with --skip-unreadable), and SIGINT,
// SIGTERM and SIGHUP in the middle of a real-time run (mapping thread busy).
// The program is found relative to this test executable (<build>/test/ -> <build>/tutorials/).
#include "HSlamTestData.h"
#include "HSlamTestPrograms.h"
#include "SystemTestUtils.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <fstream>
#include <iomanip>
#include <sstream>
#include <string>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>
#include <vector>

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

TEST(SystemTutorial, RejectsUnknownModes)
{
  HSLAM_REQUIRE_DATASET_TUTORIAL();
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

namespace
{
/*!
  A copy of the synthetic sequence's first \e frames frames (symlinks) in a new TUM RGB-D folder, with an
  undecodable image "rgb/corrupt<k>.png" listed after each frame index in \e corruptAfter (timestamps spread over the
  following frame period). Returns the folder.
*/
std::string sequenceWithCorruptImages(const std::string &dir, const std::string &name, int frames,
                                      const std::vector<int> &corruptAfter)
{
  const std::string broken = scratch(name);
  EXPECT_EQ(::mkdir(broken.c_str(), 0700), 0);
  EXPECT_EQ(::mkdir((broken + "/rgb").c_str(), 0700), 0);
  EXPECT_EQ(::symlink((dir + "/camera.txt").c_str(), (broken + "/camera.txt").c_str()), 0);
  std::ifstream in((dir + "/rgb.txt").c_str());
  std::ofstream list((broken + "/rgb.txt").c_str());
  std::string line;
  int frame = 0, corrupt = 0;
  const double period = 1. / 30.;
  auto addCorrupt = [&](double time, int after) {
    // Spread over the next frame period: timestamps stay strictly increasing.
    const int n = static_cast<int>(std::count(corruptAfter.begin(), corruptAfter.end(), after));
    for (int j = 1; j <= n; ++j) {
      const std::string file = "rgb/corrupt" + std::to_string(corrupt++) + ".png";
      std::ofstream(broken + "/" + file) << "not a png\n";
      list << std::setprecision(17) << time + period * j / (n + 1) << " " << file << "\n";
    }
  };
  while (std::getline(in, line) && frame < frames) {
    if (line.empty() || line[0] == '#') {
      continue;
    }
    std::istringstream fields(line);
    double time = 0.;
    std::string image;
    fields >> time >> image;
    EXPECT_EQ(::symlink((dir + "/" + image).c_str(), (broken + "/" + image).c_str()), 0);
    list << line << "\n";
    addCorrupt(time, frame);
    ++frame;
  }
  return broken;
}
} // namespace

TEST(SystemTutorial, SourceErrorMidwayStillWritesFiles)
{
  HSLAM_REQUIRE_DATASET_TUTORIAL();
  HSLAM_REQUIRE_SYNTHETIC(dir);
  // The first 30 frames of the synthetic sequence, then an undecodable image.
  const std::string broken = sequenceWithCorruptImages(dir, "broken", 30, {29});
  const std::string traj = scratch("broken-traj.txt"), stats = scratch("broken-stats.json");
  const RunResult r = runTutorial("--input " + broken + " --deterministic --no-display --quiet --trajectory " + traj +
                                  " --stats " + stats);
  EXPECT_NE(r.exitCode, 0) << r.output;
  EXPECT_NE(r.output.find("corrupt0.png"), std::string::npos) << r.output;
  const std::string json = readFile(stats);
  EXPECT_EQ(jsonValue(json, "frames"), 30.);
  EXPECT_EQ(jsonValue(json, "dropped_frames"), 0.);
  EXPECT_NE(json.find("\"error\": \""), std::string::npos) << json;
  EXPECT_EQ(static_cast<double>(countPoseLines(traj)), jsonValue(json, "tracked_frames"));
  EXPECT_GE(jsonValue(json, "tracked_frames"), 28.);
  std::remove(traj.c_str());
  std::remove(stats.c_str());
  vpIoTools::remove(broken);
}

TEST(SystemTutorial, SkipUnreadableDropsCorruptFramesAndCarriesOn)
{
  HSLAM_REQUIRE_DATASET_TUTORIAL();
  HSLAM_REQUIRE_SYNTHETIC(dir);
  // 40 good frames; undecodable images in the middle of initialisation, while tracking (two in a row) and at the
  // end. (Not before the first: sources read the first listed image when they open, for its size.)
  const std::string broken = sequenceWithCorruptImages(dir, "skip", 40, {3, 20, 20, 39});
  const std::string traj = scratch("skip-traj.txt"), stats = scratch("skip-stats.json");
  const RunResult r = runTutorial("--input " + broken + " --skip-unreadable --deterministic --no-display --quiet" +
                                  " --trajectory " + traj + " --stats " + stats);
  EXPECT_EQ(r.exitCode, 0) << r.output;
  for (const char *name : {"corrupt0.png", "corrupt1.png", "corrupt2.png", "corrupt3.png"}) {
    EXPECT_NE(r.output.find(name), std::string::npos) << r.output;
  }
  EXPECT_NE(r.output.find("warning: dropped an unreadable frame ("), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("dropped (unreadable): 4"), std::string::npos) << r.output;
  const std::string json = readFile(stats);
  EXPECT_EQ(jsonValue(json, "frames"), 40.);
  EXPECT_EQ(jsonValue(json, "dropped_frames"), 4.);
  EXPECT_NE(json.find("\"error\": null"), std::string::npos) << json;
  EXPECT_GE(jsonValue(json, "tracked_frames"), 38.);
  EXPECT_EQ(jsonValue(json, "segments"), 1.);
  EXPECT_EQ(static_cast<double>(countPoseLines(traj)), jsonValue(json, "tracked_frames"));
  EXPECT_LT(hslam_test::simAte(vpHSlamTrajectory::readTum(dir + "/groundtruth.txt"), vpHSlamTrajectory::readTum(traj)),
            0.005);
  std::remove(traj.c_str());
  std::remove(stats.c_str());
  vpIoTools::remove(broken);
}

TEST(SystemTutorial, SkipUnreadableStillStopsOnAWhollyBrokenInput)
{
  HSLAM_REQUIRE_DATASET_TUTORIAL();
  HSLAM_REQUIRE_SYNTHETIC(dir);
  // 10 good frames, then 120 undecodable images: the run stops at the 100th in a row, with the error.
  const std::string broken = sequenceWithCorruptImages(dir, "skip-all", 10, std::vector<int>(120, 9));
  const std::string stats = scratch("skip-all-stats.json");
  const RunResult r =
      runTutorial("--input " + broken + " --skip-unreadable --deterministic --no-display --quiet --stats " + stats);
  EXPECT_NE(r.exitCode, 0) << r.output;
  EXPECT_NE(r.output.find("corrupt99.png"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("corrupt100.png"), std::string::npos) << r.output;
  const std::string json = readFile(stats);
  EXPECT_EQ(jsonValue(json, "frames"), 10.);
  EXPECT_EQ(jsonValue(json, "dropped_frames"), 99.);
  EXPECT_NE(json.find("\"error\": \""), std::string::npos) << json;
  std::remove(stats.c_str());
  vpIoTools::remove(broken);
}

class SystemTutorialSignal : public ::testing::TestWithParam<int>
{
};

TEST_P(SystemTutorialSignal, StopsWritesWhatWasComputedAndExitsWith128PlusSignal)
{
  HSLAM_REQUIRE_DATASET_TUTORIAL();
  HSLAM_REQUIRE_SYNTHETIC(dir);
  const int signal = GetParam();
  const std::string name = "sig" + std::to_string(signal);
  const std::string traj = scratch(name + "-traj.txt"), kf = scratch(name + "-kf.txt"),
                    stats = scratch(name + "-stats.json");
  const std::string program = tutorialPath();
  // The child's stderr comes through a pipe: without a terminal, the program prints a progress line every 50
  // frames. The signal is sent on the first one, so tracking and the mapping thread are running whatever the
  // speed of the build (a sanitizer build is several times slower than the sequence's frame rate).
  int pipeFds[2];
  ASSERT_EQ(::pipe(pipeFds), 0);
  const pid_t pid = ::fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    ::dup2(pipeFds[1], STDERR_FILENO);
    ::close(pipeFds[0]);
    ::close(pipeFds[1]);
    // Real-time mode (mapping thread) at the sequence's frame rate: 100 frames last 3.3 s.
    ::execl(program.c_str(), program.c_str(), "--input", dir.c_str(), "--no-display", "--trajectory", traj.c_str(),
            "--keyframes", kf.c_str(), "--stats", stats.c_str(), static_cast<char *>(nullptr));
    ::_exit(127);
  }
  ::close(pipeFds[1]);
  FILE *childStderr = ::fdopen(pipeFds[0], "r");
  ASSERT_NE(childStderr, nullptr);
  std::string progress;
  char line[512];
  bool signalled = false;
  while (std::fgets(line, sizeof(line), childStderr) != nullptr) {
    if (!signalled && std::string(line).compare(0, 6, "frame ") == 0) {
      progress = line;
      ::kill(pid, signal);
      signalled = true;
    } // then drained to the end, so the child never blocks on a full pipe
  }
  std::fclose(childStderr);
  int status = 0;
  ASSERT_EQ(::waitpid(pid, &status, 0), pid);
  ASSERT_TRUE(signalled) << "the program ended without a progress line";
  ASSERT_TRUE(WIFEXITED(status)) << "killed by signal " << (WIFSIGNALED(status) ? WTERMSIG(status) : 0);
  EXPECT_EQ(WEXITSTATUS(status), 128 + signal) << progress;
  const std::string json = readFile(stats);
  EXPECT_NE(json.find("\"interrupted\": true"), std::string::npos) << json;
  const char *names[] = {"", "SIGHUP", "SIGINT", "", "", "", "", "", "", "", "", "", "", "", "", "SIGTERM"};
  EXPECT_NE(json.find(std::string("\"signal\": \"") + names[signal] + "\""), std::string::npos) << json;
  const double frames = jsonValue(json, "frames");
  EXPECT_GE(frames, 50.); // signalled at the progress line of frame 50
  EXPECT_LT(frames, static_cast<double>(kFrames));
  EXPECT_GT(jsonValue(json, "tracked_frames"), 0.);
  EXPECT_GE(jsonValue(json, "keyframes"), 1.);
  EXPECT_EQ(static_cast<double>(countPoseLines(traj)), jsonValue(json, "tracked_frames"));
  EXPECT_EQ(static_cast<double>(countPoseLines(kf)), jsonValue(json, "keyframes"));
  std::remove(traj.c_str());
  std::remove(kf.c_str());
  std::remove(stats.c_str());
}

INSTANTIATE_TEST_SUITE_P(TerminationSignals, SystemTutorialSignal, ::testing::Values(SIGINT, SIGTERM, SIGHUP),
                         [](const ::testing::TestParamInfo<int> &info) {
                           return info.param == SIGINT    ? std::string("SIGINT")
                                  : info.param == SIGTERM ? std::string("SIGTERM")
                                                          : std::string("SIGHUP");
                         });
