// The synthetic room with an AprilTag (test_system_tag and the program hslam_tag_room, run by
// tutorials/hslam-tag-benchmark.sh): the outward-looking camera's two laps (640x480, 400 frames a lap) with a 20 cm
// tag36h11 on the right wall, filmed from about 2 m in frames 60-115 of each lap. Three systems are fed at once:
// one sees the tag on both laps, one sees the wall without it on the second lap (the tag taken down), and one is
// given no tag (the monocular reference, its ATE after a Sim(3) alignment).
#ifndef HSLAM_TEST_TAG_ROOM_H
#define HSLAM_TEST_TAG_ROOM_H

#include "HSlamTestTags.h"
#include "SystemTestUtils.h"

#include <visp3/core/vpThetaUVector.h>

#include <cmath>

namespace hslam_test
{
constexpr unsigned int kTagRoomLaps = 2, kTagRoomFramesPerLap = 400;
constexpr unsigned int kTagRoomFrames = kTagRoomLaps * kTagRoomFramesPerLap + 1;
constexpr int kTagRoomTagId = 5;
constexpr double kTagRoomTagSize = 0.2; //!< side of the black square, metres

//! How far a metric run's output frame is from the tag's.
struct TagFrameError {
  double scale = 1.;        //!< |s - 1| of the Sim(3) aligning the estimate onto the truth
  double metres = 1.;       //!< that alignment's displacement of the estimate's centroid, metres
  double degrees = 180.;    //!< its rotation, degrees
  double ateUnaligned = 1.; //!< ATE RMSE with no alignment at all, metres
  double ateSim3 = 1.;      //!< ATE RMSE after the Sim(3) alignment, metres
};

//! One system's run in the tag room.
struct TagRoomRun {
  vpHSlam::Statistics statistics;
  vpHSlam::WorldFrame world;
  vpHSlamTrajectory trajectory;
  TagFrameError error;
};

struct TagRoomRuns {
  TagRoomRun bothLaps, firstLapOnly, noTag;
  vpHSlamTrajectory truth; //!< camera-to-tag poses of every frame
};

//! The frame error of \e estimate against \e truth (both camera-to-world, same stamps).
inline TagFrameError tagFrameError(const vpHSlamTrajectory &truth, const vpHSlamTrajectory &estimate)
{
  const vpHSlamTrajectoryEvaluator evaluator(truth, estimate, 0.001);
  const vpHSlamTrajectoryEvaluator::AteResult sim3 = evaluator.computeAte(vpHSlamTrajectoryEvaluator::alignSim3);
  vpColVector c(3, 0.);
  for (const auto &m : evaluator.getMatches()) {
    for (unsigned int k = 0; k < 3; ++k) {
      c[k] += estimate.get_wMc(m.first)[k][3] / evaluator.getMatchedCount();
    }
  }
  const vpColVector moved =
      sim3.scale * vpColVector(sim3.gMe.getRotationMatrix() * c) + vpColVector(sim3.gMe.getTranslationVector());
  TagFrameError e;
  e.scale = std::fabs(sim3.scale - 1.);
  e.metres = (moved - c).frobeniusNorm();
  e.degrees = vpMath::deg(vpThetaUVector(sim3.gMe.getRotationMatrix()).getTheta());
  e.ateSim3 = sim3.error.rmse;
  e.ateUnaligned = evaluator.computeAte(vpHSlamTrajectoryEvaluator::alignNone).error.rmse;
  return e;
}

//! The tag room's scene (set up, the tag hung); \e wMt its tag's pose, \e centre where it hangs.
inline void makeTagRoom(vpHSlamSyntheticScene &scene, vpHomogeneousMatrix &wMt, vpColVector &centre)
{
  scene.setLaps(kTagRoomLaps);
  scene.setLookOutward(true);
  scene.configure(640, 480, kTagRoomFrames, 30., 1);
  centre.resize(3);
  centre[0] = 2.5;
  centre[1] = -0.17;
  centre[2] = 0.8;
  wMt = hangTag36h11(scene, kTagRoomTagId, centre, kTagRoomTagSize);
}

/*!
  Feed the tag room to three systems built with \e params (see the file comment). With \e saveMap, the map of the
  system that saw the tag on both laps is saved there at the end.
*/
inline TagRoomRuns runTagRoom(const vpHSlamParameters &params, const std::string &saveMap = std::string())
{
  vpHSlamSyntheticScene scene;
  vpHomogeneousMatrix wMt;
  vpColVector centre;
  makeTagRoom(scene, wMt, centre);
  const vpHSlamCamera camera = syntheticCamera(scene);
  vpHSlam both(camera, params), firstLapOnly(camera, params), noTag(camera, params);
  const vpHSlamTag tag("tag36h11", kTagRoomTagSize, kTagRoomTagId);
  both.setTag(tag);
  firstLapOnly.setTag(tag);
  TagRoomRuns r;
  vpImage<unsigned char> I;
  for (unsigned int i = 0; i < kTagRoomFrames; ++i) {
    const double t = scene.getTimestamp(i);
    r.truth.add(t, wMt.inverse() * scene.getPose(i));
    scene.render(i, I);
    both.track(I, t);
    noTag.track(I, t);
    if (i >= kTagRoomFramesPerLap) { // the second lap without the tag: one more render
      scene.clearWallPictures();
      scene.render(i, I);
      hangTag36h11(scene, kTagRoomTagId, centre, kTagRoomTagSize);
    }
    firstLapOnly.track(I, t);
  }
  const std::pair<vpHSlam *, TagRoomRun *> runs[] = {
      {&both, &r.bothLaps}, {&firstLapOnly, &r.firstLapOnly}, {&noTag, &r.noTag}};
  for (const auto &run : runs) {
    run.first->synchronize();
    run.second->statistics = run.first->getStatistics();
    run.second->world = run.first->getWorldFrame();
    run.second->trajectory = run.first->getTrajectory();
    run.second->error = tagFrameError(r.truth, run.second->trajectory);
  }
  if (!saveMap.empty()) {
    both.saveMap(saveMap);
  }
  return r;
}
} // namespace hslam_test

#endif
