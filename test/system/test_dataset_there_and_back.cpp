// The dataset program's --there-and-back: the frames tracked on the way there are tracked again in reverse order,
// from the second-to-last to the first (M frames -> 2M - 1), stamped after the last one at the way there's median
// frame interval; --groundtruth-out writes the ground truth under those stamps, each frame of the way back with the
// pose of its source frame. Unit tests of the playback (tutorials/dataset/DatasetPlayback) on an in-memory source,
// then end-to-end runs of the program on a shared sequence (skipped when ../shared/data is absent).
#include "HSlamTestData.h"
#include "HSlamTestPrograms.h"

#include "dataset/DatasetGroundTruth.h"
#include "dataset/DatasetPlayback.h"

#include <visp3/hslam/vpHSlamException.h>
#include <visp3/hslam/vpHSlamTrajectory.h>
#include <visp3/hslam/vpHSlamTrajectoryEvaluator.h>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <map>
#include <set>
#include <string>
#include <unistd.h>
#include <vector>

using hslam_dataset::Arguments;
using hslam_dataset::FedStamp;
using hslam_dataset::FramePlayback;
using hslam_dataset::PlayedFrame;

namespace
{
//! A source of 4x4 images in memory: frame i is filled with i + 1 (never black) and stamped stamps[i]; the frames of
//! \e unreadable throw fileUnreadable (consumed, as the real sources do).
class MemorySource : public vpHSlamImageSource
{
public:
  explicit MemorySource(std::vector<double> stamps, Format format = formatImages,
                        std::set<unsigned int> unreadable = std::set<unsigned int>())
      : m_stamps(std::move(stamps)), m_format(format), m_unreadable(std::move(unreadable))
  {
  }
  bool acquire(vpImage<unsigned char> &I, Frame &frame) override
  {
    if (m_next >= m_stamps.size()) {
      return false;
    }
    const unsigned int i = m_next++;
    if (m_unreadable.count(i) != 0) {
      throw vpHSlamException(vpHSlamException::fileUnreadable, "frame " + std::to_string(i) + " is corrupt");
    }
    I.resize(4, 4, static_cast<unsigned char>(i + 1));
    frame.index = i;
    frame.timestamp = m_stamps[i];
    frame.exposure = 10. + i;
    frame.name = "frame" + std::to_string(i);
    return true;
  }
  const vpHSlamCamera &getCamera() const override { return m_camera; }
  const vpHSlamPhotometricCalibration &getPhotometricCalibration() const override { return m_photometric; }
  int getFrameCount() const override { return static_cast<int>(m_stamps.size()); }
  double getFrameRate() const override { return 0.; }
  Format getFormat() const override { return m_format; }
  std::string describe() const override { return "memory"; }

private:
  std::vector<double> m_stamps;
  Format m_format;
  std::set<unsigned int> m_unreadable;
  unsigned int m_next = 0;
  vpHSlamCamera m_camera;
  vpHSlamPhotometricCalibration m_photometric;
};

//! \e n stamps from \e t0 at \e dt.
std::vector<double> regularStamps(unsigned int n, double t0, double dt)
{
  std::vector<double> stamps;
  for (unsigned int i = 0; i < n; ++i) {
    stamps.push_back(t0 + i * dt);
  }
  return stamps;
}

//! Every frame of a playback: (played frame, its image's first pixel and size check).
struct Played {
  PlayedFrame played;
  unsigned int pixel = 0;
};

std::vector<Played> playAll(FramePlayback &playback)
{
  std::vector<Played> all;
  vpImage<unsigned char> I;
  PlayedFrame played;
  while (playback.next(I, played)) {
    EXPECT_EQ(I.getWidth(), 4u);
    EXPECT_EQ(I.getHeight(), 4u);
    all.push_back({played, I[3][3]});
  }
  return all;
}

Arguments thereAndBack(unsigned int stride = 1)
{
  Arguments args;
  args.thereAndBack = true;
  args.stride = stride;
  return args;
}

std::string scratch(const std::string &name)
{
  const char *tmp = std::getenv("TMPDIR");
  return std::string((tmp && *tmp) ? tmp : "/tmp") + "/hslam-test-tab-" + std::to_string(::getpid()) + "-" + name;
}

std::string tutorialPath()
{
  return hslam_test::builtTutorialPath("tutorial-hslam-dataset");
}

#define HSLAM_REQUIRE_DATASET_TUTORIAL()                                                                               \
  if (tutorialPath().empty()) {                                                                                        \
    GTEST_SKIP() << "tutorial-hslam-dataset is not built";                                                             \
  }
} // namespace

TEST(ThereAndBack, NFramesBecome2NMinus1InMirrorOrderReTimedAtTheMedianInterval)
{
  // Irregular stamps: intervals 0.1, 0.1, 0.15, 0.05 -> median 0.1.
  MemorySource source({5.0, 5.1, 5.2, 5.35, 5.4});
  FramePlayback playback(source, thereAndBack());
  const std::vector<Played> all = playAll(playback);
  const std::vector<unsigned int> order = {0, 1, 2, 3, 4, 3, 2, 1, 0};
  ASSERT_EQ(all.size(), order.size());
  const std::vector<double> sourceStamps = {5.0, 5.1, 5.2, 5.35, 5.4};
  for (std::size_t i = 0; i < all.size(); ++i) {
    const PlayedFrame &p = all[i].played;
    EXPECT_EQ(p.frame.index, order[i]) << i;
    EXPECT_EQ(all[i].pixel, order[i] + 1) << "the image of source frame " << order[i];
    EXPECT_EQ(p.backward, i >= 5) << i;
    EXPECT_DOUBLE_EQ(p.sourceTimestamp, sourceStamps[order[i]]) << i;
    EXPECT_DOUBLE_EQ(p.frame.exposure, 10. + order[i]) << i;
    // The way there keeps the source's stamps; frame k of the way back is at t_last + k * 0.1.
    const double expected = i < 5 ? sourceStamps[i] : 5.4 + static_cast<double>(i - 4) * 0.1;
    EXPECT_NEAR(p.frame.timestamp, expected, 1e-12) << i;
  }
  EXPECT_EQ(playback.getFramesRead(), 5u);
  EXPECT_EQ(playback.getBackwardFrames(), 4u);
  EXPECT_NEAR(playback.getBackwardInterval(), 0.1, 1e-12);
  const std::vector<FedStamp> &fed = playback.getFedStamps();
  ASSERT_EQ(fed.size(), 9u);
  for (std::size_t i = 1; i < fed.size(); ++i) {
    EXPECT_GT(fed[i].timestamp, fed[i - 1].timestamp) << "stamps given to tracking increase strictly";
  }
  EXPECT_NEAR(playback.getPlayedSeconds(), 0.4 * 5 / 4 + 4 * 0.1, 1e-12);
}

TEST(ThereAndBack, StrideSelectsTheWayThereAndTheWayBackReplaysIt)
{
  // 10 frames at 30 Hz, stride 3: there 0, 3, 6, 9; back 6, 3, 0 at 3 / 30 s.
  MemorySource source(regularStamps(10, 100., 1. / 30.));
  FramePlayback playback(source, thereAndBack(3));
  const std::vector<Played> all = playAll(playback);
  const std::vector<unsigned int> order = {0, 3, 6, 9, 6, 3, 0};
  ASSERT_EQ(all.size(), order.size());
  for (std::size_t i = 0; i < all.size(); ++i) {
    EXPECT_EQ(all[i].played.frame.index, order[i]) << i;
    EXPECT_EQ(all[i].pixel, order[i] + 1) << i;
    const double expected = i < 4 ? 100. + order[i] / 30. : 100. + 9. / 30. + static_cast<double>(i - 3) * 0.1;
    EXPECT_NEAR(all[i].played.frame.timestamp, expected, 1e-9) << i;
  }
  EXPECT_EQ(playback.getFramesRead(), 10u);
  EXPECT_EQ(playback.getBackwardFrames(), 3u);
  EXPECT_NEAR(playback.getBackwardInterval(), 0.1, 1e-12);
}

TEST(ThereAndBack, BlackoutGoesBySourceIndexBothWays)
{
  MemorySource source(regularStamps(5, 0., 0.05));
  Arguments args = thereAndBack();
  args.blackout = true;
  args.blackoutFrames.first = 2;
  args.blackoutFrames.last = 3;
  FramePlayback playback(source, args);
  const std::vector<Played> all = playAll(playback);
  ASSERT_EQ(all.size(), 9u);
  for (const Played &p : all) {
    const bool black = p.played.frame.index == 2 || p.played.frame.index == 3;
    EXPECT_EQ(p.played.blackedOut, black) << p.played.frame.index;
    EXPECT_EQ(p.pixel, black ? 0u : p.played.frame.index + 1) << p.played.frame.index;
  }
  EXPECT_EQ(playback.getBlackedOutFrames(), 4u); // 2 and 3 there, 3 and 2 back
}

TEST(ThereAndBack, WithoutTheOptionOnlyTheWayThere)
{
  MemorySource source(regularStamps(10, 0., 0.1));
  Arguments args;
  args.stride = 3;
  FramePlayback playback(source, args);
  const std::vector<Played> all = playAll(playback);
  ASSERT_EQ(all.size(), 4u);
  EXPECT_EQ(all.back().played.frame.index, 9u);
  EXPECT_EQ(playback.getBackwardFrames(), 0u);
}

TEST(ThereAndBack, ADroppedFrameIsNeitherThereNorBack)
{
  MemorySource source(regularStamps(5, 0., 0.1), vpHSlamImageSource::formatImages, {2});
  Arguments args = thereAndBack();
  args.skipUnreadable = true;
  std::vector<std::string> reports;
  FramePlayback playback(source, args, [&](const std::string &message) { reports.push_back(message); });
  const std::vector<Played> all = playAll(playback);
  const std::vector<unsigned int> order = {0, 1, 3, 4, 3, 1, 0};
  ASSERT_EQ(all.size(), order.size());
  for (std::size_t i = 0; i < all.size(); ++i) {
    EXPECT_EQ(all[i].played.frame.index, order[i]) << i;
  }
  // Intervals 0.1, 0.2, 0.1: the gap of the dropped frame does not set the pace of the way back.
  EXPECT_NEAR(playback.getBackwardInterval(), 0.1, 1e-12);
  EXPECT_EQ(playback.getDroppedFrames(), 1u);
  ASSERT_EQ(reports.size(), 1u);
  EXPECT_NE(reports[0].find("frame 2"), std::string::npos) << reports[0];

  // Without --skip-unreadable the error stops the way there, and there is no way back.
  MemorySource failing(regularStamps(5, 0., 0.1), vpHSlamImageSource::formatImages, {2});
  FramePlayback stopped(failing, thereAndBack());
  vpImage<unsigned char> I;
  PlayedFrame played;
  EXPECT_TRUE(stopped.next(I, played));
  EXPECT_TRUE(stopped.next(I, played));
  EXPECT_THROW(stopped.next(I, played), vpHSlamException);
  EXPECT_EQ(stopped.getBackwardFrames(), 0u);
}

TEST(ThereAndBack, OneFrameHasNoWayBack)
{
  MemorySource source({1.});
  FramePlayback playback(source, thereAndBack());
  EXPECT_EQ(playAll(playback).size(), 1u);
  EXPECT_EQ(playback.getBackwardFrames(), 0u);
  MemorySource empty(std::vector<double>{});
  FramePlayback nothing(empty, thereAndBack());
  EXPECT_TRUE(playAll(nothing).empty());
}

TEST(ThereAndBack, ALiveCameraIsRefused)
{
  MemorySource camera(regularStamps(3, 0., 0.1), vpHSlamImageSource::formatV4l2);
  try {
    FramePlayback playback(camera, thereAndBack());
    FAIL() << "a live camera was accepted";
  } catch (const vpHSlamException &e) {
    EXPECT_EQ(e.getCode(), vpHSlamException::invalidArgument);
    EXPECT_NE(e.getStringMessage().find("--there-and-back"), std::string::npos) << e.getStringMessage();
  }
  EXPECT_NO_THROW(FramePlayback(camera, Arguments()));
}

TEST(ThereAndBack, GroundTruthOfTheWayBackIsThePoseOfTheMirroredFrame)
{
  // Images at 30 Hz (stride 2), ground truth at 100 Hz shifted by 3 ms with a gap around image 5 (as TUM RGB-D: not
  // at the image times): the pose of ground-truth stamp t has x = t, so each pose names the stamp it was taken at.
  const std::vector<double> imageStamps = regularStamps(9, 1., 1. / 30.);
  vpHSlamTrajectory groundTruth;
  for (int i = 0; i < 40; ++i) {
    const double t = 0.993 + 0.01 * i;
    if (std::fabs(t - imageStamps[4]) > 0.03) {
      groundTruth.add(t, vpHomogeneousMatrix(t, 2. * t, 0., 0., 0., 0.1 * t));
    }
  }
  MemorySource source(imageStamps);
  FramePlayback playback(source, thereAndBack(2));
  playAll(playback); // there 0, 2, 4, 6, 8; back 6, 4, 2, 0
  const std::vector<FedStamp> &fed = playback.getFedStamps();
  ASSERT_EQ(fed.size(), 9u);
  const vpHSlamTrajectory out = hslam_dataset::groundTruthOfFedFrames(groundTruth, fed);
  ASSERT_EQ(out.size(), 7u) << "source frame 4 has no ground truth within 0.02 s, there nor back";
  std::map<unsigned int, vpHomogeneousMatrix> there; // source index -> its ground truth on the way there
  std::size_t k = 0;
  for (const FedStamp &f : fed) {
    if (f.index == 4) {
      continue;
    }
    ASSERT_LT(k, out.size());
    EXPECT_DOUBLE_EQ(out.getTimestamp(k), f.timestamp) << "under the stamp the frame was tracked with";
    const vpHomogeneousMatrix &pose = out.get_wMc(k);
    if (!f.backward) {
      // The pose of the ground-truth stamp nearest the image stamp (3 or 4 ms away).
      EXPECT_LE(std::fabs(pose[0][3] - f.sourceTimestamp), 0.005) << f.index;
      there[f.index] = pose;
    } else {
      ASSERT_EQ(there.count(f.index), 1u);
      EXPECT_EQ(pose, there[f.index]) << "frame " << f.index << " back has its pose of the way there";
    }
    ++k;
  }
  // Evaluating an estimate equal to the ground truth on these stamps: every pose pairs with its own, ATE 0.
  const vpHSlamTrajectoryEvaluator evaluator(out, out, 0.02);
  EXPECT_EQ(evaluator.getMatchedCount(), out.size());
  EXPECT_NEAR(evaluator.computeAte(vpHSlamTrajectoryEvaluator::alignSE3).error.rmse, 0., 1e-9);
}

TEST(ThereAndBack, ProgramRefusesBadCombinations)
{
  HSLAM_REQUIRE_DATASET_TUTORIAL();
  struct Case {
    const char *options;
    const char *expected;
  };
  for (const Case &c : {Case{"--input /dev/video0 --there-and-back", "error: --there-and-back"},
                        Case{"--input /nonexistent --format v4l2 --there-and-back", "error: --there-and-back"},
                        Case{"--input /nonexistent --groundtruth gt.txt", "error: --groundtruth 'gt.txt'"},
                        Case{"--input /nonexistent --there-and-back --groundtruth-out gt.txt",
                             "error: --groundtruth-out: no ground truth found"}}) {
    const hslam_test::ProgramRun r = hslam_test::runProgram(tutorialPath(), std::string(c.options) + " --no-display");
    EXPECT_NE(r.exitCode, 0) << c.options << "\n" << r.output;
    EXPECT_NE(r.output.find(c.expected), std::string::npos) << c.options << "\n" << r.output;
    EXPECT_EQ(r.output.find("source:"), std::string::npos) << "refused before the source is opened\n" << r.output;
  }
}

namespace
{
//! Runs the program there and back on the first 20 frames of a shared sequence and checks its outputs.
void checkProgramRun(const std::string &dir, unsigned int stride, unsigned int there)
{
  const std::string traj = scratch("traj.txt"), stats = scratch("stats.json"), gt = scratch("gt.txt");
  const hslam_test::ProgramRun r = hslam_test::runProgram(
      tutorialPath(), "--input " + dir + " --max-frames 20 --stride " + std::to_string(stride) +
                          " --there-and-back --deterministic --no-display --quiet --trajectory " + traj + " --stats " +
                          stats + " --groundtruth-out " + gt);
  ASSERT_EQ(r.exitCode, 0) << r.output;
  const std::string json = hslam_test::readTextFile(stats);
  EXPECT_NE(json.find("\"there_and_back\": true"), std::string::npos) << json;
  EXPECT_EQ(hslam_test::jsonNumber(json, "frames"), 2. * there - 1.) << json;
  EXPECT_EQ(hslam_test::jsonNumber(json, "backward_frames"), there - 1.) << json;
  EXPECT_EQ(hslam_test::jsonNumber(json, "frames_read"), 20.) << json;
  // The ground truth of every frame tracked (the sequence has one at every image), under its stamp: the way back
  // continues at stride / 30 s and each frame back has the pose of its mirrored frame there.
  const vpHSlamTrajectory truth = vpHSlamTrajectory::readTum(gt);
  ASSERT_EQ(truth.size(), 2u * there - 1u);
  // (The sequence's stamps have 6 decimals: the median interval is stride / 30 within 1e-6.)
  const double dt = truth.getTimestamp(there) - truth.getTimestamp(there - 1);
  EXPECT_NEAR(dt, stride / 30., 1e-6);
  for (unsigned int k = 1; k < there; ++k) {
    EXPECT_NEAR(truth.getTimestamp(there - 1 + k), truth.getTimestamp(there - 1) + k * dt, 1e-8) << k;
    EXPECT_EQ(truth.get_wMc(there - 1 + k), truth.get_wMc(there - 1 - k)) << k;
  }
  // Every pose of the estimate has its ground truth at exactly its stamp.
  const vpHSlamTrajectory estimate = vpHSlamTrajectory::readTum(traj);
  EXPECT_EQ(static_cast<double>(estimate.size()), hslam_test::jsonNumber(json, "tracked_frames"));
  EXPECT_EQ(vpHSlamTrajectoryEvaluator(truth, estimate, 0.).getMatchedCount(), estimate.size());
  for (const std::string &path : {traj, stats, gt}) {
    std::remove(path.c_str());
  }
}
} // namespace

TEST(ThereAndBack, ProgramTracksTheWayBackWithAMatchingGroundTruth)
{
  HSLAM_REQUIRE_DATASET_TUTORIAL();
  HSLAM_REQUIRE_SHARED_DATA(dir, "tsukuba_cg_000-149");
  checkProgramRun(dir, 1, 20);
}

TEST(ThereAndBack, ProgramCombinesWithStride)
{
  HSLAM_REQUIRE_DATASET_TUTORIAL();
  HSLAM_REQUIRE_SHARED_DATA(dir, "tsukuba_cg_000-149");
  checkProgramRun(dir, 3, 7); // there 0, 3, ..., 18 of the 20 read; back 15, ..., 0
}

TEST(ThereAndBack, StatisticsSayWhenTheOptionIsOff)
{
  HSLAM_REQUIRE_DATASET_TUTORIAL();
  HSLAM_REQUIRE_SHARED_DATA(dir, "tsukuba_cg_000-149");
  const std::string stats = scratch("off.json");
  const hslam_test::ProgramRun r = hslam_test::runProgram(
      tutorialPath(), "--input " + dir + " --max-frames 5 --deterministic --no-display --quiet --stats " + stats);
  ASSERT_EQ(r.exitCode, 0) << r.output;
  const std::string json = hslam_test::readTextFile(stats);
  EXPECT_NE(json.find("\"there_and_back\": false"), std::string::npos) << json;
  EXPECT_EQ(hslam_test::jsonNumber(json, "backward_frames"), 0.) << json;
  std::remove(stats.c_str());
}

TEST(ThereAndBack, ProgramCombinesWithStartFrameAndBlackout)
{
  HSLAM_REQUIRE_DATASET_TUTORIAL();
  HSLAM_REQUIRE_SHARED_DATA(dir, "tsukuba_cg_000-149");
  const std::string stats = scratch("combined.json"), gt = scratch("combined-gt.txt");
  // Source frames 5..24 are read as 0..19; there 0, 3, ..., 18 (6 and 9 black), back 15, ..., 0 (9 and 6 black).
  const hslam_test::ProgramRun r = hslam_test::runProgram(
      tutorialPath(), "--input " + dir + " --start-frame 5 --max-frames 20 --stride 3 --blackout 4:9 --there-and-back" +
                          " --deterministic --no-display --quiet --stats " + stats + " --groundtruth-out " + gt);
  ASSERT_EQ(r.exitCode, 0) << r.output;
  const std::string json = hslam_test::readTextFile(stats);
  EXPECT_EQ(hslam_test::jsonNumber(json, "frames"), 13.) << json;
  EXPECT_EQ(hslam_test::jsonNumber(json, "frames_read"), 20.) << json;
  EXPECT_EQ(hslam_test::jsonNumber(json, "blacked_out_frames"), 4.) << json;
  EXPECT_EQ(hslam_test::jsonNumber(json, "backward_frames"), 6.) << json;
  // The ground truth starts at source frame 5 (stamps index / 30) and comes back to it.
  const vpHSlamTrajectory truth = vpHSlamTrajectory::readTum(gt);
  ASSERT_EQ(truth.size(), 13u);
  EXPECT_NEAR(truth.getTimestamp(0), 5. / 30., 1e-5);
  EXPECT_NEAR(truth.getTimestamp(6), 23. / 30., 1e-5);
  EXPECT_NEAR(truth.getTimestamp(12), 23. / 30. + 6 * 0.1, 1e-4);
  EXPECT_EQ(truth.get_wMc(12), truth.get_wMc(0));
  std::remove(stats.c_str());
  std::remove(gt.c_str());
}
