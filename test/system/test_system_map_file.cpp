// Map files through vpHSlam (issue 10, save/load): a map saved after a synthetic run holds every keyframe and the
// temporal chain of pose-pose edges; loaded into a new system it is the global map (points and edges shown) and
// stays inert while the new system tracks (its own segment: the trajectory is the same as without it); a map saved
// after that holds both runs. Misuse and foreign maps give clear errors; reset() forgets a loaded map.
#include "HSlamTestData.h"
#include "HSlamTestErrors.h"
#include "SystemTestUtils.h"

#include "map/MapFile.h"

#include <visp3/hslam/vpHSlam.h>
#include <visp3/hslam/vpHSlamVocabulary.h>

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iostream>
#include <iterator>
#include <map>
#include <set>

#include <unistd.h>

namespace
{
constexpr unsigned int kWidth = 320, kHeight = 240, kFrames = 200;

vpHSlamParameters reuseParameters()
{
  vpHSlamParameters params;
  params.system.deterministic = true;
  params.system.mode = vpHSlamParameters::modeVoReuse;
  params.tracking.mode = vpHSlamParameters::trackingHybrid; // as the global map test: every frame tracked
  return params;
}

void track(vpHSlam &slam, const vpHSlamSyntheticScene &scene, unsigned int frames)
{
  vpImage<unsigned char> I;
  for (unsigned int i = 0; i < frames; ++i) {
    scene.render(i, I);
    slam.track(I, scene.getTimestamp(i));
  }
}

size_t storedPoints(const hslam::MapSnapshot &map)
{
  size_t n = 0;
  for (const hslam::GlobalKeyframe &kf : map.keyframes) {
    for (const hslam::GlobalPoint &p : kf.points) {
      n += p.state == hslam::GlobalPointState::stored ? 1u : 0u;
    }
  }
  return n;
}

class SystemMapFile : public ::testing::Test
{
protected:
  void SetUp() override
  {
    // One folder per test and process: ctest runs this suite's tests side by side, and a test's TearDown must not
    // remove the maps another one is still writing or reading.
    m_dir = std::filesystem::temp_directory_path() / ("hslam-system-map-" + std::to_string(::getpid()) + "-" +
                                                      ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::create_directories(m_dir);
  }
  void TearDown() override { std::filesystem::remove_all(m_dir); }
  std::string path(const std::string &name) const { return (m_dir / name).string(); }

  std::filesystem::path m_dir;
};
} // namespace

TEST_F(SystemMapFile, SavedMapReloadsInertAndAccumulatesRuns)
{
  if (hslam_test::vispImagesDir().empty()) {
    GTEST_SKIP() << "ViSP image data (visp-images-data) not found: no texture for the synthetic scene";
  }
  vpHSlamSyntheticScene scene;
  scene.configure(kWidth, kHeight, kFrames, 30., 3);
  const vpHSlamParameters params = reuseParameters();

  vpHSlam first(hslam_test::syntheticCamera(scene), params);
  track(first, scene, kFrames);
  const vpHSlam::Statistics s = first.getStatistics();
  std::cout << "first run: " << s.trackedFrames << "/" << kFrames << " frames tracked, " << s.segments
            << " segment(s), " << s.keyframesHeld << " keyframes held" << std::endl;
  ASSERT_EQ(s.trackedFrames, kFrames);
  // A map with stored keyframes to save (3 since the first frames after the initialisation get its velocity and
  // no longer lag behind, which made extra keyframes).
  ASSERT_GE(s.marginalizedKeyframes, 3u);
  first.saveMap(path("first.hmap"));

  // Everything held is in the file: stored keyframes and the window's, linked in time by pose-pose edges.
  const hslam::MapSnapshot saved = hslam::loadMapFile(path("first.hmap"));
  EXPECT_EQ(saved.keyframes.size(), s.keyframesHeld);
  EXPECT_EQ(saved.camera.width, static_cast<int>(kWidth));
  std::set<int> ids;
  for (const hslam::GlobalKeyframe &kf : saved.keyframes) {
    ids.insert(kf.id);
  }
  std::map<std::pair<int, int>, int> links; // (older, newer) -> consecutive edges between them
  for (const hslam::PosePoseEdge &e : saved.edges) {
    if (e.consecutive) {
      ++links[std::make_pair(std::min(e.from, e.to), std::max(e.from, e.to))];
    }
  }
  for (auto it = ids.begin(); std::next(it) != ids.end(); ++it) {
    EXPECT_EQ((links[std::make_pair(*it, *std::next(it))]), 1)
        << "keyframes " << *it << " and " << *std::next(it) << " are not linked once in time";
  }

  // Loaded into a new system: the global map, shown before any frame.
  vpHSlam second(hslam_test::syntheticCamera(scene), params);
  second.loadMap(path("first.hmap"));
  EXPECT_EQ(second.getMapPoints().size(), storedPoints(saved));
  size_t posePose = 0;
  for (const vpHSlam::GraphEdge &e : second.getGraphEdges()) {
    posePose += e.covisibility ? 0u : 1u;
  }
  EXPECT_EQ(posePose, saved.edges.size());

  // Tracking the same frames: the loaded map is another segment, so the new trajectory is the one of the first run.
  track(second, scene, kFrames);
  const vpHSlamTrajectory firstTrajectory = first.getTrajectory(), secondTrajectory = second.getTrajectory();
  const std::vector<vpHomogeneousMatrix> &a = firstTrajectory.getPoses();
  const std::vector<vpHomogeneousMatrix> &b = secondTrajectory.getPoses();
  ASSERT_EQ(a.size(), b.size());
  double largest = 0.;
  for (size_t i = 0; i < a.size(); ++i) {
    for (unsigned int r = 0; r < 3; ++r) {
      for (unsigned int c = 0; c < 4; ++c) {
        largest = std::max(largest, std::fabs(a[i][r][c] - b[i][r][c]));
      }
    }
  }
  EXPECT_LT(largest, 1e-9) << "the loaded map changed how the new run was tracked";

  // Saved again: both runs, in different segments, with distinct keyframe ids.
  second.saveMap(path("both.hmap"));
  const hslam::MapSnapshot both = hslam::loadMapFile(path("both.hmap"));
  EXPECT_EQ(both.keyframes.size(), 2 * saved.keyframes.size());
  std::set<int> bothIds, segments;
  for (const hslam::GlobalKeyframe &kf : both.keyframes) {
    bothIds.insert(kf.id);
    segments.insert(kf.segment);
  }
  EXPECT_EQ(bothIds.size(), both.keyframes.size());
  EXPECT_EQ(segments.size(), 2u);
  std::cout << "saved " << saved.keyframes.size() << " keyframes, " << storedPoints(saved) << " stored points, "
            << saved.edges.size() << " pose-pose edges, " << std::filesystem::file_size(path("first.hmap"))
            << " bytes; with the second run " << both.keyframes.size() << " keyframes" << std::endl;

  // reset() forgets the loaded map with everything else.
  second.reset();
  EXPECT_TRUE(second.getMapPoints().empty());
  EXPECT_TRUE(second.getGraphEdges().empty());

  // Misuse and foreign maps.
  using hslam_test::expectHSlamError;
  expectHSlamError([&]() { first.loadMap(path("first.hmap")); }, vpHSlamException::invalidArgument,
                   {"before the first frame"});
  vpHSlamParameters strict = params;
  strict.system.mode = vpHSlamParameters::modeVoStrict;
  vpHSlam strictSlam(hslam_test::syntheticCamera(scene), strict);
  expectHSlamError([&]() { strictSlam.saveMap(path("strict.hmap")); }, vpHSlamException::invalidArgument,
                   {"vo-strict"});
  expectHSlamError([&]() { strictSlam.loadMap(path("first.hmap")); }, vpHSlamException::invalidArgument, {"vo-strict"});
  vpHSlam empty(hslam_test::syntheticCamera(scene), params);
  expectHSlamError([&]() { empty.saveMap(path("empty.hmap")); }, vpHSlamException::invalidArgument, {"no map to save"});
  EXPECT_FALSE(std::filesystem::exists(path("empty.hmap")));
  vpHSlamSyntheticScene other;
  other.configure(2 * kWidth, 2 * kHeight, kFrames, 30., 3);
  vpHSlam otherCamera(hslam_test::syntheticCamera(other), params);
  expectHSlamError([&]() { otherCamera.loadMap(path("first.hmap")); }, vpHSlamException::invalidCalibration,
                   {"another camera", "320x240", "640x480"});
  // A map indexed with another vocabulary, in a mode that loads one (slam) when the shipped one is found.
  vpHSlamParameters slamParams = params;
  slamParams.system.mode = vpHSlamParameters::modeSlam;
  vpHSlam slam(hslam_test::syntheticCamera(scene), slamParams);
  hslam::MapSnapshot foreign = saved;
  foreign.vocabularyId = 0x1234;
  hslam::saveMapFile(path("foreign.hmap"), foreign);
  if (!vpHSlamVocabulary::defaultPath().empty()) {
    expectHSlamError([&]() { slam.loadMap(path("foreign.hmap")); }, vpHSlamException::unsupported,
                     {"vocabulary 0000000000001234"});
  }
}

TEST_F(SystemMapFile, LocalizationOnlyTracksEveryFrameInTheLoadedMapWithoutChangingIt)
{
  if (hslam_test::vispImagesDir().empty()) {
    GTEST_SKIP() << "ViSP image data (visp-images-data) not found: no texture for the synthetic scene";
  }
  if (vpHSlamVocabulary::defaultPath().empty()) {
    GTEST_SKIP() << "no vocabulary found (data/hslam-orb.hvoc or HSLAM_VOCABULARY): localisation-only needs one";
  }
  vpHSlamSyntheticScene scene;
  scene.configure(kWidth, kHeight, kFrames, 30., 3);
  const vpHSlamTrajectory gt = hslam_test::syntheticGroundTruth(scene, kFrames);
  vpHSlam mapping(hslam_test::syntheticCamera(scene), reuseParameters());
  track(mapping, scene, kFrames);
  mapping.saveMap(path("map.hmap"));
  const double mappingAte = hslam_test::simAte(gt, mapping.getTrajectory());

  vpHSlamParameters params = reuseParameters();
  params.system.localizationOnly = true;
  vpHSlam localization(hslam_test::syntheticCamera(scene), params);
  vpImage<unsigned char> I;
  scene.render(0, I);
  hslam_test::expectHSlamError([&]() { localization.track(I, scene.getTimestamp(0)); },
                               vpHSlamException::invalidArgument, {"loadMap"});
  localization.loadMap(path("map.hmap"));
  localization.loadMap(path("map.hmap")); // a second load replaces the first (nothing indexed twice)
  track(localization, scene, kFrames);
  const vpHSlam::Statistics s = localization.getStatistics();
  const double localizationAte = hslam_test::simAte(gt, localization.getTrajectory());
  std::cout << "localisation only: " << s.trackedFrames << "/" << kFrames << " frames located, ATE " << localizationAte
            << " m (mapping run " << mappingAte << " m), tracking " << s.trackingMsMedian << " ms median, "
            << s.relocalizationsSucceeded << "/" << s.relocalizationsAttempted << " by place recognition" << std::endl;
  EXPECT_EQ(s.trackedFrames, kFrames);
  EXPECT_EQ(s.segments, 0u); // nothing initialised
  // Poses from ORB matches to the map jointly with the photometric alignment to the last located frame (its depths
  // from the map): measured 3.6 mm against 1.0 mm for the mapping run here (4.5 mm with ORB and PnP alone); on the
  // shared sequences within 10 % of the mapping run or better (docs/map-files.md). Bound: the one the global map
  // test sets for vo-reuse itself on this scene.
  EXPECT_LT(localizationAte, 0.01);
  // The map is not changed: saved again, it is the same file byte for byte.
  localization.saveMap(path("after.hmap"));
  std::ifstream a(path("map.hmap"), std::ios::binary), b(path("after.hmap"), std::ios::binary);
  const std::string before((std::istreambuf_iterator<char>(a)), std::istreambuf_iterator<char>());
  const std::string after((std::istreambuf_iterator<char>(b)), std::istreambuf_iterator<char>());
  EXPECT_TRUE(before == after) << "localisation-only changed the map";

  // The first frame has no motion to predict from: place recognition and PnP against its keyframe's stored points
  // (41 inliers here). Asked for more than that, the PnP pose is a near miss which the points around the keyframe,
  // matched by projection from it, confirm (about 390 inliers): every frame is still located, the first by that.
  vpHSlamParameters demanding = params;
  demanding.tracking.relocalizationMinInliers = 60;
  vpHSlam confirmed(hslam_test::syntheticCamera(scene), demanding);
  confirmed.loadMap(path("map.hmap"));
  track(confirmed, scene, kFrames);
  const vpHSlam::Statistics c = confirmed.getStatistics();
  std::cout << "60 inliers asked of a relocalisation: " << c.trackedFrames << "/" << kFrames << " frames located, "
            << c.relocalizationsSucceeded << "/" << c.relocalizationsAttempted << " by place recognition" << std::endl;
  EXPECT_EQ(c.trackedFrames, kFrames);
  EXPECT_EQ(c.relocalizationsSucceeded, 1u);
  EXPECT_LT(hslam_test::simAte(gt, confirmed.getTrajectory()), 0.01);

  // A covered lens (frames 80-99 black): lost while covered, located again in the same map right after.
  vpHSlam covered(hslam_test::syntheticCamera(scene), params);
  covered.loadMap(path("map.hmap"));
  constexpr unsigned int kCoverFirst = 80, kCoverLast = 99, kBackWithin = 5;
  int backAt = -1;
  for (unsigned int i = 0; i < kFrames; ++i) {
    scene.render(i, I);
    if (i >= kCoverFirst && i <= kCoverLast) {
      I = 0;
    }
    const vpHSlam::State state = covered.track(I, scene.getTimestamp(i));
    if (i >= kCoverFirst && i <= kCoverLast) {
      EXPECT_EQ(state, vpHSlam::stateLost) << "frame " << i << " is black";
    } else if (i > kCoverLast && backAt < 0 && state == vpHSlam::stateTracking) {
      backAt = static_cast<int>(i);
    }
  }
  std::cout << "covered lens " << kCoverFirst << "-" << kCoverLast << ": located again at frame " << backAt << ", "
            << covered.getStatistics().trackedFrames << "/" << kFrames << " located" << std::endl;
  ASSERT_GE(backAt, 0);
  EXPECT_LE(backAt, static_cast<int>(kCoverLast + kBackWithin));
  EXPECT_LT(hslam_test::simAte(gt, covered.getTrajectory()), 0.01);
}

TEST_F(SystemMapFile, RealTimeSaveThenLocalizationOnly)
{
  // The threaded path (ThreadSanitizer runs this test): saveMap while the mapping thread may still hold jobs, then
  // localisation-only with the mapping thread idle beside it.
  if (hslam_test::vispImagesDir().empty()) {
    GTEST_SKIP() << "ViSP image data (visp-images-data) not found: no texture for the synthetic scene";
  }
  if (vpHSlamVocabulary::defaultPath().empty()) {
    GTEST_SKIP() << "no vocabulary found (data/hslam-orb.hvoc or HSLAM_VOCABULARY): localisation-only needs one";
  }
  constexpr unsigned int kRealTimeFrames = kFrames;
  vpHSlamSyntheticScene scene;
  scene.configure(kWidth, kHeight, kRealTimeFrames, 30., 3);
  vpHSlamParameters params = reuseParameters();
  params.system.deterministic = false;
  vpHSlam mapping(hslam_test::syntheticCamera(scene), params);
  track(mapping, scene, kRealTimeFrames);
  mapping.saveMap(path("realtime.hmap")); // waits for mapping first
  std::cout << "real-time mapping run: " << mapping.getStatistics().trackedFrames << " frames tracked, "
            << mapping.getStatistics().keyframes << " keyframes" << std::endl;
  const hslam::MapSnapshot saved = hslam::loadMapFile(path("realtime.hmap"));
  EXPECT_EQ(saved.keyframes.size(), mapping.getStatistics().keyframesHeld);

  params.system.localizationOnly = true;
  vpHSlam localization(hslam_test::syntheticCamera(scene), params);
  localization.loadMap(path("realtime.hmap"));
  std::vector<unsigned int> lost;
  vpImage<unsigned char> I;
  for (unsigned int i = 0; i < kRealTimeFrames; ++i) {
    scene.render(i, I);
    if (localization.track(I, scene.getTimestamp(i)) != vpHSlam::stateTracking) {
      lost.push_back(i);
    }
  }
  localization.synchronize();
  const vpHSlam::Statistics s = localization.getStatistics();
  std::cout << "real time: " << saved.keyframes.size() << " keyframes saved (frames";
  for (const hslam::GlobalKeyframe &kf : saved.keyframes) {
    std::cout << " " << kf.frameId;
  }
  std::cout << "), " << s.trackedFrames << "/" << kRealTimeFrames << " frames located" << std::endl;
  EXPECT_EQ(s.trackedFrames, kRealTimeFrames) << "not located: " << ::testing::PrintToString(lost);
  EXPECT_EQ(s.keyframes, 0u);
}
