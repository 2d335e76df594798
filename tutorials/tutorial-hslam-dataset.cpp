//! \example tutorial-hslam-dataset.cpp
//! Run H-SLAM on a dataset, a video, an image folder or a V4L2 camera: every frame is read from a
//! vpHSlamImageSource, given to vpHSlam::track(), and the trajectory (TUM, camera-to-world, every frame with a pose),
//! the keyframes and run statistics (JSON) are written at the end -- also when tracking was lost midway, when the
//! source failed, or when the run was stopped by SIGINT (Ctrl-C), SIGTERM (timeout, systemd, docker stop) or SIGHUP
//! (the terminal closed); the exit status is then 128 + the signal number, as a shell reports a killed program.
//! With --skip-unreadable, an image that cannot be decoded is counted as dropped and the run carries on.
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
#include <visp3/hslam/vpHSlamImageSource.h>
#include <visp3/hslam/vpHSlamLiveView.h>
#include <visp3/hslam/vpHSlamLog.h>
#include <visp3/hslam/vpHSlamParameters.h>
#include <visp3/hslam/vpHSlamRectifier.h>
#include <visp3/io/vpImageIo.h>

#include <algorithm>
#include <cmath>
#include <csignal>
#include <cstdlib>
#include <fstream>
#include <functional>
#include <iomanip>
#include <iostream>
#include <memory>
#include <sstream>
#include <string>
#include <sys/resource.h>
#include <unistd.h>
#include <vector>

//! Without a terminal, the progress line is printed once every this many frames.
constexpr unsigned int kProgressLogEvery = 50;

//! With --skip-unreadable, the run still stops when this many frames in a row cannot be read: the input is then
//! broken as a whole (a wrong folder, a dead disk), not a frame here and there.
constexpr unsigned int kMaxConsecutiveUnreadable = 100;

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

std::string signalName(int signal)
{
  switch (signal) {
  case SIGINT:
    return "SIGINT";
  case SIGTERM:
    return "SIGTERM";
  case SIGHUP:
    return "SIGHUP";
  default:
    return "signal " + std::to_string(signal);
  }
}

struct Arguments {
  std::string input;
  vpHSlamImageSource::Options options;
  std::string mode = "vo-strict";
  bool deterministic = false;
  double speed = 1.; //!< real-time mode: play the sequence at this multiple of its frame rate (0: no pacing)
  std::string config;
  std::string trajectory;
  std::string keyframes;
  std::string stats;
  std::string saveConfig;
  std::string logLevel = "warning";
  bool display = true;
  std::string screenshot; //!< PNG of the last view drawn (needs a display)
  bool quiet = false;
  bool skipUnreadable = false; //!< count undecodable frames as dropped and carry on (default: stop with the error)
  bool help = false;
};

void printUsage(const char *program, std::ostream &out)
{
  out << "Usage: " << program
      << " --input PATH [--format auto|euroc|tum-mono|tum-rgbd|kitti|images|video|v4l2]\n"
         "       [--camera FILE] [--max-frames N] [--start-frame N] [--fps HZ] [--mode vo-strict]\n"
         "       [--deterministic] [--speed X] [--config FILE.yaml] [--save-config FILE.yaml] [--trajectory OUT.txt]\n"
         "       [--keyframes OUT.txt] [--stats OUT.json] [--skip-unreadable] [--log-level LEVEL] [--quiet]\n"
         "       [--no-display] [--screenshot FILE.png] [--help]\n\n"
         "Runs H-SLAM on PATH (a dataset folder, an image folder, a printf pattern such as img/%06d.png, a video\n"
         "file or /dev/videoN). Output files are written at the end, also after a loss of tracking, an error of\n"
         "the source or a termination signal: SIGINT (Ctrl-C), SIGTERM or SIGHUP end the run after the current\n"
         "frame, write the files and exit with status 128 + the signal number (130, 143, 129); a second signal\n"
         "ends the program at once.\n\n"
         "  --input PATH       what to read (required)\n"
         "  --format NAME      input format, detected from PATH's content by default (auto)\n"
         "  --camera FILE      camera file (DSO camera.txt, ViSP XML, EuRoC sensor.yaml, KITTI calib.txt);\n"
         "                     required for image folders and videos unless camera.txt/camera.xml sits beside them\n"
         "  --max-frames N     stop after N frames (0 = all, default)\n"
         "  --start-frame N    skip the first N frames (default 0)\n"
         "  --fps HZ           frame rate of image folders and videos (default 30)\n"
         "  --mode NAME        vo-strict (window only, DSO-like; the only mode implemented so far)\n"
         "  --deterministic    map in the tracking thread: identical output run to run (default: real time,\n"
         "                     mapping in its own thread)\n"
         "  --speed X          real-time mode: feed recorded frames at X times their frame rate, as a camera\n"
         "                     would (default 1; 0 = as fast as possible). Ignored with --deterministic\n"
         "  --config FILE      settings (YAML, see vpHSlamParameters); command-line options override it;\n"
         "                     data/hslam-fast.yaml is a real-time preset (DSO defaults otherwise)\n"
         "  --save-config FILE write the settings in use (YAML)\n"
         "  --trajectory FILE  every frame with a pose, TUM format (t tx ty tz qx qy qz qw), camera-to-world;\n"
         "                     when tracking was lost and a new map segment started, FILE.segN.txt per segment too\n"
         "  --keyframes FILE   keyframe poses, TUM format\n"
         "  --stats FILE       run statistics as JSON (frames, tracked_frames, keyframes, tracking_ms_median,\n"
         "                     tracking_ms_p95, mapping_ms_per_keyframe_median, peak_rss_mb,\n"
         "                     memory_mb_per_keyframe, dropped_frames, wall_s, cpu_s, ...)\n"
         "  --skip-unreadable  an image that cannot be read or decoded is reported, counted as dropped (in the\n"
         "                     summary and the statistics) and skipped; tracking carries on with the next frame.\n"
         "                     Without it (default), the run stops at that image with an error naming it. The run\n"
         "                     stops anyway after "
      << kMaxConsecutiveUnreadable
      << " unreadable frames in a row\n"
         "  --log-level LEVEL  library messages on stderr: error, warning (default), info, debug\n"
         "  --quiet            no progress line\n"
         "  --no-display       do not open a window (also when no X display is available)\n"
         "  --screenshot FILE  with a window: save the last view shown as a PNG at the end\n"
         "  --help             this text\n";
}

unsigned int parseCount(const std::string &option, const std::string &value)
{
  std::size_t used = 0;
  long long n = -1;
  try {
    n = std::stoll(value, &used);
  } catch (const std::exception &) {
    used = 0;
  }
  if (used != value.size() || n < 0 || n > 1000000000LL) {
    throw vpHSlamException(vpHSlamException::invalidArgument,
                           option + " expects a non-negative integer, got '" + value + "'");
  }
  return static_cast<unsigned int>(n);
}

double parsePositive(const std::string &option, const std::string &value)
{
  std::size_t used = 0;
  double x = -1.;
  try {
    x = std::stod(value, &used);
  } catch (const std::exception &) {
    used = 0;
  }
  if (used != value.size() || !(x > 0.)) {
    throw vpHSlamException(vpHSlamException::invalidArgument,
                           option + " expects a positive number, got '" + value + "'");
  }
  return x;
}

Arguments parseArguments(int argc, const char *const argv[])
{
  Arguments args;
  for (int i = 1; i < argc; ++i) {
    const std::string option = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) {
        throw vpHSlamException(vpHSlamException::invalidArgument, option + " needs a value");
      }
      return argv[++i];
    };
    if (option == "--help" || option == "-h") {
      args.help = true;
    } else if (option == "--input") {
      args.input = value();
    } else if (option == "--format") {
      args.options.format = vpHSlamImageSource::parseFormat(value());
    } else if (option == "--camera") {
      args.options.cameraFile = value();
    } else if (option == "--max-frames") {
      args.options.maxFrames = parseCount(option, value());
    } else if (option == "--start-frame") {
      args.options.startFrame = parseCount(option, value());
    } else if (option == "--fps") {
      args.options.frameRate = parsePositive(option, value());
    } else if (option == "--mode") {
      args.mode = value();
    } else if (option == "--deterministic") {
      args.deterministic = true;
    } else if (option == "--speed") {
      const std::string text = value();
      args.speed = text == "0" ? 0. : parsePositive(option, text);
    } else if (option == "--config") {
      args.config = value();
    } else if (option == "--save-config") {
      args.saveConfig = value();
    } else if (option == "--trajectory") {
      args.trajectory = value();
    } else if (option == "--keyframes") {
      args.keyframes = value();
    } else if (option == "--stats") {
      args.stats = value();
    } else if (option == "--log-level") {
      args.logLevel = value();
    } else if (option == "--quiet") {
      args.quiet = true;
    } else if (option == "--no-display") {
      args.display = false;
    } else if (option == "--screenshot") {
      args.screenshot = value();
    } else if (option == "--skip-unreadable") {
      args.skipUnreadable = true;
    } else {
      throw vpHSlamException(vpHSlamException::invalidArgument, "unknown option '" + option + "' (see --help)");
    }
  }
  if (!args.help && args.input.empty()) {
    throw vpHSlamException(vpHSlamException::invalidArgument, "--input PATH is required (see --help)");
  }
  return args;
}

//! Settings: defaults, then --config, then the command line.
vpHSlamParameters makeParameters(const Arguments &args)
{
  vpHSlamParameters params;
  if (!args.config.empty()) {
    params.load(args.config);
  }
  const vpHSlamParameters::Mode mode = vpHSlamParameters::parseMode(args.mode);
  if (mode != vpHSlamParameters::modeVoStrict) {
    throw vpHSlamException(vpHSlamException::unsupported,
                           "--mode " + args.mode +
                               ": not implemented yet; only vo-strict (window-only odometry) is available for now");
  }
  params.system.mode = mode;
  if (args.deterministic) {
    params.system.deterministic = true;
  }
  params.validate();
  return params;
}

std::string jsonNumber(double x)
{
  if (!std::isfinite(x)) {
    return "null";
  }
  std::ostringstream s;
  s << std::setprecision(10) << x;
  return s.str();
}

//! How a run ended, besides what vpHSlam::Statistics says.
struct RunOutcome {
  double wallS = 0.;
  double cpuS = 0.;
  double videoS = 0.;
  unsigned int droppedFrames = 0; //!< unreadable frames skipped (--skip-unreadable)
  int signal = 0;                 //!< termination signal that stopped the run, 0 when none
  std::string error;              //!< error that stopped the run, empty when none
};

void writeStats(const std::string &path, const vpHSlam::Statistics &s, const std::string &input,
                const RunOutcome &outcome, double peakRssMb, bool deterministic)
{
  const std::string &error = outcome.error;
  const double wallS = outcome.wallS, cpuS = outcome.cpuS, videoS = outcome.videoS;
  std::ofstream out(path.c_str());
  if (!out) {
    throw vpHSlamException(vpHSlamException::fileUnreadable, "cannot write the statistics file '" + path + "'");
  }
  const unsigned int held = std::max(1u, s.keyframesHeld);
  std::string escapedError;
  for (char c : error) {
    if (c == '"' || c == '\\') {
      escapedError += '\\';
    }
    escapedError += (c == '\n' ? ' ' : c);
  }
  std::string escapedInput;
  for (char c : input) {
    if (c == '"' || c == '\\') {
      escapedInput += '\\';
    }
    escapedInput += c;
  }
  out << "{\n"
      << "  \"input\": \"" << escapedInput << "\",\n"
      << "  \"deterministic\": " << (deterministic ? "true" : "false") << ",\n"
      << "  \"frames\": " << s.frames << ",\n"
      << "  \"dropped_frames\": " << outcome.droppedFrames << ",\n"
      << "  \"tracked_frames\": " << s.trackedFrames << ",\n"
      << "  \"tracked_share\": " << jsonNumber(s.frames ? double(s.trackedFrames) / s.frames : 0.) << ",\n"
      << "  \"lost_frames\": " << s.lostFrames << ",\n"
      << "  \"segments\": " << s.segments << ",\n"
      << "  \"keyframes\": " << s.keyframes << ",\n"
      << "  \"mapping_skipped_frames\": " << s.mappingSkippedFrames << ",\n"
      << "  \"tracking_ms_median\": " << jsonNumber(s.trackingMsMedian) << ",\n"
      << "  \"tracking_ms_p95\": " << jsonNumber(s.trackingMsP95) << ",\n"
      << "  \"tracking_ms_max\": " << jsonNumber(s.trackingMsMax) << ",\n"
      << "  \"initialization_ms_median\": " << jsonNumber(s.initializationMsMedian) << ",\n"
      << "  \"mapping_ms_per_keyframe_median\": " << jsonNumber(s.mappingMsPerKeyframeMedian) << ",\n"
      << "  \"mapping_ms_per_keyframe_p95\": " << jsonNumber(s.mappingMsPerKeyframeP95) << ",\n"
      << "  \"mapping_ms_per_frame_median\": " << jsonNumber(s.mappingMsPerFrameMedian) << ",\n"
      << "  \"active_points\": " << s.activePoints << ",\n"
      << "  \"peak_rss_mb\": " << jsonNumber(peakRssMb) << ",\n"
      << "  \"map_memory_mb\": " << jsonNumber(s.mapMemoryMb) << ",\n"
      << "  \"memory_mb_per_keyframe\": " << jsonNumber(s.mapMemoryMb / held) << ",\n"
      << "  \"wall_s\": " << jsonNumber(wallS) << ",\n"
      << "  \"cpu_s\": " << jsonNumber(cpuS) << ",\n"
      << "  \"video_s\": " << jsonNumber(videoS) << ",\n"
      << "  \"realtime_factor\": " << jsonNumber(wallS > 0. ? videoS / wallS : 0.) << ",\n"
      << "  \"interrupted\": " << (outcome.signal != 0 ? "true" : "false") << ",\n"
      << "  \"signal\": " << (outcome.signal != 0 ? "\"" + signalName(outcome.signal) + "\"" : std::string("null"))
      << ",\n"
      << "  \"error\": " << (error.empty() ? std::string("null") : "\"" + escapedError + "\"") << "\n"
      << "}\n";
  out.flush();
  if (!out) {
    throw vpHSlamException(vpHSlamException::fileUnreadable, "cannot write the statistics file '" + path + "'");
  }
}

//! Peak resident memory of this process from /proc/self/status (VmHWM), MB; 0 when unavailable.
double peakRssMb()
{
  std::ifstream status("/proc/self/status");
  std::string line;
  while (std::getline(status, line)) {
    if (line.compare(0, 6, "VmHWM:") == 0) {
      std::istringstream in(line.substr(6));
      double kb = 0.;
      if (in >> kb) {
        return kb / 1024.;
      }
    }
  }
  return 0.;
}

//! CPU time (user + system) used by this process so far, seconds.
double processCpuSeconds()
{
  rusage usage{};
  if (getrusage(RUSAGE_SELF, &usage) != 0) {
    return 0.;
  }
  constexpr double kMicro = 1e-6;
  return static_cast<double>(usage.ru_utime.tv_sec + usage.ru_stime.tv_sec) +
         kMicro * static_cast<double>(usage.ru_utime.tv_usec + usage.ru_stime.tv_usec);
}

//! Write every requested output; report (do not throw) failures so that each file gets its chance.
bool writeOutputs(const Arguments &args, const vpHSlam &slam, const RunOutcome &outcome)
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
    attempt(args.stats, [&]() {
      writeStats(args.stats, stats, args.input, outcome, peakRssMb(), slam.getParameters().system.deterministic);
    });
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
  std::cout << "mode: " << vpHSlamParameters::modeName(params.system.mode)
            << (params.system.deterministic ? ", deterministic" : ", real time") << "; rectified " << slam.getWidth()
            << "x" << slam.getHeight() << std::endl;

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
  double firstTimestamp = 0., lastTimestamp = 0.;
  unsigned int framesRead = 0;
  const bool progressOnTerminal = ::isatty(STDERR_FILENO) != 0;
  RunOutcome outcome;
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
      if (!args.quiet && (progressOnTerminal || framesRead % kProgressLogEvery == 0)) {
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
        view.draw(slam, frame.index, fps, canvas, "space: pause  q: quit");
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
      vpImageIo::write(shot, args.screenshot);
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
            << (args.skipUnreadable ? ", dropped (unreadable): " + std::to_string(outcome.droppedFrames) : "") << "\n"
            << "tracking: " << std::setprecision(2) << s.trackingMsMedian << " ms median, " << s.trackingMsP95
            << " ms p95; mapping: " << s.mappingMsPerKeyframeMedian << " ms per keyframe (median)\n"
            << "wall time: " << std::setprecision(2) << wallS << " s for " << videoS << " s of video ("
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
