//! \example tutorial-hslam-servo.cpp
//! Pose-based visual servoing with H-SLAM in the loop: a simulated free-flying camera (vpSimulatorCamera) sees the
//! synthetic textured room (vpHSlamSyntheticScene::renderAtPose); vpHSlam tracks the rendered images and its pose,
//! not the simulator's, drives a vpServo PBVS task to a goal pose. Prints every iteration and the final figures,
//! and writes a PNG plot of the servo error and the SLAM error over time.
//!
//!   ./tutorial-hslam-servo --plot servo.png
//!   ./tutorial-hslam-servo --width 480 --height 360 --goal-translation 0.15,0,0.15 --goal-rotation 0,-8,0
//!   ./tutorial-hslam-servo --tag 0.3 --tag-goal-translation 0,0,1.2 --tag-goal-rotation 180,0,0
#include "servo/HSlamServoSimulation.h"
#include "servo/ServoErrorPlot.h"
#include "servo/TagPicture.h"

#include <visp3/core/vpException.h>
#include <visp3/core/vpThetaUVector.h>
#include <visp3/core/vpTime.h>
#include <visp3/io/vpImageIo.h>

#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <sstream>
#include <string>

namespace
{
void usage(const char *program)
{
  const hslam_servo::ServoSettings d;
  const vpThetaUVector tu(d.c0Mcd.getRotationMatrix());
  std::cout << "Usage: " << program
            << " [--plot FILE.png] [--goal-translation X,Y,Z] [--goal-rotation X,Y,Z]\n"
               "       [--tag SIZE [--tag-goal-translation X,Y,Z --tag-goal-rotation X,Y,Z]]\n"
               "       [--width W --height H] [--seed S] [--noise SIGMA] [--init-frames N] [--init-radius R]\n"
               "       [--gain-zero L0] [--gain-infinity LI] [--gain-slope S] [--max-step-m M] [--max-step-deg D]\n"
               "       [--max-iterations N] [--converged-m M] [--converged-deg D] [--config FILE.yaml]\n"
               "       [--print-every N] [--help]\n"
            << R"(
Pose-based visual servoing (PBVS) of a simulated free-flying camera whose pose comes from H-SLAM.

Loop, once per frame (1/30 s of simulated time): the camera's image is rendered at the simulator's
pose (the synthetic textured room of tutorial-hslam-synthetic), vpHSlam tracks it, and the SLAM pose,
mapped into the simulator's world frame, gives the PBVS features s = (cd_t_c, theta u of cdRc)
(vpFeatureTranslation, vpFeatureThetaU; desired value 0). vpServo, eye-in-hand, with the current
interaction matrix L = [cdRc 0; 0 L_thetau]: v = -lambda L^-1 e moves the camera centre along a
straight line to the goal while the rotation error decays on its own, each as exp(-lambda t).
lambda is a vpAdaptiveGain (small far from the goal, large near it), and the twist is scaled down
as a whole so that the camera moves at most --max-step-m and --max-step-deg per frame: direct image
alignment needs small motion between frames.

Scale and frame: monocular SLAM has its own world frame and an unknown scale. Both are fixed ONCE,
before servoing. The camera first moves along a known initialisation path (a semicircle of radius
--init-radius in its image plane, no rotation, --init-frames frames, starting and ending at rest);
the SLAM initialises on it (the frames before its map are tracked backwards). A Sim(3) (scale s,
rotation R, translation t) is then fitted between that path's SLAM poses eMc_i and the simulator's
gMc_i: R is the mean of the gRc_i eRc_i^T (orientations fix it better than the positions of a short
path do), then s and t are the least-squares fit of the camera centres for that R. Every later SLAM
pose maps into the simulator's frame as orientation R eRc, centre s R etc + t. The fit is never
refreshed: SLAM drift after it shows up as servo error.

Tag mode (--tag SIZE): instead, a tag36h11 (id 0, black square SIZE metres) hangs on the wall the start
camera faces, and vpHSlam::setTag() makes the SLAM's poses metric and expressed in the tag's frame (x
right, y up as printed, z out of the wall) from its sightings in keyframes: the semicircle is still
driven (a monocular map needs motion to start) but its known poses are not used, and the goal is
given in the tag's frame (--tag-goal-translation/rotation; default: the same physical goal as the
semicircle mode's, so the two modes can be compared). The run fails if the poses are not metric by
the end of the path.

Ground truth only reports: the servo error (camera to goal) and the SLAM error (SLAM pose to
simulator pose), translation in metres and rotation in degrees. Converged: the error measured by
the SLAM below --converged-m and --converged-deg for )"
            << d.convergedFrames << R"( frames in a row. Exit status 0 when
converged, 1 otherwise.

)"
            << "  --plot FILE.png           error plot, default servo-errors.png (empty: none)\n"
            << "  --goal-translation X,Y,Z  goal position in the starting camera frame, metres, default "
            << d.c0Mcd[0][3] << "," << d.c0Mcd[1][3] << "," << d.c0Mcd[2][3] << "\n"
            << "  --goal-rotation X,Y,Z     goal orientation in that frame, theta u in degrees, default "
            << vpMath::deg(tu[0]) << "," << vpMath::deg(tu[1]) << "," << vpMath::deg(tu[2]) << "\n"
            << "  --tag SIZE                tag mode: the tag's black square, metres (0.3 shows it about 50 pixels\n"
               "                            wide from the start); needs a build with libapriltag-dev\n"
            << "  --tag-goal-translation X,Y,Z  tag mode: the goal's position in the tag's frame, metres\n"
            << "  --tag-goal-rotation X,Y,Z     tag mode: its orientation in the tag's frame, theta u in degrees\n"
            << "  --width W, --height H     image size, default " << d.width << "x" << d.height
            << " (the initialisation needs about 480x360 or more)\n"
            << "  --seed S                  synthetic scene seed (moves the start pose), default " << d.sceneSeed
            << "\n"
            << "  --noise SIGMA             image noise, grey levels, default " << d.noiseSigma << "\n"
            << "  --init-frames N           frames of the initialisation path, default " << d.initFrames << "\n"
            << "  --init-radius R           radius of its semicircle, metres, default " << d.initRadiusMetres << "\n"
            << "  --gain-zero L0            adaptive gain at zero error, 1/s, default " << d.gainAtZero << "\n"
            << "  --gain-infinity LI        adaptive gain far from the goal, 1/s, default " << d.gainAtInfinity << "\n"
            << "  --gain-slope S            slope of the adaptive gain at zero, default " << d.gainSlopeAtZero << "\n"
            << "  --max-step-m M            largest translation per frame, metres, default " << d.maxStepMetres << "\n"
            << "  --max-step-deg D          largest rotation per frame, degrees, default " << d.maxStepDegrees << "\n"
            << "  --max-iterations N        servo iterations before giving up, default " << d.maxIterations << "\n"
            << "  --converged-m M           convergence threshold on the measured translation error, metres, "
               "default "
            << d.convergedMetres << "\n"
            << "  --converged-deg D         the same on the rotation error, degrees, default " << d.convergedDegrees
            << "\n"
            << "  --config FILE.yaml        SLAM settings (vpHSlamParameters); mapping always runs in the loop's\n"
               "                            thread (deterministic), the loop runs in simulated time\n"
            << "  --print-every N           print one iteration in N, default 1\n";
}

bool parseUnsigned(const std::string &text, unsigned int &value)
{
  char *end = nullptr;
  const unsigned long v = std::strtoul(text.c_str(), &end, 10);
  if (end == text.c_str() || *end != '\0' || text[0] == '-') {
    return false;
  }
  value = static_cast<unsigned int>(v);
  return true;
}

bool parseDouble(const std::string &text, double &value)
{
  char *end = nullptr;
  value = std::strtod(text.c_str(), &end);
  return end != text.c_str() && *end == '\0';
}

//! "X,Y,Z" as three numbers.
bool parseTriple(const std::string &text, double xyz[3])
{
  std::istringstream in(text);
  char comma1 = 0, comma2 = 0;
  in >> xyz[0] >> comma1 >> xyz[1] >> comma2 >> xyz[2];
  return in && comma1 == ',' && comma2 == ',' && (in >> std::ws).eof();
}

//! What the command line sets: the run's settings, the goal (metres, degrees) and the program's own options.
struct Options {
  hslam_servo::ServoSettings settings;
  std::string plot = "servo-errors.png", config;
  unsigned int printEvery = 1;
  double goalT[3] = {0., 0., 0.};
  double goalR[3] = {0., 0., 0.};
  bool tagGoalT = false, tagGoalR = false; //!< the tag-frame goal was given
  double tagGoalTranslation[3] = {0., 0., 0.};
  double tagGoalRotation[3] = {0., 0., 0.};
};

//! One "--option value" pair into \e options; false with a message on stderr when unknown or a bad value.
bool parseOption(const std::string &arg, const std::string &value, Options &options)
{
  hslam_servo::ServoSettings &settings = options.settings;
  bool ok = true;
  if (arg == "--plot") {
    options.plot = value;
  } else if (arg == "--config") {
    options.config = value;
  } else if (arg == "--goal-translation") {
    ok = parseTriple(value, options.goalT);
  } else if (arg == "--goal-rotation") {
    ok = parseTriple(value, options.goalR);
  } else if (arg == "--tag") {
    ok = parseDouble(value, settings.tagSize) && settings.tagSize > 0.;
  } else if (arg == "--tag-goal-translation") {
    ok = options.tagGoalT = parseTriple(value, options.tagGoalTranslation);
  } else if (arg == "--tag-goal-rotation") {
    ok = options.tagGoalR = parseTriple(value, options.tagGoalRotation);
  } else if (arg == "--width") {
    ok = parseUnsigned(value, settings.width);
  } else if (arg == "--height") {
    ok = parseUnsigned(value, settings.height);
  } else if (arg == "--seed") {
    ok = parseUnsigned(value, settings.sceneSeed);
  } else if (arg == "--noise") {
    ok = parseDouble(value, settings.noiseSigma);
  } else if (arg == "--init-frames") {
    ok = parseUnsigned(value, settings.initFrames);
  } else if (arg == "--init-radius") {
    ok = parseDouble(value, settings.initRadiusMetres);
  } else if (arg == "--gain-zero") {
    ok = parseDouble(value, settings.gainAtZero);
  } else if (arg == "--gain-infinity") {
    ok = parseDouble(value, settings.gainAtInfinity);
  } else if (arg == "--gain-slope") {
    ok = parseDouble(value, settings.gainSlopeAtZero);
  } else if (arg == "--max-step-m") {
    ok = parseDouble(value, settings.maxStepMetres);
  } else if (arg == "--max-step-deg") {
    ok = parseDouble(value, settings.maxStepDegrees);
  } else if (arg == "--max-iterations") {
    ok = parseUnsigned(value, settings.maxIterations);
  } else if (arg == "--converged-m") {
    ok = parseDouble(value, settings.convergedMetres);
  } else if (arg == "--converged-deg") {
    ok = parseDouble(value, settings.convergedDegrees);
  } else if (arg == "--print-every") {
    ok = parseUnsigned(value, options.printEvery) && options.printEvery > 0;
  } else {
    std::cerr << "Unknown option '" << arg << "' (see --help)\n";
    return false;
  }
  if (!ok) {
    std::cerr << "Bad value for " << arg << ": '" << value << "'\n";
  }
  return ok;
}

//! The command line into \e options (goal defaults from the settings' c0Mcd); an exit code when the program must
//! stop (--help, or an error), -1 to run.
int parseCommandLine(int argc, char **argv, Options &options)
{
  const vpHomogeneousMatrix &c0Mcd = options.settings.c0Mcd;
  const vpThetaUVector defaultTu(c0Mcd.getRotationMatrix());
  for (int i = 0; i < 3; ++i) {
    options.goalT[i] = c0Mcd[static_cast<unsigned int>(i)][3];
    options.goalR[i] = vpMath::deg(defaultTu[static_cast<unsigned int>(i)]);
  }
  for (int k = 1; k < argc; ++k) {
    const std::string arg = argv[k];
    if (arg == "--help" || arg == "-h") {
      usage(argv[0]);
      return EXIT_SUCCESS;
    }
    if (k + 1 >= argc) {
      std::cerr << "Unknown or incomplete option '" << arg << "' (see --help)\n";
      return EXIT_FAILURE;
    }
    if (!parseOption(arg, argv[++k], options)) {
      return EXIT_FAILURE;
    }
  }
  return -1;
}

/*!
  Tag mode's settings from the options: the tag's picture (libapriltag) and the goal in its frame. False with a
  message when they cannot be used.
*/
bool configureTagMode(Options &options)
{
  hslam_servo::ServoSettings &settings = options.settings;
  if (settings.tagSize <= 0.) {
    if (options.tagGoalT || options.tagGoalR) {
      std::cerr << "--tag-goal-translation and --tag-goal-rotation need --tag SIZE\n";
      return false;
    }
    return true;
  }
  if (!hslam_tag::canDrawTags()) {
    std::cerr << "--tag: this build cannot draw the tag (Debian libapriltag-dev was not found at build time)\n";
    return false;
  }
  settings.tagPicture = hslam_tag::tag36h11Image(settings.tagId, settings.tagBlackCells);
  if (options.tagGoalT != options.tagGoalR) {
    std::cerr << "--tag-goal-translation and --tag-goal-rotation go together\n";
    return false;
  }
  settings.goalInTagFrame = options.tagGoalT;
  const double *t = options.tagGoalTranslation, *r = options.tagGoalRotation;
  settings.tMcd = vpHomogeneousMatrix(t[0], t[1], t[2], vpMath::rad(r[0]), vpMath::rad(r[1]), vpMath::rad(r[2]));
  return true;
}

//! One line per printed sample: errors, SLAM error and speed while servoing, the SLAM state otherwise.
void printSample(const hslam_servo::ServoSample &s)
{
  char line[256];
  if (s.servoing && s.hasEstimate) {
    std::snprintf(line, sizeof(line),
                  "servo %4u t=%6.2f s  error %.5f m %7.3f deg | slam %.5f m %6.3f deg | v %.3f m/s "
                  "%5.2f deg/s",
                  s.frame, s.time, s.servoErrorMetres, s.servoErrorDegrees, s.slamErrorMetres, s.slamErrorDegrees,
                  s.speedMetresPerSecond, s.speedDegreesPerSecond);
  } else {
    std::snprintf(line, sizeof(line), "%s %4u t=%6.2f s  error %.5f m %7.3f deg | slam %s",
                  s.servoing ? "servo" : "init ", s.frame, s.time, s.servoErrorMetres, s.servoErrorDegrees,
                  vpHSlam::stateName(s.state).c_str());
  }
  std::cout << line << "\n";
}

//! The errors over time as a picture (drawServoErrors) at \e plot.
void writePlot(const std::string &plot, const hslam_servo::ServoResult &result)
{
  vpImage<vpRGBa> I;
  char caption[160];
  std::snprintf(caption, sizeof(caption), "PBVS with H-SLAM in the loop: %s after %u iterations",
                result.converged ? "converged" : "NOT converged", result.iterations);
  hslam_servo::drawServoErrors(I, result.samples, caption);
  vpImageIo::write(I, plot);
  std::cout << "Plot written to " << plot << "\n";
}

//! The run's outcome as key=value lines (read by the tests and scripts).
void printSummary(const hslam_servo::ServoResult &result, double seconds)
{
  const hslam_servo::ServoSample &last = result.samples.back();
  std::cout << "converged=" << (result.converged ? 1 : 0) << "\nmode=" << (result.tagMode ? "tag" : "semicircle")
            << "\n";
  if (!result.failure.empty()) {
    std::cout << "failure=" << result.failure << "\n";
  }
  std::cout << "iterations=" << result.iterations << "\nframes=" << result.frames
            << "\nsim3_scale=" << result.alignmentScale << "\nsim3_rmse_m=" << result.alignmentRmseMetres
            << "\nsim3_poses=" << result.alignmentPoses << "\nfinal_translation_error_m=" << last.servoErrorMetres
            << "\nfinal_rotation_error_deg=" << last.servoErrorDegrees
            << "\nfinal_slam_translation_error_m=" << last.slamErrorMetres
            << "\nfinal_slam_rotation_error_deg=" << last.slamErrorDegrees << "\nslam_s=" << result.slamSeconds
            << "\nrender_s=" << result.renderSeconds << "\nrun_time_s=" << seconds << std::endl;
}
} // namespace

int main(int argc, char **argv)
{
  Options options;
  const int exitCode = parseCommandLine(argc, argv, options);
  if (exitCode >= 0) {
    return exitCode;
  }
  hslam_servo::ServoSettings &settings = options.settings;
  const double *goalT = options.goalT, *goalR = options.goalR;
  try {
    if (!options.config.empty()) {
      settings.slam.load(options.config);
    }
    settings.slam.system.deterministic = true; // the closed loop runs in simulated time
    settings.c0Mcd = vpHomogeneousMatrix(goalT[0], goalT[1], goalT[2], vpMath::rad(goalR[0]), vpMath::rad(goalR[1]),
                                         vpMath::rad(goalR[2]));
    if (!configureTagMode(options)) {
      return EXIT_FAILURE;
    }
    std::cout << "Goal in the starting camera frame: t = (" << goalT[0] << ", " << goalT[1] << ", " << goalT[2]
              << ") m, theta u = (" << goalR[0] << ", " << goalR[1] << ", " << goalR[2] << ") deg\n"
              << "Images " << settings.width << "x" << settings.height
              << ", initialisation path: " << settings.initFrames << " frames, semicircle of radius "
              << settings.initRadiusMetres << " m\n";

    const double start = vpTime::measureTimeMs();
    const unsigned int printEvery = options.printEvery;
    const hslam_servo::ServoResult result = hslam_servo::runServo(settings, [&](const hslam_servo::ServoSample &s) {
      if (s.frame % printEvery == 0) {
        printSample(s);
      }
    });
    const double seconds = 1e-3 * (vpTime::measureTimeMs() - start);
    if (result.tagMode) {
      const vpThetaUVector tu(result.tMcd.getRotationMatrix());
      std::cout << "Tag mode: goal in the tag's frame t = (" << result.tMcd[0][3] << ", " << result.tMcd[1][3] << ", "
                << result.tMcd[2][3] << ") m, theta u = (" << vpMath::deg(tu[0]) << ", " << vpMath::deg(tu[1]) << ", "
                << vpMath::deg(tu[2]) << ") deg\n";
    }
    if (!options.plot.empty() && result.samples.size() >= 2) {
      writePlot(options.plot, result);
    }
    printSummary(result, seconds);
    return result.converged ? EXIT_SUCCESS : EXIT_FAILURE;
  } catch (const vpException &e) {
    std::cerr << "Error: " << e.getStringMessage() << std::endl;
    return EXIT_FAILURE;
  }
}
