#include "servo/HSlamServoSimulation.h"
#include "servo/Sim3FromPoses.h"

#include <visp3/core/vpException.h>
#include <visp3/core/vpImage.h>
#include <visp3/core/vpThetaUVector.h>
#include <visp3/core/vpTime.h>
#include <visp3/hslam/vpHSlamCamera.h>
#include <visp3/hslam/vpHSlamSyntheticScene.h>
#include <visp3/hslam/vpHSlamTrajectory.h>
#include <visp3/robot/vpSimulatorCamera.h>
#include <visp3/visual_features/vpFeatureThetaU.h>
#include <visp3/visual_features/vpFeatureTranslation.h>
#include <visp3/vs/vpAdaptiveGain.h>
#include <visp3/vs/vpServo.h>

#include <algorithm>
#include <cmath>

namespace hslam_servo
{
namespace
{
//! The synthetic scene is configured as its default sequence (a 300-frame hand-held loop around the room): frame 0
//! of that loop, which the seed moves, is the start pose; every later image is rendered at the simulator's pose.
constexpr unsigned int kSceneFrames = 300;
//! Largest step per frame of the initialisation path, metres: the synthetic sequences' bound (2 cm), which the
//! direct tracker is tested on. Its peak step is radius pi^2 / (2 frames), see initialisationVelocity().
constexpr double kMaxInitStepMetres = 0.02;
//! Tag mode: a point of the tag seen farther than this from where it hangs is hidden (metres).
constexpr double kTagOcclusionMetres = 0.01;
//! The Sim(3) alignment needs at least this share of the initialisation frames to have a SLAM pose.
constexpr double kMinAlignedShare = 0.5;

struct PoseError {
  double metres = 0.;
  double degrees = 0.;
};

//! Size of a relative pose aMb: distance between the two frames' origins and rotation angle.
PoseError poseError(const vpHomogeneousMatrix &aMb)
{
  PoseError e;
  e.metres = std::sqrt(aMb.getTranslationVector().sumSquare());
  e.degrees = vpMath::deg(vpThetaUVector(aMb.getRotationMatrix()).getTheta());
  return e;
}

vpHSlamCamera pinholeCamera(const vpHSlamSyntheticScene &scene)
{
  const vpCameraParameters K = scene.getCameraParameters();
  vpHSlamCamera camera(vpHSlamCamera::pinhole, scene.getWidth(), scene.getHeight(), K.get_px(), K.get_py(), K.get_u0(),
                       K.get_v0());
  camera.setRectification(vpHSlamCamera::rectifyNone);
  return camera;
}

/*!
  Scale the whole twist (v, w) down, if needed, so that |v| <= maxSpeed and |w| <= maxRate: the direction of motion,
  hence the straight-line path of the PBVS law, is kept.
*/
vpColVector boundTwist(const vpColVector &v, double maxSpeed, double maxRate)
{
  const double speed = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
  const double rate = std::sqrt(v[3] * v[3] + v[4] * v[4] + v[5] * v[5]);
  double factor = 1.;
  if (speed > maxSpeed) {
    factor = std::min(factor, maxSpeed / speed);
  }
  if (rate > maxRate) {
    factor = std::min(factor, maxRate / rate);
  }
  return factor * v;
}

/*!
  Camera-frame velocity that moves the camera from the point of parameter k to that of k + 1 of the initialisation
  path, in one frame period: a semicircle p(a) = r (sin a, 1 - cos a, 0) in the starting camera's x-y plane (the
  camera does not rotate, so that frame keeps its orientation), with a = pi (1 - cos(pi s)) / 2 for s = k / frames:
  the speed starts and ends at zero, so the servo starts from rest.
*/
vpColVector initialisationVelocity(unsigned int k, unsigned int frames, double radius, double dt)
{
  auto position = [&](unsigned int step) {
    const double s = static_cast<double>(step) / frames;
    const double a = 0.5 * M_PI * (1. - std::cos(M_PI * s));
    return vpColVector({radius * std::sin(a), radius * (1. - std::cos(a)), 0.});
  };
  const vpColVector p0 = position(k), p1 = position(k + 1);
  vpColVector v(6, 0.);
  for (unsigned int i = 0; i < 3; ++i) {
    v[i] = (p1[i] - p0[i]) / dt;
  }
  return v;
}

void checkSettings(const ServoSettings &s)
{
  if (!(s.fps > 0.) || s.initFrames < 10 || !(s.initRadiusMetres > 0.) || !(s.maxStepMetres > 0.) ||
      !(s.maxStepDegrees > 0.) || !(s.gainAtZero > 0.) || !(s.gainAtInfinity > 0.) ||
      !(s.gainAtZero >= s.gainAtInfinity) || !(s.gainSlopeAtZero > 0.) || s.convergedFrames == 0 ||
      !(s.convergedMetres > 0.) || !(s.convergedDegrees > 0.) || !(s.tagSize >= 0.) || s.tagId < 0) {
    throw vpException(vpException::badValue,
                      "servo settings: need fps > 0, at least 10 initialisation frames, positive radius, bounds, "
                      "thresholds and gains, gain at zero >= gain at infinity, and a tag size >= 0 with an id >= 0");
  }
  const double initPeakStep = s.initRadiusMetres * M_PI * M_PI / (2. * s.initFrames);
  if (initPeakStep > kMaxInitStepMetres) {
    throw vpException(vpException::badValue,
                      "servo settings: the initialisation path would move %.3f m per frame at its peak (at most %.3f): "
                      "give it more frames or a smaller radius",
                      initPeakStep, kMaxInitStepMetres);
  }
}
} // namespace

namespace
{
//! The synthetic scene of the run: its size, frame rate, seed and image noise.
void configureScene(vpHSlamSyntheticScene &scene, const ServoSettings &settings)
{
  if (!settings.imagesDataPath.empty()) {
    scene.setImagesDataPath(settings.imagesDataPath);
  }
  vpHSlamSyntheticScene::Effects effects;
  effects.noiseSigma = settings.noiseSigma;
  scene.configure(settings.width, settings.height, kSceneFrames, settings.fps, settings.sceneSeed, effects);
}

/*!
  True when the tag at \e wMt (white margin included: \e halfWidth metres from its centre) is seen whole from the start
  camera: every point of a grid over it is the surface its pixel sees (nothing in front, inside the image).
*/
bool tagSeenWhole(const vpHSlamSyntheticScene &scene, const vpHomogeneousMatrix &wMt, double halfWidth)
{
  const vpHomogeneousMatrix cMw = scene.getPose(0).inverse();
  const vpCameraParameters K = scene.getCameraParameters();
  constexpr int kGrid = 4;
  for (int i = -kGrid; i <= kGrid; ++i) {
    for (int j = -kGrid; j <= kGrid; ++j) {
      const vpColVector Pw = wMt * vpColVector({halfWidth * i / kGrid, halfWidth * j / kGrid, 0., 1.});
      const vpColVector Pc = cMw * Pw;
      if (Pc[2] <= 0.) {
        return false;
      }
      const double u = K.get_u0() + K.get_px() * Pc[0] / Pc[2], v = K.get_v0() + K.get_py() * Pc[1] / Pc[2];
      if (u < 0. || v < 0. || u > scene.getWidth() - 1. || v > scene.getHeight() - 1.) {
        return false;
      }
      const vpColVector seen = scene.worldPointAt(u, v, 0);
      double d = 0.;
      for (unsigned int k = 0; k < 3; ++k) {
        d += (seen[k] - Pw[k]) * (seen[k] - Pw[k]);
      }
      if (d > kTagOcclusionMetres * kTagOcclusionMetres) {
        return false; // something stands in front (the pillar)
      }
    }
  }
  return true;
}

/*!
  Tag mode: the tag hung on the wall the start camera faces, as near the image centre as it is seen whole (the
  pillar may stand in front of the centre): pixels tried outward from the centre on a coarse grid. Returns wMt.
*/
vpHomogeneousMatrix hangTagInView(vpHSlamSyntheticScene &scene, const ServoSettings &settings)
{
  if (settings.tagPicture.getSize() == 0 || settings.tagBlackCells == 0) {
    throw vpException(vpException::badValue, "servo settings: tag mode needs the tag's picture");
  }
  const double u0 = 0.5 * (scene.getWidth() - 1), v0 = 0.5 * (scene.getHeight() - 1);
  const double step = scene.getWidth() / 16.;
  for (int ring = 0; ring < 6; ++ring) {
    for (int dv = -ring; dv <= ring; ++dv) {
      for (int du = -ring; du <= ring; ++du) {
        if (std::max(std::abs(du), std::abs(dv)) != ring) {
          continue;
        }
        try {
          const vpColVector centre = scene.worldPointAt(u0 + du * step, v0 + dv * step, 0);
          const vpHomogeneousMatrix wMt =
              scene.addWallTag(settings.tagPicture, settings.tagBlackCells, centre, settings.tagSize);
          if (tagSeenWhole(scene, wMt,
                           0.5 * settings.tagSize * settings.tagPicture.getWidth() / settings.tagBlackCells)) {
            return wMt;
          }
          scene.clearWallPictures();
        } catch (const vpException &) {
          // not on a wall (a box, the floor) or too close to a corner: the next pixel
        }
      }
    }
  }
  throw vpException(vpException::badValue, "servo: no wall in view of the start camera to hang the tag on");
}

/*!
  Tag mode, at the end of the initialisation path: the SLAM's poses are metric and in the tag's frame, so the map
  from them to the simulator's world is the tag's pose there (scale 1). False, with result.failure, when they are not.
*/
bool alignSlamToTag(const vpHSlam &slam, const vpHomogeneousMatrix &wMt, const ServoSample &sample, ServoResult &result,
                    Sim3 &sim3)
{
  const vpHSlam::WorldFrame world = slam.getWorldFrame();
  if (sample.state != vpHSlam::stateTracking || !world.metric || !world.tagFrame) {
    result.failure = "the tag did not make the SLAM's poses metric on the initialisation path (state " +
                     vpHSlam::stateName(sample.state) + ", " + std::to_string(world.sightings) +
                     " sightings of the tag in keyframes)";
    return false;
  }
  sim3.gMe = wMt;
  sim3.scale = 1.;
  result.initialised = true;
  result.alignmentScale = world.scale;
  result.alignmentRmseMetres = world.rmsMetres;
  result.alignmentPoses = world.sightingsUsed;
  return true;
}

/*!
  The goal in the simulator's world (wMcd): c0Mcd from the start pose \e wMc0; in tag mode the tag is hung first
  (\e wMt) and the goal may be given in its frame, which result.tMcd then records.
*/
vpHomogeneousMatrix placeGoal(vpHSlamSyntheticScene &scene, const ServoSettings &settings,
                              const vpHomogeneousMatrix &wMc0, vpHomogeneousMatrix &wMt, ServoResult &result)
{
  vpHomogeneousMatrix wMcd = wMc0 * settings.c0Mcd;
  result.tagMode = settings.tagSize > 0.;
  if (result.tagMode) {
    wMt = hangTagInView(scene, settings);
    if (settings.goalInTagFrame) {
      wMcd = wMt * settings.tMcd;
    }
    result.tMcd = wMt.inverse() * wMcd;
  }
  return wMcd;
}

//! The free-flying camera at \e wMc0. Its own velocity saturation (per component, with a message on stdout) is set
//! above every velocity sent: the initialisation path's peak and boundTwist() (on the norms) bound them here.
void configureRobot(vpSimulatorCamera &robot, double dt, double maxSpeed, double maxRate,
                    const vpHomogeneousMatrix &wMc0)
{
  robot.setSamplingTime(dt);
  robot.setMaxTranslationVelocity(2. * std::max(maxSpeed, kMaxInitStepMetres / dt));
  robot.setMaxRotationVelocity(2. * maxRate);
  robot.setPosition(wMc0);
}

//! Frame \e k rendered at the true pose \e wMc and tracked by SLAM (state into \e sample), both timed.
void renderAndTrack(vpHSlamSyntheticScene &scene, vpHSlam &slam, const vpHomogeneousMatrix &wMc, unsigned int k,
                    vpImage<unsigned char> &I, ServoSample &sample, ServoResult &result)
{
  double t0 = vpTime::measureTimeMs();
  scene.renderAtPose(wMc, I, k);
  result.renderSeconds += 1e-3 * (vpTime::measureTimeMs() - t0);
  t0 = vpTime::measureTimeMs();
  sample.state = slam.track(I, sample.time);
  result.slamSeconds += 1e-3 * (vpTime::measureTimeMs() - t0);
  ++result.frames;
}

/*!
  PBVS, eye-in-hand: s = (cd_t_c, theta u of cdRc), s* = 0. With the current interaction matrix
  L = [cdRc 0; 0 L_thetau], v = -lambda L^+ e decouples translation and rotation: the camera centre goes to the
  goal along a straight line and each error decays as exp(-lambda t). The task keeps pointers to the features.
*/
void configureTask(vpServo &task, vpFeatureTranslation &t, vpFeatureTranslation &td, vpFeatureThetaU &tu,
                   vpFeatureThetaU &tud, const ServoSettings &settings)
{
  task.setServo(vpServo::EYEINHAND_CAMERA);
  task.setInteractionMatrixType(vpServo::CURRENT);
  task.setLambda(vpAdaptiveGain(settings.gainAtZero, settings.gainAtInfinity, settings.gainSlopeAtZero));
  t.buildFrom(vpHomogeneousMatrix());
  tu.buildFrom(vpHomogeneousMatrix());
  task.addFeature(t, td);
  task.addFeature(tu, tud);
}

/*!
  Monocular scale and world frame, fixed once at the end of the initialisation path: the Sim(3) that best maps the
  SLAM poses of the path (and of this frame) onto the simulator's known ones (\e truth); the path's samples get their
  SLAM errors. False, with result.failure, when SLAM did not initialise on the path.
*/
bool alignSlamToSimulator(const vpHSlam &slam, const vpHSlamTrajectory &truth, const ServoSample &sample,
                          const ServoSettings &settings, ServoResult &result, Sim3 &sim3)
{
  const vpHSlamTrajectory estimate = slam.getTrajectory();
  const unsigned int minPoses = static_cast<unsigned int>(std::ceil(kMinAlignedShare * (settings.initFrames + 1)));
  if (sample.state != vpHSlam::stateTracking || estimate.size() < minPoses) {
    result.failure = "SLAM did not initialise on the initialisation path (" + std::to_string(estimate.size()) + " of " +
                     std::to_string(settings.initFrames + 1) + " frames with a pose, state " +
                     vpHSlam::stateName(sample.state) + ")";
    return false;
  }
  std::vector<vpHomogeneousMatrix> eMc, gMc;
  std::vector<size_t> frames;
  for (size_t i = 0; i < estimate.size(); ++i) {
    const double frame = std::round(estimate.getTimestamp(i) * settings.fps);
    if (frame >= 0. && frame < truth.size()) {
      frames.push_back(static_cast<size_t>(frame));
      eMc.push_back(estimate.get_wMc(i));
      gMc.push_back(truth.get_wMc(frames.back()));
    }
  }
  sim3 = alignSim3(eMc, gMc);
  result.initialised = true;
  result.alignmentScale = sim3.scale;
  result.alignmentRmseMetres = sim3.rmseMetres;
  result.alignmentPoses = static_cast<unsigned int>(eMc.size());
  // The initialisation frames' SLAM errors, now that they can be expressed in the simulator's frame.
  for (size_t i = 0; i < frames.size() && frames[i] < result.samples.size(); ++i) {
    ServoSample &past = result.samples[frames[i]];
    const PoseError e = poseError(toWorld(sim3, eMc[i]).inverse() * gMc[i]);
    past.hasEstimate = true;
    past.slamErrorMetres = e.metres;
    past.slamErrorDegrees = e.degrees;
  }
  return true;
}

//! The servo velocity from the SLAM pose (mapped into the simulator's world by \e sim3), bounded; the sample's SLAM
//! and measured errors (against the true pose \e wMc and the goal \e cdMw).
vpColVector servoVelocity(const vpHSlam &slam, const Sim3 &sim3, const vpHomogeneousMatrix &cdMw,
                          const vpHomogeneousMatrix &wMc, vpServo &task, vpFeatureTranslation &t, vpFeatureThetaU &tu,
                          double maxSpeed, double maxRate, ServoSample &sample)
{
  const vpHomogeneousMatrix wMcSlam = toWorld(sim3, slam.get_cMw().inverse());
  const vpHomogeneousMatrix cdMcSlam = cdMw * wMcSlam;
  const PoseError slamError = poseError(wMcSlam.inverse() * wMc);
  const PoseError measured = poseError(cdMcSlam);
  sample.hasEstimate = true;
  sample.slamErrorMetres = slamError.metres;
  sample.slamErrorDegrees = slamError.degrees;
  sample.measuredErrorMetres = measured.metres;
  sample.measuredErrorDegrees = measured.degrees;
  t.buildFrom(cdMcSlam);
  tu.buildFrom(cdMcSlam);
  return boundTwist(task.computeControlLaw(), maxSpeed, maxRate);
}

//! True when the measured error has stayed within the convergence bounds for convergedFrames servo frames in a row
//! (\e streak counts them).
bool convergedStreak(const ServoSample &sample, const ServoSettings &settings, unsigned int &streak)
{
  if (sample.servoing && sample.hasEstimate && sample.measuredErrorMetres < settings.convergedMetres &&
      sample.measuredErrorDegrees < settings.convergedDegrees) {
    return ++streak >= settings.convergedFrames;
  }
  streak = 0;
  return false;
}
} // namespace

ServoResult runServo(const ServoSettings &settings, const std::function<void(const ServoSample &)> &onSample)
{
  checkSettings(settings);
  ServoResult result;
  vpHSlamSyntheticScene scene;
  configureScene(scene, settings);

  const double dt = 1. / settings.fps;
  const vpHomogeneousMatrix wMc0 = scene.getPose(0);
  vpHomogeneousMatrix wMt; // tag mode: the tag's pose in the simulator's world
  const vpHomogeneousMatrix cdMw = placeGoal(scene, settings, wMc0, wMt, result).inverse();

  const double maxSpeed = settings.maxStepMetres / dt, maxRate = vpMath::rad(settings.maxStepDegrees) / dt;
  vpSimulatorCamera robot;
  configureRobot(robot, dt, maxSpeed, maxRate, wMc0);

  vpFeatureTranslation t(vpFeatureTranslation::cdMc), td(vpFeatureTranslation::cdMc);
  vpFeatureThetaU tu(vpFeatureThetaU::cdRc), tud(vpFeatureThetaU::cdRc);
  vpServo task;
  configureTask(task, t, td, tu, tud, settings);

  vpHSlam slam(pinholeCamera(scene), settings.slam);
  if (result.tagMode) {
    slam.setTag(vpHSlamTag("tag36h11", settings.tagSize, settings.tagId));
  }
  vpHSlamTrajectory truth; // simulator poses of the frames seen so far (for the alignment)
  Sim3 sim3;               // SLAM world e to simulator world g, once aligned
  unsigned int untracked = 0, streak = 0;
  vpImage<unsigned char> I;
  const auto record = [&result, &onSample](const ServoSample &sample) {
    result.samples.push_back(sample);
    onSample(sample);
  };

  const unsigned int lastFrame = settings.initFrames + settings.maxIterations;
  for (unsigned int k = 0; k <= lastFrame; ++k) {
    ServoSample sample;
    sample.frame = k;
    sample.time = k * dt;
    sample.servoing = k >= settings.initFrames;

    const vpHomogeneousMatrix wMc = robot.getPosition();
    renderAndTrack(scene, slam, wMc, k, I, sample, result);
    truth.add(sample.time, wMc);
    const PoseError servoError = poseError(cdMw * wMc);
    sample.servoErrorMetres = servoError.metres;
    sample.servoErrorDegrees = servoError.degrees;
    if (k == settings.initFrames &&
        !(result.tagMode ? alignSlamToTag(slam, wMt, sample, result, sim3)
                         : alignSlamToSimulator(slam, truth, sample, settings, result, sim3))) {
      record(sample);
      return result;
    }

    vpColVector v(6, 0.);
    if (!sample.servoing) {
      v = initialisationVelocity(k, settings.initFrames, settings.initRadiusMetres, dt);
    } else if (sample.state == vpHSlam::stateTracking && (!result.tagMode || slam.isMetric())) {
      // (tag mode: a pose of a new map segment, after a loss, is not in metres until the tag is seen again)
      untracked = 0;
      v = servoVelocity(slam, sim3, cdMw, wMc, task, t, tu, maxSpeed, maxRate, sample);
      ++result.iterations;
    } else if (++untracked > settings.maxUntrackedFrames) {
      // Without a pose the camera is held still (v = 0) for a few frames, then the run gives up.
      result.failure = "SLAM lost the camera while servoing (" + std::to_string(untracked) +
                       " frames in a row without a pose, state " + vpHSlam::stateName(sample.state) + ")";
      record(sample);
      return result;
    }
    sample.speedMetresPerSecond = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    sample.speedDegreesPerSecond = vpMath::deg(std::sqrt(v[3] * v[3] + v[4] * v[4] + v[5] * v[5]));
    robot.setVelocity(vpRobot::CAMERA_FRAME, v);
    record(sample);

    if (convergedStreak(sample, settings, streak)) {
      result.converged = true;
      result.iterations -= settings.convergedFrames - 1; // to the first frame of the streak
      return result;
    }
  }
  result.failure = "not converged after " + std::to_string(settings.maxIterations) + " servo iterations";
  return result;
}
} // namespace hslam_servo
