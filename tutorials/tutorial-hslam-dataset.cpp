//! \example tutorial-hslam-dataset.cpp
//! Run H-SLAM on a dataset, a video, an image folder or a V4L2 camera: every frame is read from a
//! vpHSlamImageSource, given to vpHSlam::track(), and the trajectory (TUM, camera-to-world, every frame with a pose),
//! the keyframes and run statistics (JSON) are written at the end -- also when tracking was lost midway, when the
//! source failed, or when the run was stopped by SIGINT (Ctrl-C), SIGTERM (timeout, systemd, docker stop) or SIGHUP
//! (the terminal closed); the exit status is then 128 + the signal number, as a shell reports a killed program.
//! With --skip-unreadable, an image that cannot be decoded is counted as dropped and the run carries on.
//! Stress runs: --stride K tracks every K-th frame (large motion), --blackout A:B feeds black frames (a covered
//! lens), --tracking-mode direct|indirect|hybrid selects the tracker. Options and statistics: tutorials/dataset/.
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
#include "dataset/DatasetMapOutput.h"
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
bool writeOutputs(const Arguments &args, vpHSlam &slam, const RunOutcome &outcome)
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

  std::unique_ptr<vpHSlamImageSource> source = vpHSlamImageSource::create(args.input, args.options);
  std::cout << "source: " << source->describe() << std::endl;
  std::cout << source->getPhotometricCalibration().getStatus() << std::endl;
  vpHSlam slam(*source, params);
  if (!args.loadMap.empty()) {
    slam.loadMap(args.loadMap);
    std::cout << "map: " << args.loadMap << " loaded"
              << (params.system.localizationOnly ? ", localisation only (the map is not changed)" : "") << std::endl;
  }
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

  bool display = args.display;
#if defined(VISP_HAVE_X11)
  const char *xDisplay = std::getenv("DISPLAY");
  if (display && (xDisplay == nullptr || *xDisplay == '\0')) {
    std::cout << "no X display: running without window" << std::endl;
    display = false;
  }
  vpDisplayX window;
  bool windowOpen = false;
  vpHSlamLiveView view;
  vpImage<vpRGBa> canvas;
  double fps = 0., lastDrawMs = 0.;
#else
  display = false;
#endif

  const int frameCount = source->getFrameCount();
  vpImage<unsigned char> I;
  vpHSlamImageSource::Frame frame;
  RunOutcome outcome;
  double firstTimestamp = 0., lastTimestamp = 0.;
  unsigned int &framesRead = outcome.framesRead;
  unsigned int framesFed = 0;
  const bool progressOnTerminal = ::isatty(STDERR_FILENO) != 0;
  std::string &error = outcome.error;
  unsigned int consecutiveUnreadable = 0;
  const double t0 = vpTime::measureTimeMs();
  const double cpu0 = processCpuSeconds();
  try {
    while (g_signal == 0) {
      try {
        if (!source->acquire(I, frame)) {
          break;
        }
        consecutiveUnreadable = 0;
      } catch (const vpHSlamException &e) {
        // The source consumed the frame it could not read: the next acquire() reads the one after.
        if (!args.skipUnreadable || e.getCode() != vpHSlamException::fileUnreadable ||
            ++consecutiveUnreadable >= kMaxConsecutiveUnreadable) {
          throw;
        }
        ++outcome.droppedFrames;
        std::cerr << (progressOnTerminal && !args.quiet ? "\n" : "") << "warning: dropped an unreadable frame ("
                  << e.getStringMessage() << ")" << std::endl;
        continue;
      }
      if (framesRead == 0) {
        firstTimestamp = frame.timestamp;
      }
      lastTimestamp = frame.timestamp;
      ++framesRead;
      // --stride and --blackout go by the source's numbering (after --start-frame; an unreadable frame dropped by
      // --skip-unreadable keeps its number), so a run with dropped frames still tracks the same frames.
      if (!args.feeds(frame.index)) {
        continue;
      }
      if (args.blacksOut(frame.index)) {
        I = 0; // a covered lens: same size, same timestamp and exposure
        ++outcome.blackedOutFrames;
      }
      ++framesFed;
      if (!params.system.deterministic && args.speed > 0.) {
        // A recorded sequence played like a live camera: frame i is not available before its time.
        const double dueMs = t0 + 1000. * (frame.timestamp - firstTimestamp) / args.speed;
        const double waitMs = dueMs - vpTime::measureTimeMs();
        if (waitMs > 0.) {
          vpTime::sleepMs(waitMs);
        }
      }
      const vpHSlam::State state = slam.track(I, frame.timestamp, frame.exposure);
      // On a terminal the progress line rewrites itself; in a log (CI, a file) it becomes one line every
      // kProgressLogEvery frames so the log stays readable.
      if (!args.quiet && (progressOnTerminal || framesFed % kProgressLogEvery == 0)) {
        const vpHSlam::Statistics s = slam.getStatistics();
        std::cerr << (progressOnTerminal ? "\r" : "") << "frame " << frame.index + 1;
        if (frameCount > 0) {
          std::cerr << "/" << frameCount;
        }
        std::cerr << "  " << std::setw(12) << std::left << vpHSlam::stateName(state) << std::right << " tracked "
                  << s.trackedFrames << "  kf " << s.keyframes << "  pts " << s.activePoints << "  trk " << std::fixed
                  << std::setprecision(1) << s.trackingMsMedian << " ms  map " << s.mappingMsPerKeyframeMedian
                  << " ms/kf   " << (progressOnTerminal ? "" : "\n") << std::flush;
      }
#if defined(VISP_HAVE_X11)
      if (display) {
        // Live view: image with the active points by inverse depth, status, top view; space pauses, q or
        // Escape (or a click) quits.
        const double now = vpTime::measureTimeMs();
        if (lastDrawMs > 0. && now > lastDrawMs) {
          const double instantFps = 1000. / (now - lastDrawMs);
          fps = fps > 0. ? 0.9 * fps + 0.1 * instantFps : instantFps;
        }
        lastDrawMs = now;
        view.draw(slam, frame.index, fps, canvas,
                  args.blacksOut(frame.index) ? "blackout  q: quit" : "space: pause  q: quit");
        if (!windowOpen) {
          try {
            window.init(canvas, 0, 0, "H-SLAM");
            windowOpen = true;
          } catch (const vpException &e) {
            std::cerr << "warning: cannot open a window (" << e.getStringMessage() << "): running without display"
                      << std::endl;
            display = false;
            continue;
          }
        }
        vpDisplay::display(canvas);
        vpDisplay::flush(canvas);
        bool quit = vpDisplay::getClick(canvas, false);
        std::string key;
        bool paused = false;
        while (!quit && g_signal == 0) {
          if (vpDisplay::getKeyboardEvent(canvas, key, false)) {
            if (key == "q" || key == "Q" || key == "\x1b" || key == "Escape") {
              quit = true;
            } else if (key == " " || key == "space" || key == "p") {
              paused = !paused;
            }
          }
          quit = quit || vpDisplay::getClick(canvas, false);
          if (!paused) {
            break;
          }
          vpTime::wait(20.);
        }
        if (quit) {
          break;
        }
      }
#endif
    }
  } catch (const vpException &e) {
    error = e.getStringMessage();
  } catch (const std::exception &e) {
    error = e.what();
  }
  slam.synchronize();
#if defined(VISP_HAVE_X11)
  if (windowOpen && !args.screenshot.empty()) {
    try {
      vpImage<vpRGBa> shot;
      vpDisplay::getImage(canvas, shot);
      vpHSlamImageIo::writePng(args.screenshot, shot);
      std::cout << "screenshot: " << args.screenshot << std::endl;
    } catch (const vpException &e) {
      std::cerr << "warning: cannot save the screenshot '" << args.screenshot << "': " << e.getStringMessage()
                << std::endl;
    }
  }
#endif
  const int signal = g_signal; // read once: a signal arriving from now on only ends the program if repeated
  outcome.signal = signal;
  outcome.wallS = (vpTime::measureTimeMs() - t0) / 1000.;
  outcome.cpuS = processCpuSeconds() - cpu0;
  const double wallS = outcome.wallS, cpuS = outcome.cpuS;
  if (!args.quiet && progressOnTerminal) {
    std::cerr << std::endl;
  }
  if (signal != 0) {
    std::cout << "interrupted by " << signalName(signal) << ": writing what was computed" << std::endl;
  }
  if (!error.empty()) {
    std::cerr << "error after " << framesRead << " frames: " << error << " (writing what was computed)" << std::endl;
  }

  const vpHSlam::Statistics s = slam.getStatistics();
  const double videoS = framesRead > 1 ? (lastTimestamp - firstTimestamp) * framesRead / (framesRead - 1) : 0.;
  outcome.videoS = videoS;
  std::cout << "frames: " << s.frames << ", tracked: " << s.trackedFrames << " (" << std::fixed << std::setprecision(1)
            << (s.frames ? 100. * s.trackedFrames / s.frames : 0.) << " %), lost: " << s.lostFrames
            << ", segments: " << s.segments << ", keyframes: " << s.keyframes
            << (args.skipUnreadable ? ", dropped (unreadable): " + std::to_string(outcome.droppedFrames) : "")
            << (args.stride > 1 ? ", read: " + std::to_string(framesRead) : "")
            << (args.blackout ? ", blacked out: " + std::to_string(outcome.blackedOutFrames) : "") << "\n"
            << "tracking: " << std::setprecision(2) << s.trackingMsMedian << " ms median, " << s.trackingMsP95
            << " ms p95; mapping: " << s.mappingMsPerKeyframeMedian << " ms per keyframe (median)\n";
  if (params.tracking.mode != vpHSlamParameters::trackingDirect) {
    std::cout << "ORB: " << s.orbMatchesMedian << " matches, " << s.orbInliersMedian << " inliers (medians); K "
              << s.geometricWeightMedian << "; relocalisations " << s.relocalizationsSucceeded << "/"
              << s.relocalizationsAttempted << "\n";
  }
  std::cout << "wall time: " << std::setprecision(2) << wallS << " s for " << videoS << " s of video ("
            << (wallS > 0. ? videoS / wallS : 0.) << "x real time), CPU " << cpuS << " s; peak memory "
            << std::setprecision(1) << peakRssMb() << " MB" << std::endl;
  if (s.segments > 1) {
    std::cout << "warning: tracking was lost; the trajectory has " << s.segments
              << " map segments with independent scales (see the .segN.txt files)" << std::endl;
  }
  const bool written = writeOutputs(args, slam, outcome);
  if (g_signal != 0) {     // also a signal that came while the files were written
    return 128 + g_signal; // the shell convention for a program ended by a signal
  }
  if (framesRead == 0 && error.empty()) {
    std::cerr << "error: no frame could be read from '" << args.input << "'" << std::endl;
    return EXIT_FAILURE;
  }
  return (error.empty() && written) ? EXIT_SUCCESS : EXIT_FAILURE;
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
