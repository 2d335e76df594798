//! \example tutorial-hslam-dataset.cpp
//! Run H-SLAM on a dataset, a video, an image folder or a V4L2 camera: every frame is read from a
//! vpHSlamImageSource, given to vpHSlam::track(), and the trajectory (TUM, camera-to-world, every frame with a pose),
//! the keyframes and run statistics (JSON) are written at the end -- also when tracking was lost midway, when the
//! source failed, or when the run was stopped by SIGINT (Ctrl-C), SIGTERM (timeout, systemd, docker stop) or SIGHUP
//! (the terminal closed); the exit status is then 128 + the signal number, as a shell reports a killed program.
//! With --skip-unreadable, an image that cannot be decoded is counted as dropped and the run carries on.
//! Stress runs: --stride K tracks every K-th frame (large motion), --blackout A:B feeds black frames (a covered
//! lens), --there-and-back tracks the frames again in reverse order (re-timed after the last; --groundtruth-out
//! writes the ground truth under the same stamps), --tracking-mode direct|indirect|hybrid|adaptive selects the tracker.
//! Options, frame playback and statistics: tutorials/dataset/.
//!
//!   ./tutorial-hslam-dataset --input ../shared/data/tsukuba_cg_000-149 --deterministic --no-display
//!       --trajectory tsukuba.txt --keyframes tsukuba-kf.txt --stats tsukuba.json   (one line)
//!   ./tutorial-hslam-evaluate --groundtruth ../shared/data/tsukuba_cg_000-149/groundtruth.txt --estimate tsukuba.txt
#include <visp3/core/vpConfig.h>
#include <visp3/core/vpImage.h>
#include <visp3/core/vpTime.h>
#include <visp3/gui/vpDisplayX.h>
#include <visp3/hslam/vpHSlam.h>
#include <visp3/hslam/vpHSlamException.h>
#include <visp3/hslam/vpHSlamImageIo.h>
#include <visp3/hslam/vpHSlamImageSource.h>
#include <visp3/hslam/vpHSlamLiveView.h>
#include <visp3/hslam/vpHSlamLog.h>
#include <visp3/hslam/vpHSlamParameters.h>
#include <visp3/hslam/vpHSlamRectifier.h>

#include "dataset/DatasetArguments.h"
#include "dataset/DatasetGroundTruth.h"
#include "dataset/DatasetMapOutput.h"
#include "dataset/DatasetPlayback.h"
#include "dataset/DatasetStatistics.h"

#include <csignal>
#include <cstdlib>
#include <functional>
#include <iomanip>
#include <iostream>
#include <memory>
#include <string>
#include <unistd.h>

//! Without a terminal, the progress line is printed once every this many frames.
constexpr unsigned int kProgressLogEvery = 50;

using namespace hslam_dataset;

namespace
{
//! Number of the termination signal received (SIGINT, SIGTERM, SIGHUP), 0 while none: the main loop polls it, stops
//! and writes its files (nothing is written from the handler).
volatile std::sig_atomic_t g_signal = 0;

extern "C" void onTerminationSignal(int number)
{
  if (g_signal != 0) {
    // A second signal while the files are being written: the user insists, end at once (async-signal-safe calls).
    std::signal(number, SIG_DFL);
    std::raise(number);
    return;
  }
  g_signal = number;
}

//! The signals that stop a run the way Ctrl-C does.
const int kTerminationSignals[] = {SIGINT, SIGTERM, SIGHUP};

void installTerminationHandlers()
{
  for (int signal : kTerminationSignals) {
    struct sigaction action {
    };
    action.sa_handler = onTerminationSignal;
    sigemptyset(&action.sa_mask);
    action.sa_flags = SA_RESTART; // reads of the source are not cut short; the loop stops after the current frame
    sigaction(signal, &action, nullptr);
  }
}

//! Write every requested output; report (do not throw) failures so that each file gets its chance.
//! \param groundTruthOut : the --groundtruth-out poses (empty without the option).
bool writeOutputs(const Arguments &args, vpHSlam &slam, const RunOutcome &outcome,
                  const vpHSlamTrajectory &groundTruthOut)
{
  bool ok = true;
  auto attempt = [&](const std::string &what, const std::function<void()> &write) {
    try {
      write();
      std::cout << "wrote " << what << std::endl;
    } catch (const vpException &e) {
      std::cerr << "error: " << what << ": " << e.getStringMessage() << std::endl;
      ok = false;
    }
  };
  const vpHSlam::Statistics stats = slam.getStatistics();
  if (!args.trajectory.empty()) {
    attempt(args.trajectory, [&]() { slam.getTrajectory().saveTum(args.trajectory); });
    if (stats.segments > 1) {
      for (unsigned int s = 0; s < stats.segments; ++s) {
        const std::string path = args.trajectory + ".seg" + std::to_string(s) + ".txt";
        attempt(path, [&]() { slam.getTrajectory(static_cast<int>(s)).saveTum(path); });
      }
    }
  }
  if (!args.keyframes.empty()) {
    attempt(args.keyframes, [&]() { slam.getKeyframeTrajectory().saveTum(args.keyframes); });
  }
  if (!args.groundTruthOut.empty()) {
    attempt(args.groundTruthOut, [&]() { groundTruthOut.saveTum(args.groundTruthOut); });
  }
  if (!args.stats.empty()) {
    attempt(args.stats, [&]() { writeStats(args.stats, stats, args, slam.getParameters(), outcome); });
  }
  if (!args.mapPly.empty() || !args.mapPng.empty()) {
    const std::vector<vpHSlam::MapPoint> points = slam.getMapPoints();
    if (!args.mapPly.empty()) {
      attempt(args.mapPly, [&]() { writeMapPly(args.mapPly, points, slam.getKeyframes()); });
    }
    if (!args.mapPng.empty()) {
      attempt(args.mapPng, [&]() { writeMapPng(args.mapPng, points, slam.getTrajectory()); });
    }
  }
  if (!args.saveMap.empty()) {
    attempt(args.saveMap, [&]() { slam.saveMap(args.saveMap); });
  }
  return ok;
}

//! What the run will do, before the first frame.
void printSetup(const Arguments &args, const vpHSlamParameters &params, const vpHSlam &slam)
{
  std::cout << "mode: " << vpHSlamParameters::modeName(params.system.mode) << ", "
            << vpHSlamParameters::trackingModeName(params.tracking.mode) << " tracking"
            << (params.system.deterministic ? ", deterministic" : ", real time") << "; rectified " << slam.getWidth()
            << "x" << slam.getHeight() << std::endl;
  if (args.stride > 1) {
    std::cout << "stride " << args.stride << ": tracking frames 0, " << args.stride << ", " << 2 * args.stride
              << ", ... of the source" << std::endl;
  }
  if (args.blackout) {
    std::cout << "blackout: frames " << args.blackoutFrames.text() << " replaced by a black image" << std::endl;
  }
  if (args.thereAndBack) {
    std::cout << "there and back: the frames tracked are then tracked again in reverse order, kept in memory"
              << std::endl;
  }
}

//! The progress line: on a terminal it rewrites itself; in a log (CI, a file) it becomes one line every
//! kProgressLogEvery frames so the log stays readable.
void printProgress(const vpHSlam &slam, vpHSlam::State state, const PlayedFrame &played, int frameCount,
                   bool onTerminal)
{
  const vpHSlam::Statistics s = slam.getStatistics();
  std::cerr << (onTerminal ? "\r" : "") << "frame " << played.frame.index + 1;
  if (frameCount > 0) {
    std::cerr << "/" << frameCount;
  }
  std::cerr << (played.backward ? " back" : "") << "  " << std::setw(12) << std::left << vpHSlam::stateName(state)
            << std::right << " tracked " << s.trackedFrames << "  kf " << s.keyframes << "  pts " << s.activePoints
            << "  trk " << std::fixed << std::setprecision(1) << s.trackingMsMedian << " ms  map "
            << s.mappingMsPerKeyframeMedian << " ms/kf   " << (onTerminal ? "" : "\n") << std::flush;
}

/*!
  The live view: image with the active points by inverse depth, status, top view; space pauses, q or Escape (or a
  click) quits. Without X11, or without an X display, it shows nothing.
*/
class LiveWindow
{
public:
  explicit LiveWindow(bool wanted) : m_enabled(wanted)
  {
#if defined(VISP_HAVE_X11)
    const char *xDisplay = std::getenv("DISPLAY");
    if (m_enabled && (xDisplay == nullptr || *xDisplay == '\0')) {
      std::cout << "no X display: running without window" << std::endl;
      m_enabled = false;
    }
#else
    m_enabled = false;
#endif
  }

  //! Show the frame just tracked. \return false when the user asked to quit.
  bool show(const vpHSlam &slam, const PlayedFrame &played)
  {
#if defined(VISP_HAVE_X11)
    if (!m_enabled) {
      return true;
    }
    const double now = vpTime::measureTimeMs();
    if (m_lastDrawMs > 0. && now > m_lastDrawMs) {
      const double instantFps = 1000. / (now - m_lastDrawMs);
      m_fps = m_fps > 0. ? 0.9 * m_fps + 0.1 * instantFps : instantFps;
    }
    m_lastDrawMs = now;
    const std::string way = played.backward ? "way back  " : "";
    m_view.draw(slam, played.frame.index, m_fps, m_canvas,
                way + (played.blackedOut ? "blackout  q: quit" : "space: pause  q: quit"));
    if (!m_open) {
      try {
        m_window.init(m_canvas, 0, 0, "H-SLAM");
        m_open = true;
      } catch (const vpException &e) {
        std::cerr << "warning: cannot open a window (" << e.getStringMessage() << "): running without display"
                  << std::endl;
        m_enabled = false;
        return true;
      }
    }
    vpDisplay::display(m_canvas);
    vpDisplay::flush(m_canvas);
    return !waitForKeys();
#else
    (void)slam;
    (void)played;
    return true;
#endif
  }

  //! With a window: save the last view shown as a PNG (a failure is a warning).
  void saveScreenshot(const std::string &path)
  {
#if defined(VISP_HAVE_X11)
    if (!m_open || path.empty()) {
      return;
    }
    try {
      vpImage<vpRGBa> shot;
      vpDisplay::getImage(m_canvas, shot);
      vpHSlamImageIo::writePng(path, shot);
      std::cout << "screenshot: " << path << std::endl;
    } catch (const vpException &e) {
      std::cerr << "warning: cannot save the screenshot '" << path << "': " << e.getStringMessage() << std::endl;
    }
#else
    (void)path;
#endif
  }

private:
#if defined(VISP_HAVE_X11)
  //! Keys and clicks: true when the user quits; space (or p) pauses until pressed again.
  bool waitForKeys()
  {
    bool quit = vpDisplay::getClick(m_canvas, false);
    std::string key;
    bool paused = false;
    while (!quit && g_signal == 0) {
      if (vpDisplay::getKeyboardEvent(m_canvas, key, false)) {
        if (key == "q" || key == "Q" || key == "\x1b" || key == "Escape") {
          quit = true;
        } else if (key == " " || key == "space" || key == "p") {
          paused = !paused;
        }
      }
      quit = quit || vpDisplay::getClick(m_canvas, false);
      if (!paused) {
        break;
      }
      vpTime::wait(20.);
    }
    return quit;
  }

  vpDisplayX m_window;
  bool m_open = false;
  vpHSlamLiveView m_view;
  vpImage<vpRGBa> m_canvas;
  double m_fps = 0., m_lastDrawMs = 0.;
#endif
  bool m_enabled;
};

//! The frame loop: every frame of \e playback tracked, until its end, a signal, the user's q or an error (returned
//! in \e outcome.error, not thrown).
void trackFrames(const Arguments &args, const vpHSlamParameters &params, vpHSlam &slam, FramePlayback &playback,
                 int frameCount, RunOutcome &outcome)
{
  LiveWindow window(args.display);
  const bool progressOnTerminal = ::isatty(STDERR_FILENO) != 0;
  vpImage<unsigned char> I;
  PlayedFrame played;
  unsigned int framesFed = 0;
  const double t0 = vpTime::measureTimeMs();
  try {
    while (g_signal == 0 && playback.next(I, played)) {
      ++framesFed;
      if (!params.system.deterministic && args.speed > 0.) {
        // A recorded sequence played like a live camera: frame i is not available before its time.
        const double dueMs = t0 + 1000. * (played.frame.timestamp - playback.getFirstStamp()) / args.speed;
        const double waitMs = dueMs - vpTime::measureTimeMs();
        if (waitMs > 0.) {
          vpTime::sleepMs(waitMs);
        }
      }
      const vpHSlam::State state = slam.track(I, played.frame.timestamp, played.frame.exposure);
      if (!args.quiet && (progressOnTerminal || framesFed % kProgressLogEvery == 0)) {
        printProgress(slam, state, played, frameCount, progressOnTerminal);
      }
      if (!window.show(slam, played)) {
        break;
      }
    }
  } catch (const vpException &e) {
    outcome.error = e.getStringMessage();
  } catch (const std::exception &e) {
    outcome.error = e.what();
  }
  slam.synchronize();
  window.saveScreenshot(args.screenshot);
  if (!args.quiet && progressOnTerminal) {
    std::cerr << std::endl;
  }
}

//! The summary printed at the end of a run.
void printSummary(const Arguments &args, const vpHSlamParameters &params, const vpHSlam::Statistics &s,
                  const RunOutcome &outcome)
{
  std::cout << "frames: " << s.frames << ", tracked: " << s.trackedFrames << " (" << std::fixed << std::setprecision(1)
            << (s.frames ? 100. * s.trackedFrames / s.frames : 0.) << " %), lost: " << s.lostFrames
            << ", segments: " << s.segments << ", keyframes: " << s.keyframes
            << (args.skipUnreadable ? ", dropped (unreadable): " + std::to_string(outcome.droppedFrames) : "")
            << (args.stride > 1 || args.thereAndBack ? ", read: " + std::to_string(outcome.framesRead) : "")
            << (args.thereAndBack ? ", way back: " + std::to_string(outcome.backwardFrames) : "")
            << (args.blackout ? ", blacked out: " + std::to_string(outcome.blackedOutFrames) : "") << "\n"
            << "tracking: " << std::setprecision(2) << s.trackingMsMedian << " ms median, " << s.trackingMsP95
            << " ms p95; mapping: " << s.mappingMsPerKeyframeMedian << " ms per keyframe (median)\n";
  if (params.tracking.mode != vpHSlamParameters::trackingDirect) {
    std::cout << "ORB: " << s.orbMatchesMedian << " matches, " << s.orbInliersMedian << " inliers (medians); K "
              << s.geometricWeightMedian << "; relocalisations " << s.relocalizationsSucceeded << "/"
              << s.relocalizationsAttempted << "\n";
  }
  if (params.tracking.mode == vpHSlamParameters::trackingAdaptive) {
    std::cout << "adaptive tracking: geometric term in " << s.geometricTermFrames << " of " << s.trackedFrames
              << " frames (large motion " << s.adaptiveLargeMotionFrames << ", prediction refused "
              << s.adaptivePredictionRefusedFrames << ", direct failed " << s.adaptiveDirectFailedFrames << ")\n";
  }
  const double wallS = outcome.wallS, videoS = outcome.videoS;
  std::cout << "wall time: " << std::setprecision(2) << wallS << " s for " << videoS << " s of video ("
            << (wallS > 0. ? videoS / wallS : 0.) << "x real time), CPU " << outcome.cpuS << " s; peak memory "
            << std::setprecision(1) << peakRssMb() << " MB" << std::endl;
  if (args.tag.isSet()) {
    std::cout << "tag " << args.tag.toString() << ": " << s.tagSightings << " sightings in keyframes, "
              << s.tagSightingsUsed << " kept, " << s.tagCorrections << " map corrections on seeing it again; ";
    if (s.metric) {
      std::cout << "outputs in metres" << (args.tag.hasId() ? " and in the tag's frame" : "") << " (scale "
                << std::setprecision(4) << s.metricScale << " m per map unit, +- " << std::setprecision(2)
                << 100. * s.metricScaleUncertainty << " %)" << std::endl;
    } else {
      std::cout << "NOT metric: "
                << (s.tagSightings == 0 ? "the tag was never seen in a keyframe"
                                        : "its sightings do not fix the scale well enough yet")
                << "; outputs are in the map's own unit and frame" << std::endl;
    }
  }
  if (s.segments > 1) {
    std::cout << "warning: tracking was lost; the trajectory has " << s.segments
              << " map segments with independent scales (see the .segN.txt files)" << std::endl;
  }
}

//! --groundtruth-out's poses for the frames fed (empty without the option), with a word on those left without one.
vpHSlamTrajectory makeGroundTruthOut(const vpHSlamTrajectory &groundTruth, const FramePlayback &playback)
{
  const std::vector<FedStamp> &fed = playback.getFedStamps();
  vpHSlamTrajectory out = groundTruthOfFedFrames(groundTruth, fed);
  if (out.size() < fed.size()) {
    std::cerr << "warning: --groundtruth-out: " << fed.size() - out.size() << " of " << fed.size()
              << " frames tracked have no ground-truth pose within " << kGroundTruthMaxDt << " s of their stamp"
              << std::endl;
  }
  return out;
}

int run(const Arguments &args)
{
  // First: a signal during the opening of a long sequence also ends the run cleanly.
  installTerminationHandlers();
  vpHSlamLog::setSink(vpHSlamLog::stderrSink());
  vpHSlamLog::setLevel(vpHSlamLog::levelFromString(args.logLevel));
  const vpHSlamParameters params = makeParameters(args);
  if (!args.saveConfig.empty()) {
    params.save(args.saveConfig);
  }
  // Read before the run: a missing or malformed ground truth is reported now, not after a long sequence.
  const std::string groundTruthPath = groundTruthInput(args);
  const vpHSlamTrajectory groundTruth =
      groundTruthPath.empty() ? vpHSlamTrajectory() : vpHSlamTrajectory::readTum(groundTruthPath);

  std::unique_ptr<vpHSlamImageSource> source = vpHSlamImageSource::create(args.input, args.options);
  std::cout << "source: " << source->describe() << std::endl;
  std::cout << source->getPhotometricCalibration().getStatus() << std::endl;
  vpHSlam slam(*source, params);
  slam.setTag(args.tag);
  if (!args.loadMap.empty()) {
    slam.loadMap(args.loadMap);
    std::cout << "map: " << args.loadMap << " loaded"
              << (params.system.localizationOnly ? ", localisation only (the map is not changed)" : "") << std::endl;
  }
  printSetup(args, params, slam);
  const bool progressOnTerminal = ::isatty(STDERR_FILENO) != 0;
  FramePlayback playback(*source, args, [&](const std::string &message) {
    std::cerr << (progressOnTerminal && !args.quiet ? "\n" : "") << "warning: dropped an unreadable frame (" << message
              << ")" << std::endl;
  });

  RunOutcome outcome;
  const double t0 = vpTime::measureTimeMs();
  const double cpu0 = processCpuSeconds();
  trackFrames(args, params, slam, playback, source->getFrameCount(), outcome);
  const int signal = g_signal; // read once: a signal arriving from now on only ends the program if repeated
  outcome.signal = signal;
  outcome.wallS = (vpTime::measureTimeMs() - t0) / 1000.;
  outcome.cpuS = processCpuSeconds() - cpu0;
  outcome.framesRead = playback.getFramesRead();
  outcome.droppedFrames = playback.getDroppedFrames();
  outcome.blackedOutFrames = playback.getBlackedOutFrames();
  outcome.backwardFrames = playback.getBackwardFrames();
  outcome.videoS = playback.getPlayedSeconds();
  if (signal != 0) {
    std::cout << "interrupted by " << signalName(signal) << ": writing what was computed" << std::endl;
  }
  if (!outcome.error.empty()) {
    std::cerr << "error after " << outcome.framesRead << " frames: " << outcome.error << " (writing what was computed)"
              << std::endl;
  }
  printSummary(args, params, slam.getStatistics(), outcome);
  const vpHSlamTrajectory groundTruthOut =
      args.groundTruthOut.empty() ? vpHSlamTrajectory() : makeGroundTruthOut(groundTruth, playback);
  const bool written = writeOutputs(args, slam, outcome, groundTruthOut);
  if (g_signal != 0) {     // also a signal that came while the files were written
    return 128 + g_signal; // the shell convention for a program ended by a signal
  }
  if (outcome.framesRead == 0 && outcome.error.empty()) {
    std::cerr << "error: no frame could be read from '" << args.input << "'" << std::endl;
    return EXIT_FAILURE;
  }
  return (outcome.error.empty() && written) ? EXIT_SUCCESS : EXIT_FAILURE;
}
} // namespace

int main(int argc, const char *argv[])
{
  try {
    const Arguments args = parseArguments(argc, argv);
    if (args.help) {
      printUsage(argv[0], std::cout);
      return EXIT_SUCCESS;
    }
    return run(args);
  } catch (const vpHSlamException &e) {
    std::cerr << "error: " << e.getStringMessage() << std::endl;
  } catch (const vpException &e) {
    std::cerr << "error (ViSP): " << e.getStringMessage() << std::endl;
  } catch (const std::exception &e) {
    std::cerr << "error: " << e.what() << std::endl;
  } catch (...) {
    std::cerr << "error: unknown exception" << std::endl;
  }
  return EXIT_FAILURE;
}
