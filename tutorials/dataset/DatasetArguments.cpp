#include "dataset/DatasetArguments.h"

#include <visp3/hslam/vpHSlamException.h>

#include <unistd.h>

#include <exception>
#include <filesystem>
#include <fstream>
#include <functional>

namespace hslam_dataset
{
namespace
{
//! Largest count accepted on the command line (frames, stride): far beyond any sequence, well inside unsigned int.
constexpr long long kMaxCount = 1000000000LL;

//! \e value as an integer in [\e lo, kMaxCount]; false when it is not one (sign, text, overflow, trailing bytes).
bool readCount(const std::string &value, long long lo, unsigned int &n)
{
  std::size_t used = 0;
  long long x = -1;
  try {
    x = std::stoll(value, &used);
  } catch (const std::exception &) {
    return false;
  }
  // std::stoll skips leading blanks and takes a sign: neither belongs in a count.
  if (value.empty() || value[0] < '0' || value[0] > '9' || used != value.size() || x < lo || x > kMaxCount) {
    return false;
  }
  n = static_cast<unsigned int>(x);
  return true;
}

unsigned int parseCount(const std::string &option, const std::string &value)
{
  unsigned int n = 0;
  if (!readCount(value, 0, n)) {
    throw vpHSlamException(vpHSlamException::invalidArgument,
                           option + " expects a non-negative integer, got '" + value + "'");
  }
  return n;
}

unsigned int parseStride(const std::string &value)
{
  unsigned int n = 0;
  if (!readCount(value, 1, n)) {
    throw vpHSlamException(vpHSlamException::invalidArgument,
                           "--stride expects an integer >= 1 (1 = every frame), got '" + value + "'");
  }
  return n;
}

FrameInterval parseBlackout(const std::string &value)
{
  const std::size_t colon = value.find(':');
  FrameInterval frames;
  if (colon == std::string::npos || !readCount(value.substr(0, colon), 0, frames.first) ||
      !readCount(value.substr(colon + 1), 0, frames.last) || frames.first > frames.last) {
    throw vpHSlamException(vpHSlamException::invalidArgument,
                           "--blackout expects A:B, two frame indices with 0 <= A <= B (e.g. 120:160), got '" + value +
                               "'");
  }
  return frames;
}

//! Refused here, before the (maybe long) opening of the source, with the option's name.
void checkTrackingMode(const std::string &value)
{
  try {
    vpHSlamParameters::parseTrackingMode(value);
  } catch (const vpHSlamException &) {
    throw vpHSlamException(vpHSlamException::invalidArgument,
                           "--tracking-mode expects direct, indirect, hybrid or adaptive, got '" + value + "'");
  }
}

//! Options that do not go together, refused before the source is opened.
void checkCombinations(const Arguments &args)
{
  if (!args.groundTruth.empty() && args.groundTruthOut.empty()) {
    throw vpHSlamException(vpHSlamException::invalidArgument,
                           "--groundtruth '" + args.groundTruth +
                               "' is only read to write --groundtruth-out FILE: give that too (or leave it out)");
  }
  // A camera has no last frame to turn back at. The format as the source will see it: given, or detected from the
  // path (no image is opened); FramePlayback checks the opened source again.
  if (!args.thereAndBack) {
    return;
  }
  const vpHSlamImageSource::Format format = args.options.format != vpHSlamImageSource::formatAuto
                                                ? args.options.format
                                                : vpHSlamImageSource::detectFormat(args.input);
  if (format == vpHSlamImageSource::formatV4l2) {
    throw vpHSlamException(vpHSlamException::invalidArgument,
                           "--there-and-back needs a recorded sequence, not a live camera ('" + args.input +
                               "'): a camera has no last frame to turn back at");
  }
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
//! The options about what is read and which frames are tracked, in which order: false when \e option is not one.
//! \e value reads the option's value (the next argument).
bool parseSourceOption(const std::string &option, const std::function<std::string()> &value, Arguments &args)
{
  if (option == "--input") {
    args.input = value();
  } else if (option == "--format") {
    args.options.format = vpHSlamImageSource::parseFormat(value());
  } else if (option == "--camera") {
    args.options.cameraFile = value();
  } else if (option == "--max-frames") {
    args.options.maxFrames = parseCount(option, value());
  } else if (option == "--start-frame") {
    args.options.startFrame = parseCount(option, value());
  } else if (option == "--stride") {
    args.stride = parseStride(value());
  } else if (option == "--blackout") {
    args.blackoutFrames = parseBlackout(value());
    args.blackout = true;
  } else if (option == "--there-and-back") {
    args.thereAndBack = true;
  } else if (option == "--groundtruth") {
    args.groundTruth = value();
  } else if (option == "--groundtruth-out") {
    args.groundTruthOut = value();
  } else if (option == "--fps") {
    args.options.frameRate = parsePositive(option, value());
  } else {
    return false;
  }
  return true;
}

//! The --help lines of parseSourceOption()'s options.
void printSourceUsage(std::ostream &out)
{
  out << "  --input PATH       what to read (required)\n"
         "  --format NAME      input format, detected from PATH's content by default (auto)\n"
         "  --camera FILE      camera file (DSO camera.txt, ViSP XML, EuRoC sensor.yaml, KITTI calib.txt);\n"
         "                     required for image folders and videos unless camera.txt/camera.xml sits beside them\n"
         "  --max-frames N     stop after N frames READ from the source (0 = all, default); with --stride K,\n"
         "                     ceil(N / K) of them are tracked (and again, but the last, with --there-and-back)\n"
         "  --start-frame N    skip the first N frames (default 0); the frame after them is frame 0 for\n"
         "                     --stride and --blackout\n"
         "  --stride K         track only frames 0, K, 2K, ... of the source (default 1: all), to simulate a\n"
         "                     K times larger motion between frames; the others are read and skipped\n"
         "  --blackout A:B     replace frames A to B (inclusive, 0 <= A <= B) by a black image of the same size\n"
         "                     and timestamp: a covered lens (default: none)\n"
         "  --there-and-back   after the last frame, track the sequence again backward to its first frame, so\n"
         "                     the way back revisits every place. The way there is the frames the options above\n"
         "                     select (--start-frame, --max-frames, --stride); the way back replays those same\n"
         "                     M frames in reverse, from the second-to-last to the first (M frames become\n"
         "                     2M - 1). Frame k of the way back is stamped t_last + k dt (t_last: the last\n"
         "                     stamp there; dt: the median interval between the frames tracked there, i.e. the\n"
         "                     frame interval times K with --stride K). --blackout goes by source index: a\n"
         "                     blacked-out frame is black both ways. The sources cannot seek, so the images\n"
         "                     tracked are kept in memory (grey, 8 bits, 0.3 MB per 640x480 frame: memory grows\n"
         "                     with the sequence; released on the way back). No way back after an error, a\n"
         "                     signal or q. Refused with a live camera. Evaluate against --groundtruth-out\n"
         "  --groundtruth-out FILE  the ground truth of every frame tracked, under the stamp it was tracked with\n"
         "                     (TUM): a frame of the way there gets the ground-truth pose nearest its stamp\n"
         "                     within "
      << kGroundTruthMaxDt
      << " s (one to one, as tutorial-hslam-evaluate does), a frame of the way\n"
         "                     back the pose of the same source frame there. Give it to tutorial-hslam-evaluate\n"
         "                     --groundtruth with the --trajectory file (same stamps). With or without\n"
         "                     --there-and-back; written also after an error or a signal (the frames tracked)\n"
         "  --groundtruth FILE ground truth read by --groundtruth-out: TUM format, camera-to-world, on the\n"
         "                     source's clock (default: groundtruth.txt in the --input folder; for EuRoC or\n"
         "                     KITTI, a TUM conversion such as ../shared/data's groundtruth_*tum.txt)\n"
         "  --fps HZ           frame rate of image folders and videos (default 30)\n";
}

} // namespace

void printUsage(const char *program, std::ostream &out)
{
  out << "Usage: " << program
      << " --input PATH [--format auto|euroc|tum-mono|tum-rgbd|kitti|images|video|v4l2]\n"
         "       [--camera FILE] [--max-frames N] [--start-frame N] [--stride K] [--blackout A:B] [--there-and-back]\n"
         "       [--fps HZ] [--groundtruth-out OUT.txt [--groundtruth GT.txt]]\n"
         "       [--mode vo-strict|vo-reuse|slam] [--tracking-mode direct|indirect|hybrid|adaptive]\n"
         "       [--deterministic] [--speed X]\n"
         "       [--config FILE.yaml] [--set SECTION.KEY=VALUE] [--save-config FILE.yaml] [--trajectory OUT.txt] "
         "[--keyframes OUT.txt]\n"
         "       [--stats OUT.json] [--map-ply OUT.ply] [--map-png OUT.png] [--save-map OUT.hmap] [--load-map "
         "MAP.hmap]\n"
         "       [--localization-only] [--tag FAMILY:SIZE[:ID]] [--skip-unreadable] [--log-level LEVEL] [--quiet]\n"
         "       [--no-display] [--screenshot FILE.png] [--help]\n\n"
         "Runs H-SLAM on PATH (a dataset folder, an image folder, a printf pattern such as img/%06d.png, a video\n"
         "file or /dev/videoN). Output files are written at the end, also after a loss of tracking, an error of\n"
         "the source or a termination signal: SIGINT (Ctrl-C), SIGTERM or SIGHUP end the run after the current\n"
         "frame, write the files and exit with status 128 + the signal number (130, 143, 129); a second signal\n"
         "ends the program at once.\n\n";
  printSourceUsage(out);
  out << "  --tag F:S[:ID]     metric poses from an AprilTag: family (tag36h11, tag25h9, tag16h5, tagCircle21h7),\n"
         "                     size of its black square in metres, optionally the id whose frame becomes the\n"
         "                     world (x right, y up as printed, z out of the tag). Outputs are in metres once\n"
         "                     the tag was seen from enough places (the summary and --stats say whether:\n"
         "                     metric, tag_sightings, metric_scale); until then, and if it never is, in the\n"
         "                     map's own unit. e.g. --tag tag36h11:0.16:0\n"
         "  --mode NAME        slam (global map re-used in the window, loop detection, Sim(3) verification,\n"
         "                     pose-graph correction of the marginalised keyframes, relocalisation), vo-reuse\n"
         "                     (global map re-used, relocalisation; no loop closure) or vo-strict (window\n"
         "                     only, DSO-like; relocalisation only with hybrid or indirect tracking);\n"
         "                     default: system.mode of --config, else slam\n"
         "  --tracking-mode M  pose tracking: direct (photometric), indirect (ORB matches), hybrid (both) or\n"
         "                     adaptive (direct, both when the motion makes it doubtful); default:\n"
         "                     tracking.mode of --config, else direct\n"
         "  --deterministic    map in the tracking thread: identical output run to run (default: real time,\n"
         "                     mapping in its own thread)\n"
         "  --speed X          real-time mode: feed recorded frames at X times their frame rate, as a camera\n"
         "                     would (default 1; 0 = as fast as possible). Ignored with --deterministic\n"
         "  --config FILE      settings (YAML, see vpHSlamParameters); command-line options override it;\n"
         "                     data/hslam-dso.yaml has DSO's settings (3x the points, slower)\n"
         "  --set S.K=V        one setting (section.key=value, as in the YAML file), after --config; repeatable,\n"
         "                     e.g. --set features.desiredImmatureDensity=490 --set tracking.relocalize=false\n"
         "  --save-config FILE write the settings in use (YAML)\n"
         "  --trajectory FILE  every frame with a pose, TUM format (t tx ty tz qx qy qz qw), camera-to-world;\n"
         "                     when tracking was lost and a new map segment started, FILE.segN.txt per segment too\n"
         "  --keyframes FILE   keyframe poses, TUM format\n"
         "  --stats FILE       run statistics as JSON: frames (given to tracking), frames_read, tracked_frames,\n"
         "                     keyframes, segments, tracking_ms_median, tracking_ms_p95,\n"
         "                     mapping_ms_per_keyframe_median, peak_rss_mb, memory_mb_per_keyframe, dropped_frames,\n"
         "                     wall_s, cpu_s, hybrid tracking (orb_matches_median, orb_inliers_median,\n"
         "                     geometric_weight_median, relocalizations_attempted, relocalizations_succeeded,\n"
         "                     descriptor_kb_per_keyframe, geometric_term_frames, geometric_term_share and, adaptive\n"
         "                     tracking, adaptive_large_motion_frames, adaptive_prediction_refused_frames,\n"
         "                     adaptive_direct_failed_frames), the run's tracking_mode, stride, blackout (\"A:B\" or\n"
         "                     \"\"), blacked_out_frames (both ways), there_and_back (true/false) and\n"
         "                     backward_frames, global map (marginalized_keyframes, culled_keyframes,\n"
         "                     global_points, reactivated_points_per_keyframe, window_share_from_global), ...\n"
         "  --map-ply FILE     the map as a PLY point cloud: active points orange, global map grey, keyframes red\n"
         "  --map-png FILE     top view of the map points and the trajectory (PNG)\n"
         "  --save-map FILE    the map at the end (H-SLAM map file: keyframes, points, descriptors, graph);\n"
         "                     needs --mode vo-reuse or slam\n"
         "  --load-map FILE    a map saved by --save-map, loaded before the first frame: without\n"
         "                     --localization-only it is kept beside the new run's map (its own segment)\n"
         "  --localization-only  locate every frame in the --load-map map (ORB matches, PnP, pose-only\n"
         "                     refinement against its keyframes) without initialising, mapping or changing it;\n"
         "                     the trajectory is in the loaded map's coordinates, unlocated frames are lost\n"
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
    } else if (parseSourceOption(option, value, args)) {
      // what is read, and which frames are tracked in which order
    } else if (option == "--mode") {
      args.mode = value();
    } else if (option == "--set") {
      const std::string text = value();
      const std::size_t dot = text.find('.'), eq = text.find('=');
      if (dot == std::string::npos || eq == std::string::npos || dot == 0 || eq < dot + 2 || eq + 1 == text.size() ||
          text.find_first_of("\n\r:#") != std::string::npos) {
        throw vpHSlamException(vpHSlamException::invalidArgument,
                               "--set expects SECTION.KEY=VALUE (e.g. tracking.mode=hybrid), got '" + text + "'");
      }
      args.settings.push_back(text);
    } else if (option == "--tracking-mode") {
      args.trackingMode = value();
      checkTrackingMode(args.trackingMode);
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
    } else if (option == "--map-ply") {
      args.mapPly = value();
    } else if (option == "--map-png") {
      args.mapPng = value();
    } else if (option == "--save-map") {
      args.saveMap = value();
    } else if (option == "--tag") {
      args.tag = vpHSlamTag::parse(value());
    } else if (option == "--load-map") {
      args.loadMap = value();
    } else if (option == "--localization-only") {
      args.localizationOnly = true;
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
  if (!args.help && args.localizationOnly && args.loadMap.empty()) {
    throw vpHSlamException(vpHSlamException::invalidArgument,
                           "--localization-only needs a map to locate frames in: --load-map FILE");
  }
  if (!args.help) {
    checkCombinations(args);
  }
  return args;
}

vpHSlamParameters makeParameters(const Arguments &args)
{
  vpHSlamParameters params;
  if (!args.config.empty()) {
    params.load(args.config);
  }
  for (const std::string &setting : args.settings) {
    // Read through the YAML loader (same checks and messages as a file): one section, one key.
    const std::size_t dot = setting.find('.'), eq = setting.find('=');
    const std::filesystem::path file = std::filesystem::temp_directory_path() /
                                       ("hslam-set-" + std::to_string(static_cast<long long>(::getpid())) + ".yaml");
    {
      std::ofstream out(file);
      out << "%YAML:1.0\n---\n"
          << setting.substr(0, dot) << ":\n  " << setting.substr(dot + 1, eq - dot - 1) << ": "
          << setting.substr(eq + 1) << "\n";
    }
    try {
      params.load(file.string());
    } catch (const vpHSlamException &e) {
      std::error_code ignored;
      std::filesystem::remove(file, ignored);
      throw vpHSlamException(static_cast<vpHSlamException::ErrorCode>(e.getCode()),
                             "--set " + setting + ": " + e.getStringMessage());
    }
    std::error_code ignored;
    std::filesystem::remove(file, ignored);
  }
  if (!args.mode.empty()) {
    params.system.mode = vpHSlamParameters::parseMode(args.mode);
  }
  if (!args.trackingMode.empty()) {
    params.tracking.mode = vpHSlamParameters::parseTrackingMode(args.trackingMode);
  }
  if (args.deterministic) {
    params.system.deterministic = true;
  }
  if (args.localizationOnly) {
    params.system.localizationOnly = true;
  }
  params.validate();
  return params;
}
} // namespace hslam_dataset
