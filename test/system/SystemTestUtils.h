// Helpers of the system tests: run vpHSlam over a synthetic scene or a shared sequence and measure it.
#ifndef HSLAM_SYSTEM_TEST_UTILS_H
#define HSLAM_SYSTEM_TEST_UTILS_H

#include "HSlamTestData.h"

#include <visp3/hslam/vpHSlam.h>
#include <visp3/hslam/vpHSlamImageSource.h>
#include <visp3/hslam/vpHSlamSyntheticScene.h>
#include <visp3/hslam/vpHSlamTrajectory.h>
#include <visp3/hslam/vpHSlamTrajectoryEvaluator.h>

#include <visp3/core/vpIoTools.h>

#include <cstdio>
#include <fcntl.h>
#include <fstream>
#include <functional>
#include <memory>
#include <string>
#include <sys/file.h>
#include <unistd.h>
#include <vector>

namespace hslam_test
{
//! What a run gave.
struct SystemRun {
  std::vector<vpHSlam::State> states;
  vpHSlamTrajectory trajectory;
  vpHSlam::Statistics statistics;
  std::vector<vpHSlam::Keyframe> keyframes;
};

//! Pinhole camera of a synthetic scene (no distortion, rectification none).
inline vpHSlamCamera syntheticCamera(const vpHSlamSyntheticScene &scene)
{
  const vpCameraParameters K = scene.getCameraParameters();
  vpHSlamCamera camera(vpHSlamCamera::pinhole, scene.getWidth(), scene.getHeight(), K.get_px(), K.get_py(), K.get_u0(),
                       K.get_v0());
  camera.setRectification(vpHSlamCamera::rectifyNone);
  return camera;
}

//! Ground truth of a synthetic scene (camera-to-world) for frames [0, count).
inline vpHSlamTrajectory syntheticGroundTruth(const vpHSlamSyntheticScene &scene, unsigned int count)
{
  vpHSlamTrajectory gt;
  for (unsigned int i = 0; i < count; ++i) {
    gt.add(scene.getTimestamp(i), scene.getPose(i));
  }
  return gt;
}

/*!
  Folder of a rendered synthetic sequence (TUM RGB-D layout, see vpHSlamSyntheticScene::writeSequence), rendered
  once and shared by the test processes (rendering 640x480 frames takes ~0.1 s each): written under a temporary
  name, then renamed, so concurrent tests never read a half-written sequence.
*/
inline std::string syntheticSequence(unsigned int width, unsigned int height, unsigned int frames, unsigned int seed,
                                     unsigned int laps = 1, bool lookOutward = false,
                                     const vpHSlamSyntheticScene::Effects &effects = vpHSlamSyntheticScene::Effects())
{
  const char *tmp = std::getenv("TMPDIR");
  const std::string base = (tmp && *tmp) ? tmp : "/tmp";
  std::string dir = base + "/hslam-test-synthetic-" + std::to_string(width) + "x" + std::to_string(height) + "-" +
                    std::to_string(frames) + "-" + std::to_string(seed);
  if (laps != 1 || lookOutward) {
    dir += "-laps" + std::to_string(laps) + (lookOutward ? "-outward" : "");
  }
  if (effects.vignette || effects.response || effects.exposureChanges || effects.motionBlur ||
      effects.noiseSigma > 0.) {
    dir += std::string("-fx") + (effects.vignette ? "v" : "") + (effects.response ? "r" : "") +
           (effects.exposureChanges ? "e" : "") + (effects.motionBlur ? "b" : "") +
           std::to_string(static_cast<int>(effects.noiseSigma * 100.));
  }
  if (pathExists(dir + "/complete")) {
    return dir;
  }
  // Tests run in parallel processes (ctest -j): the first to get here renders, the others wait for it instead of
  // rendering the same sequence beside it (the two loop tests did, which cost CI minutes on 2 cores). Without a lock
  // file (read-only temporary directory) each renders, as before; the rename below stays the guard.
  struct FileLock {
    int fd;
    explicit FileLock(const std::string &path) : fd(::open(path.c_str(), O_CREAT | O_RDWR | O_CLOEXEC, 0644))
    {
      if (fd >= 0 && ::flock(fd, LOCK_EX) != 0) {
        ::close(fd);
        fd = -1;
      }
    }
    ~FileLock()
    {
      if (fd >= 0) {
        ::flock(fd, LOCK_UN);
        ::close(fd);
      }
    }
    FileLock(const FileLock &) = delete;
    FileLock &operator=(const FileLock &) = delete;
  } lock(dir + ".lock");
  if (pathExists(dir + "/complete")) {
    return dir; // rendered by the process that held the lock
  }
  const std::string staging = dir + ".staging." + std::to_string(::getpid());
  vpHSlamSyntheticScene scene;
  scene.setLaps(laps);
  scene.setLookOutward(lookOutward);
  scene.configure(width, height, frames, 30., seed, effects);
  scene.writeSequence(staging);
  std::ofstream(staging + "/complete") << "done\n";
  if (std::rename(staging.c_str(), dir.c_str()) != 0) {
    vpIoTools::remove(staging); // another process finished first
  }
  return dir;
}

//! Feed frames [0, count) of a configured scene to a new system.
inline SystemRun runSynthetic(const vpHSlamSyntheticScene &scene, unsigned int count, const vpHSlamParameters &params)
{
  vpHSlam slam(syntheticCamera(scene), params);
  SystemRun run;
  vpImage<unsigned char> I;
  for (unsigned int i = 0; i < count; ++i) {
    scene.render(i, I);
    run.states.push_back(slam.track(I, scene.getTimestamp(i)));
  }
  slam.synchronize();
  run.trajectory = slam.getTrajectory();
  run.statistics = slam.getStatistics();
  run.keyframes = slam.getKeyframes();
  return run;
}

//! Feed a shared sequence (at most maxFrames) to a new system.
inline SystemRun
runSource(const std::string &path, unsigned int maxFrames, const vpHSlamParameters &params,
          const std::function<void(const vpHSlamImageSource::Frame &, vpImage<unsigned char> &)> &alter = nullptr)
{
  vpHSlamImageSource::Options options;
  options.maxFrames = maxFrames;
  std::unique_ptr<vpHSlamImageSource> source = vpHSlamImageSource::create(path, options);
  vpHSlam slam(*source, params);
  SystemRun run;
  vpImage<unsigned char> I;
  vpHSlamImageSource::Frame frame;
  while (source->acquire(I, frame)) {
    if (alter) {
      alter(frame, I); // e.g. a covered lens: the frame replaced by a black image
    }
    run.states.push_back(slam.track(I, frame.timestamp, frame.exposure));
  }
  slam.synchronize();
  run.trajectory = slam.getTrajectory();
  run.statistics = slam.getStatistics();
  run.keyframes = slam.getKeyframes();
  return run;
}

//! Frames of the second lap fed after the half turn of runHalfTurn() (the run stops there).
constexpr unsigned int kHalfTurnFramesAfter = 60;

//! What runHalfTurn() fed and got.
struct HalfTurnRun {
  SystemRun run;
  vpHSlamTrajectory groundTruth; //!< every frame fed, the turn's included
};

/*!
  The synthetic room's two laps (320x240, 200 frames a lap, seed 3) with a half turn in the second: after frame 260
  the camera turns 180 degrees about its vertical axis and back, 3 degrees a frame, then goes on with the lap for
  \e framesAfterTurn frames. Keyframes made while turning triangulate nothing: without the points kept on a depth
  prior (mapper.rotationFlowPx) the window empties. With \e pivotBehind > 0 the camera turns about a vertical axis
  that far behind its optical centre (a hand-held turn: the camera moves on an arc of that radius, metres).
  Used by test_system_global_map and by the adaptive-tracking benchmark (hslam_half_turn).
*/
inline HalfTurnRun runHalfTurn(const vpHSlamParameters &params, double pivotBehind,
                               unsigned int framesAfterTurn = kHalfTurnFramesAfter)
{
  constexpr unsigned int kLaps = 2, kFramesPerLap = 200, kTurnAt = kFramesPerLap + 60;
  vpHSlamSyntheticScene scene;
  scene.setLaps(kLaps);
  scene.configure(320, 240, kLaps * kFramesPerLap + 1, 30., 3);
  vpHSlam slam(syntheticCamera(scene), params);
  HalfTurnRun r;
  vpImage<unsigned char> I;
  const double dt = 1. / scene.getFrameRate();
  double t = 0.;
  auto feed = [&](const vpHomogeneousMatrix &wMc) {
    r.run.states.push_back(slam.track(I, t));
    r.groundTruth.add(t, wMc);
    t += dt;
  };
  for (unsigned int i = 0; i <= kTurnAt + framesAfterTurn && i < scene.getFrameCount(); ++i) {
    scene.render(i, I);
    feed(scene.getPose(i));
    if (i != kTurnAt) {
      continue;
    }
    const vpHomogeneousMatrix wMc = scene.getPose(i);
    constexpr double kStepDeg = 3., kTurnDeg = 180.;
    const int steps = static_cast<int>(kTurnDeg / kStepDeg);
    const vpHomogeneousMatrix pivot(0., 0., -pivotBehind, 0., 0., 0.);
    for (int j = 1; j <= 2 * steps; ++j) {
      const double angle = vpMath::rad(kStepDeg * (j <= steps ? j : 2 * steps - j));
      const vpHomogeneousMatrix turned = wMc * pivot * vpHomogeneousMatrix(0., 0., 0., 0., angle, 0.) * pivot.inverse();
      scene.renderAtPose(turned, I, 1000u + static_cast<unsigned int>(j));
      feed(turned);
    }
  }
  slam.synchronize();
  r.run.trajectory = slam.getTrajectory();
  r.run.statistics = slam.getStatistics();
  return r;
}

//! Sim(3)-aligned ATE RMSE of a run against a ground truth (ground-truth units).
inline double simAte(const vpHSlamTrajectory &gt, const vpHSlamTrajectory &estimate)
{
  vpHSlamTrajectoryEvaluator evaluator(gt, estimate, 0.01);
  return evaluator.computeAte(vpHSlamTrajectoryEvaluator::alignSim3).error.rmse;
}

//! Length of a trajectory's path (sum of position steps), ground-truth units.
inline double pathLength(const vpHSlamTrajectory &traj)
{
  double length = 0.;
  for (size_t i = 1; i < traj.size(); ++i) {
    length += (traj.get_wMc(i).getTranslationVector() - traj.get_wMc(i - 1).getTranslationVector()).frobeniusNorm();
  }
  return length;
}
} // namespace hslam_test

#endif
