// Metric poses from an AprilTag (vpHSlam::setTag, map/MetricFrame.h) on the synthetic room (TagRoom.h): the camera
// films a 20 cm tag for 2 seconds of each of its two laps. Seen only on the first lap, or on both, the output must
// end metric and in the tag's frame: the Sim(3) that best aligns the trajectory onto the truth is the identity
// within 1 % in scale, 1 cm and 0.5 degree (issue 53's acceptance). A map saved metric gives metric poses to
// localisation-only from its first frame.
#include "TagRoom.h"

#include <visp3/hslam/vpHSlamLog.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <unistd.h>

TEST(SystemTag, TagMakesTheTrajectoryMetricAndInItsFrame)
{
  if (hslam_test::vispImagesDir().empty()) {
    GTEST_SKIP() << "visp-images-data not installed (/usr/share/visp-images-data/ViSP-images)";
  }
  HSLAM_REQUIRE_TAG_IMAGES();
  if (std::getenv("HSLAM_TEST_DEBUG")) {
    vpHSlamLog::setSink(vpHSlamLog::stderrSink());
    vpHSlamLog::setLevel(vpHSlamLog::debug);
  }
  vpHSlamParameters params;
  params.system.deterministic = true;
  const std::string mapPath = ::testing::TempDir() + "/hslam_tag_room_" + std::to_string(::getpid()) + ".hmap";
  const hslam_test::TagRoomRuns r = hslam_test::runTagRoom(params, mapPath);
  for (const hslam_test::TagRoomRun *run : {&r.bothLaps, &r.firstLapOnly}) {
    const char *name = run == &r.bothLaps ? "tag on both laps" : "tag on the first lap only";
    const vpHSlam::WorldFrame &w = run->world;
    const hslam_test::TagFrameError &e = run->error;
    std::cout << name << ": tracked " << run->statistics.trackedFrames << "/" << hslam_test::kTagRoomFrames
              << ", sightings " << w.sightings << " (kept " << w.sightingsUsed << "), scale error " << 100. * e.scale
              << " %, frame offset " << 100. * e.metres << " cm, " << e.degrees << " deg; ATE without alignment "
              << e.ateUnaligned << " m (Sim(3)-aligned " << e.ateSim3 << " m); scale +-" << 100. * w.scaleUncertainty
              << " %" << std::endl;
    ASSERT_TRUE(w.metric) << name << ": " << w.sightings << " sightings, kept " << w.sightingsUsed << ", scale "
                          << w.scale << " +- " << w.scaleUncertainty;
    EXPECT_TRUE(w.tagFrame);
    EXPECT_GE(run->statistics.trackedFrames, hslam_test::kTagRoomFrames - 20);
    EXPECT_LT(e.scale, 0.01) << name;
    EXPECT_LT(e.metres, 0.01) << name;
    EXPECT_LT(e.degrees, 0.5) << name;
  }
  // Seen again, the tag adds sightings (whether that improves the frame depends on the run: over point budgets
  // the median does, one budget in five not; tutorials/hslam-tag-benchmark.sh).
  EXPECT_GT(r.bothLaps.world.sightings, r.firstLapOnly.world.sightings);
  // Seen again on the second lap, the tag corrects the map as a loop would (no loop closes in this room); seen on the
  // first lap only, it never asks.
  EXPECT_GE(r.bothLaps.statistics.tagCorrections, 1u);
  EXPECT_EQ(r.firstLapOnly.statistics.tagCorrections, 0u);
  EXPECT_EQ(r.noTag.statistics.tagCorrections, 0u);
  // Without a tag: not metric, and the outputs are the map's own (the same run as before the tag existed).
  EXPECT_FALSE(r.noTag.world.metric);
  EXPECT_EQ(r.noTag.statistics.tagSightings, 0u);

  // The saved map keeps its metric frame: localisation-only in it is metric, in the tag's frame, from the first
  // frame, without seeing the tag (frames 120-279 of the second lap: the tag is behind the camera).
  vpHSlamSyntheticScene scene;
  vpHomogeneousMatrix wMt;
  vpColVector centre;
  hslam_test::makeTagRoom(scene, wMt, centre);
  vpHSlamParameters locate = params;
  locate.system.localizationOnly = true;
  vpHSlam locator(hslam_test::syntheticCamera(scene), locate);
  locator.loadMap(mapPath);
  EXPECT_TRUE(locator.isMetric());
  EXPECT_TRUE(locator.getWorldFrame().tagFrame);
  unsigned int located = 0;
  vpHSlamTrajectory truth, estimate;
  vpImage<unsigned char> I;
  for (unsigned int i = hslam_test::kTagRoomFramesPerLap + 120; i < hslam_test::kTagRoomFramesPerLap + 280; ++i) {
    scene.render(i, I);
    if (locator.track(I, scene.getTimestamp(i)) != vpHSlam::stateTracking) {
      continue;
    }
    ++located;
    truth.add(scene.getTimestamp(i), wMt.inverse() * scene.getPose(i));
    estimate.add(scene.getTimestamp(i), locator.get_cMw().inverse());
  }
  std::remove(mapPath.c_str());
  ASSERT_GE(located, 150u);
  // Metric and in the tag's frame. Measured: scale within 0.27 %, 2.9 cm without any alignment against 1.8 cm after a
  // Sim(3) one: localisation-only's own noise in this lean map (the mapping run had 0.9 cm on these frames) is most
  // of it. Bounds: the scale to 2 %, the unaligned error to 5 cm (a wrong frame is off by the tag's distance, 2 m).
  const hslam_test::TagFrameError e = hslam_test::tagFrameError(truth, estimate);
  std::cout << "localisation-only in the saved metric map: " << located << "/160 frames located; ATE without alignment "
            << e.ateUnaligned << " m, Sim(3)-aligned " << e.ateSim3 << " m, scale error " << 100. * e.scale
            << " %, frame offset " << 100. * e.metres << " cm, " << e.degrees << " deg" << std::endl;
  const double t0 = truth.getTimestamp(0), t1 = truth.getTimestamp(truth.size() - 1);
  const double mappingAte =
      hslam_test::tagFrameError(r.truth.timeSpan(t0, t1), r.bothLaps.trajectory.timeSpan(t0, t1)).ateUnaligned;
  std::cout << "mapping run on the same frames: ATE without alignment " << mappingAte << " m" << std::endl;
  EXPECT_LT(e.scale, 0.02);
  EXPECT_LT(e.ateUnaligned, 0.05);
}
