//! \example tutorial-hslam-dataset.cpp
//! Open a dataset, a video, an image folder or a V4L2 camera as a vpHSlamImageSource, read every frame, rectify
//! it to pinhole and report what was read. The same program will later feed the frames to vpHSlam.
//!
//!   ./tutorial-hslam-dataset --input ../shared/data/euroc_V1_01_easy_first95 --no-display
#include <visp3/core/vpConfig.h>
#include <visp3/core/vpImage.h>
#include <visp3/core/vpImageTools.h>
#include <visp3/core/vpTime.h>
#include <visp3/gui/vpDisplayX.h>
#include <visp3/hslam/vpHSlamException.h>
#include <visp3/hslam/vpHSlamImageSource.h>
#include <visp3/hslam/vpHSlamRectifier.h>

#include <algorithm>
#include <cstdlib>
#include <iomanip>
#include <iostream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

namespace
{
struct Arguments {
  std::string input;
  vpHSlamImageSource::Options options;
  bool display = true;
  bool help = false;
};

void printUsage(const char *program, std::ostream &out)
{
  out << "Usage: " << program
      << " --input PATH [--format auto|euroc|tum-mono|tum-rgbd|kitti|images|video|v4l2]\n"
         "       [--camera FILE] [--max-frames N] [--start-frame N] [--fps HZ] [--no-display] [--help]\n\n"
         "Reads every frame of PATH (a dataset folder, an image folder, a printf pattern such as img/%06d.png, a\n"
         "video file or /dev/videoN), rectifies it to pinhole and prints what was read.\n\n"
         "  --input PATH       what to read (required)\n"
         "  --format NAME      input format, detected from PATH's content by default (auto)\n"
         "  --camera FILE      camera file (DSO camera.txt, ViSP XML, EuRoC sensor.yaml, KITTI calib.txt);\n"
         "                     required for image folders and videos unless camera.txt/camera.xml sits beside them\n"
         "  --max-frames N     stop after N frames (0 = all, default)\n"
         "  --start-frame N    skip the first N frames (default 0)\n"
         "  --fps HZ           frame rate of image folders and videos (default 30)\n"
         "  --no-display       do not open a window (also when no X display is available)\n"
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
    } else if (option == "--no-display") {
      args.display = false;
    } else {
      throw vpHSlamException(vpHSlamException::invalidArgument, "unknown option '" + option + "' (see --help)");
    }
  }
  if (!args.help && args.input.empty()) {
    throw vpHSlamException(vpHSlamException::invalidArgument, "--input PATH is required (see --help)");
  }
  return args;
}

double median(std::vector<double> values)
{
  if (values.empty()) {
    return 0.;
  }
  const std::size_t mid = values.size() / 2;
  std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(mid), values.end());
  return values[mid];
}

int run(const Arguments &args)
{
  std::unique_ptr<vpHSlamImageSource> source = vpHSlamImageSource::create(args.input, args.options);
  std::cout << "source: " << source->describe() << std::endl;

  const vpHSlamCamera &camera = source->getCamera();
  vpHSlamRectifier rectifier(camera);

  bool display = args.display;
#if defined(VISP_HAVE_X11)
  const char *xDisplay = std::getenv("DISPLAY");
  if (display && (xDisplay == nullptr || *xDisplay == '\0')) {
    std::cout << "no X display: running without window" << std::endl;
    display = false;
  }
  vpDisplayX window;
#else
  display = false;
#endif

  vpImage<unsigned char> I, Irect;
  vpHSlamImageSource::Frame frame;
  std::vector<double> rectifyMs;
  unsigned int framesRead = 0;
  double firstTimestamp = 0., lastTimestamp = 0.;
  while (source->acquire(I, frame)) {
    const double t0 = vpTime::measureTimeMs();
    rectifier.rectify(I, Irect);
    rectifyMs.push_back(vpTime::measureTimeMs() - t0);
    if (framesRead == 0) {
      firstTimestamp = frame.timestamp;
    }
    lastTimestamp = frame.timestamp;
    ++framesRead;
#if defined(VISP_HAVE_X11)
    if (display) {
      if (framesRead == 1) {
        window.init(Irect, 0, 0, "H-SLAM dataset: rectified input");
      }
      vpDisplay::display(Irect);
      std::ostringstream text;
      text << "frame " << frame.index << "  t = " << std::fixed << std::setprecision(3) << frame.timestamp
           << " s  (click to stop)";
      vpDisplay::displayText(Irect, 15, 10, text.str(), vpColor::red);
      vpDisplay::flush(Irect);
      if (vpDisplay::getClick(Irect, false)) {
        break;
      }
    }
#endif
  }

  const vpHSlamPhotometricCalibration &photometric = source->getPhotometricCalibration();
  std::cout << "format: " << vpHSlamImageSource::formatName(source->getFormat()) << "\n"
            << "frames read: " << framesRead << "\n"
            << "image size: " << camera.getWidth() << "x" << camera.getHeight() << " (rectified "
            << rectifier.getWidth() << "x" << rectifier.getHeight() << ")\n"
            << "frame rate: " << source->getFrameRate() << " Hz";
  if (framesRead > 1 && lastTimestamp > firstTimestamp) {
    std::cout << " (measured over the frames read: " << (framesRead - 1) / (lastTimestamp - firstTimestamp) << " Hz)";
  }
  std::cout << "\n"
            << "camera: " << camera.toString() << "\n"
            << photometric.getStatus() << "\n"
            << "rectification: " << std::fixed << std::setprecision(3) << median(rectifyMs) << " ms per frame (median)"
            << std::endl;
  if (framesRead == 0) {
    std::cerr << "error: no frame could be read from '" << args.input << "'" << std::endl;
    return EXIT_FAILURE;
  }
  return EXIT_SUCCESS;
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
