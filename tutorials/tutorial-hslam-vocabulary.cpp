//! \example tutorial-hslam-vocabulary.cpp
//! Train an ORB bag-of-words vocabulary (hierarchical k-means, TF-IDF) from images, or convert a vocabulary file.
//!
//!   ./tutorial-hslam-vocabulary --images /usr/share/visp-images-data/ViSP-images --output my-vocabulary.hvoc
//!   ./tutorial-hslam-vocabulary --convert ORBvoc.txt --output ORBvoc.hvoc
#include <visp3/core/vpImage.h>
#include <visp3/core/vpImageConvert.h>
#include <visp3/core/vpTime.h>
#include <visp3/hslam/vpHSlamException.h>
#include <visp3/hslam/vpHSlamImageSource.h>
#include <visp3/hslam/vpHSlamVocabulary.h>
#include <visp3/hslam/vpHSlamVocabularyTrainer.h>
#include <visp3/io/vpImageIo.h>

#include <opencv2/videoio.hpp>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <string>
#include <unistd.h>
#include <vector>

namespace
{
struct Options {
  std::vector<std::string> inputs;
  std::string convert;
  std::string output;
  std::string format = "binary";
  unsigned int step = 1;
  vpHSlamVocabularyTrainer::Options training;
};

void printUsage(const char *program)
{
  std::cout
      << "Usage: " << program << " --images PATH [PATH ...] --output FILE [options]\n"
      << "       " << program << " --convert FILE --output FILE [--format F]\n"
      << "Trains an ORB vocabulary for H-SLAM's place recognition, or converts a vocabulary between formats.\n\n"
      << "Inputs (--images, any number, read in the order given; files of a folder sorted by name):\n"
      << "  a dataset folder any H-SLAM reader opens (EuRoC, TUM mono, TUM RGB-D, KITTI), a video file, an image\n"
      << "  file, or any other folder, searched recursively for images (.png .jpg .jpeg .pgm .ppm .bmp .tif .tiff).\n"
      << "  Unreadable images are skipped and counted. Same inputs, options and seed: byte-identical output.\n\n"
      << "Options:\n"
      << "  --images PATH...   training inputs (several paths may follow one --images)\n"
      << "  --output FILE      vocabulary to write\n"
      << "  --branching K      children per node, default 10\n"
      << "  --levels L         depth of the tree, default 6 (up to K^L words)\n"
      << "  --features N       ORB features per image, default 1000\n"
      << "  --step S           use every S-th frame of dataset folders and videos, default 1\n"
      << "  --seed S           k-means++ seed, default 1\n"
      << "  --format F         output format: binary (default, H-SLAM .hvoc), text (DBoW2 / ORBvoc.txt) or yaml\n"
      << "                     (DBoW2 OpenCV YAML, gzip when FILE ends with .gz)\n"
      << "  --convert FILE     read a vocabulary (any format) instead of training, write it with --format\n"
      << "  --help             this text\n";
}

bool parseUnsigned(const std::string &text, unsigned long long &value)
{
  char *end = nullptr;
  value = std::strtoull(text.c_str(), &end, 10);
  return !text.empty() && text[0] != '-' && end && *end == '\0';
}

bool parseArguments(int argc, char **argv, Options &options, int &status)
{
  status = EXIT_FAILURE;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    const bool hasValue = i + 1 < argc;
    unsigned long long number = 0;
    if (arg == "--help" || arg == "-h") {
      printUsage(argv[0]);
      status = EXIT_SUCCESS;
      return false;
    } else if (arg == "--images" && hasValue) {
      while (i + 1 < argc && std::string(argv[i + 1]).rfind("--", 0) != 0) {
        options.inputs.push_back(argv[++i]);
      }
    } else if (arg == "--output" && hasValue) {
      options.output = argv[++i];
    } else if (arg == "--convert" && hasValue) {
      options.convert = argv[++i];
    } else if (arg == "--format" && hasValue) {
      options.format = argv[++i];
    } else if ((arg == "--branching" || arg == "--levels" || arg == "--features" || arg == "--step" ||
                arg == "--seed") &&
               hasValue) {
      if (!parseUnsigned(argv[++i], number) || (arg != "--seed" && (number == 0 || number > 100000))) {
        std::cerr << "Invalid value '" << argv[i] << "' for " << arg << "\n";
        return false;
      }
      if (arg == "--branching") {
        options.training.branching = static_cast<unsigned int>(number);
      } else if (arg == "--levels") {
        options.training.levels = static_cast<unsigned int>(number);
      } else if (arg == "--features") {
        options.training.featuresPerImage = static_cast<unsigned int>(number);
      } else if (arg == "--step") {
        options.step = static_cast<unsigned int>(number);
      } else {
        options.training.seed = number;
      }
    } else {
      std::cerr << "Unknown or incomplete option '" << arg << "'\n\n";
      printUsage(argv[0]);
      return false;
    }
  }
  if (options.output.empty() || (options.inputs.empty() == options.convert.empty())) {
    std::cerr << "Give --output and either --images PATH... or --convert FILE\n\n";
    printUsage(argv[0]);
    return false;
  }
  return true;
}

bool hasExtension(const std::filesystem::path &path, const std::vector<std::string> &extensions)
{
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return std::find(extensions.begin(), extensions.end(), ext) != extensions.end();
}

const std::vector<std::string> kImageExtensions = {".png", ".jpg", ".jpeg", ".pgm", ".ppm", ".bmp", ".tif", ".tiff"};
const std::vector<std::string> kVideoExtensions = {".mp4", ".avi", ".mpg", ".mpeg", ".mov", ".mkv", ".ogv", ".webm"};

//! Feeds images to the trainer and counts what was used and skipped.
class Collector
{
public:
  Collector(vpHSlamVocabularyTrainer &trainer, unsigned int step) : m_trainer(trainer), m_step(step) {}

  void addPath(const std::string &path)
  {
    namespace fs = std::filesystem;
    const vpHSlamImageSource::Format format = vpHSlamImageSource::detectFormat(path);
    if (format == vpHSlamImageSource::formatEuroc || format == vpHSlamImageSource::formatTumMono ||
        format == vpHSlamImageSource::formatTumRgbd || format == vpHSlamImageSource::formatKitti) {
      addDataset(path);
    } else if (fs::is_directory(path)) {
      std::vector<std::string> files;
      for (const fs::directory_entry &e : fs::recursive_directory_iterator(path)) {
        if (e.is_regular_file() && hasExtension(e.path(), kImageExtensions)) {
          files.push_back(e.path().string());
        }
      }
      std::sort(files.begin(), files.end());
      std::cout << path << ": " << files.size() << " image files" << std::endl;
      for (const std::string &file : files) {
        addImageFile(file);
      }
    } else if (fs::is_regular_file(path) && hasExtension(fs::path(path), kVideoExtensions)) {
      addVideo(path);
    } else if (fs::is_regular_file(path)) {
      addImageFile(path);
    } else {
      throw vpHSlamException(vpHSlamException::fileNotFound, path + ": training input not found");
    }
  }

  std::size_t skipped() const { return m_skipped; }

private:
  void add(const vpImage<unsigned char> &I)
  {
    m_trainer.addImage(I);
    if (m_trainer.getImageCount() % 100 == 0) {
      std::cout << "  " << m_trainer.getImageCount() << " images, " << m_trainer.getDescriptorCount() << " descriptors"
                << std::endl;
    }
  }

  void addImageFile(const std::string &file)
  {
    vpImage<unsigned char> I;
    try {
      vpImageIo::read(I, file);
    } catch (const vpException &) {
      ++m_skipped;
      return;
    }
    if (I.getSize() == 0) {
      ++m_skipped;
      return;
    }
    add(I);
  }

  void addDataset(const std::string &path)
  {
    std::unique_ptr<vpHSlamImageSource> source = vpHSlamImageSource::create(path);
    std::cout << source->describe() << std::endl;
    vpImage<unsigned char> I;
    vpHSlamImageSource::Frame frame;
    unsigned int index = 0;
    for (;;) {
      try {
        if (!source->acquire(I, frame)) {
          break;
        }
      } catch (const vpHSlamException &e) {
        ++m_skipped; // the frame that threw is consumed: carry on with the next one
        continue;
      }
      if (index++ % m_step == 0) {
        add(I);
      }
    }
  }

  void addVideo(const std::string &path)
  {
    // OpenCV's reader directly: it reports the end of the stream, where ViSP 3.5's vpVideoReader keeps returning
    // the last decoded image when a container does not store its frame count.
    cv::VideoCapture capture(path);
    if (!capture.isOpened()) {
      throw vpHSlamException(vpHSlamException::fileUnreadable, path + ": cannot open the video");
    }
    cv::Mat frame;
    vpImage<unsigned char> I;
    unsigned int index = 0;
    while (capture.read(frame) && !frame.empty()) {
      if (index++ % m_step == 0) {
        vpImageConvert::convert(frame, I);
        add(I);
      }
    }
    std::cout << path << ": " << index << " video frames" << std::endl;
  }

  vpHSlamVocabularyTrainer &m_trainer;
  unsigned int m_step;
  std::size_t m_skipped = 0;
};
} // namespace

int main(int argc, char **argv)
{
  Options options;
  int status = EXIT_FAILURE;
  if (!parseArguments(argc, argv, options, status)) {
    return status;
  }
  try {
    const vpHSlamVocabulary::FileFormat format = vpHSlamVocabulary::parseFormat(options.format);
    if (!options.convert.empty()) {
      const double t0 = vpTime::measureTimeMs();
      const vpHSlamVocabulary vocabulary = vpHSlamVocabulary::load(options.convert);
      std::cout << vocabulary.describe() << " (read in " << (vpTime::measureTimeMs() - t0) / 1000. << " s)\n";
      vocabulary.save(options.output, format);
      std::cout << "written: " << options.output << std::endl;
      return EXIT_SUCCESS;
    }

    vpHSlamVocabularyTrainer trainer(options.training);
    Collector collector(trainer, options.step);
    for (const std::string &input : options.inputs) {
      collector.addPath(input);
    }
    std::cout << "  " << trainer.getImageCount() << " images, " << trainer.getDescriptorCount() << " descriptors ("
              << collector.skipped() << " unreadable images skipped)" << std::endl;
    const double t0 = vpTime::measureTimeMs();
    // A bar redrawn in place on a terminal; one line per 10 % in logs and pipes.
    const bool terminal = isatty(STDOUT_FILENO) != 0;
    int lastTenth = -1;
    const vpHSlamVocabulary vocabulary = trainer.train([&](double fraction) {
      const int width = 40;
      const int done = static_cast<int>(fraction * width + 0.5);
      const int percent = static_cast<int>(100 * fraction + 0.5);
      if (!terminal && percent / 10 == lastTenth) {
        return;
      }
      lastTenth = percent / 10;
      std::cout << (terminal ? "\r" : "") << "  k-means [" << std::string(static_cast<std::size_t>(done), '#')
                << std::string(static_cast<std::size_t>(width - done), ' ') << "] " << percent << " %"
                << (terminal ? "" : "\n") << std::flush;
    });
    std::cout << "\n" << vocabulary.describe() << " (trained in " << (vpTime::measureTimeMs() - t0) / 1000. << " s)\n";
    vocabulary.save(options.output, format);
    std::cout << "written: " << options.output << std::endl;
  } catch (const vpException &e) {
    std::cerr << "Error: " << e.getStringMessage() << std::endl;
    return EXIT_FAILURE;
  }
  return EXIT_SUCCESS;
}
