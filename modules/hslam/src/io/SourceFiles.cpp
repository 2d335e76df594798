/*
 * H-SLAM for ViSP.
 */
#include "io/SourceFiles.h"

#include "io/ImageCodec.h"

#include <visp3/hslam/vpHSlamException.h>

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <fstream>
#include <iterator>

namespace hslam
{
namespace io
{
namespace
{
// JPEG markers (ITU-T T.81, table B.1): start of image, start of scan, end of image.
constexpr unsigned char kJpegMarkerPrefix = 0xFF;
constexpr unsigned char kJpegStartOfImage = 0xD8;
constexpr unsigned char kJpegStartOfScan = 0xDA;
constexpr unsigned char kJpegEndOfImage = 0xD9;

bool isJpeg(const std::vector<unsigned char> &bytes)
{
  return bytes.size() >= 2 && bytes[0] == kJpegMarkerPrefix && bytes[1] == kJpegStartOfImage;
}

/*!
  True when the JPEG's last scan is followed by the end-of-image marker. libjpeg
  decodes a truncated file without error, filling the missing part, so a cut file must be caught here. Inside
  entropy-coded data a 0xFF byte is always followed by 0x00 or a restart marker (T.81 B.1.1.5), hence FF D9 after
  the last FF DA can only be the real end of the image, and data appended after it (some cameras do) is harmless.
*/
bool jpegIsComplete(const std::vector<unsigned char> &bytes)
{
  std::size_t lastScan = 0;
  for (std::size_t i = 0; i + 1 < bytes.size(); ++i) {
    if (bytes[i] == kJpegMarkerPrefix && bytes[i + 1] == kJpegStartOfScan) {
      lastScan = i;
    }
  }
  if (lastScan == 0) { // offset 0 holds the start-of-image marker: no scan at all
    return false;
  }
  for (std::size_t i = lastScan; i + 1 < bytes.size(); ++i) {
    if (bytes[i] == kJpegMarkerPrefix && bytes[i + 1] == kJpegEndOfImage) {
      return true;
    }
  }
  return false;
}

void requireCompleteJpeg(const std::vector<unsigned char> &bytes, const std::string &name)
{
  if (isJpeg(bytes) && !jpegIsComplete(bytes)) {
    throw vpHSlamException(vpHSlamException::fileUnreadable, "cannot decode image '" + name +
                                                                 "': the JPEG data ends before its end-of-image marker "
                                                                 "(truncated file)");
  }
}

std::string stripTrailingSeparators(const std::string &path)
{
  std::string p = path;
  while (p.size() > 1 && p.back() == '/') {
    p.pop_back();
  }
  return p;
}
} // namespace

std::string joinPath(const std::string &a, const std::string &b)
{
  if (a.empty() || (!b.empty() && b.front() == '/')) {
    return b;
  }
  if (b.empty()) {
    return a;
  }
  return a.back() == '/' ? a + b : a + "/" + b;
}

std::string baseName(const std::string &path)
{
  const std::string p = stripTrailingSeparators(path);
  const std::size_t slash = p.find_last_of('/');
  return slash == std::string::npos ? p : p.substr(slash + 1);
}

std::string parentPath(const std::string &path)
{
  const std::string p = stripTrailingSeparators(path);
  const std::size_t slash = p.find_last_of('/');
  if (slash == std::string::npos) {
    return ".";
  }
  return slash == 0 ? std::string("/") : p.substr(0, slash);
}

std::string stemName(const std::string &name)
{
  const std::string base = baseName(name);
  const std::size_t dot = base.find_last_of('.');
  return (dot == std::string::npos || dot == 0) ? base : base.substr(0, dot);
}

std::string lowerExtension(const std::string &name)
{
  const std::string base = baseName(name);
  const std::size_t dot = base.find_last_of('.');
  if (dot == std::string::npos || dot == 0) {
    return std::string();
  }
  std::string ext = base.substr(dot + 1);
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  return ext;
}

bool pathIsDirectory(const std::string &path)
{
  std::error_code ec;
  return std::filesystem::is_directory(path, ec);
}

bool pathIsFile(const std::string &path)
{
  std::error_code ec;
  return std::filesystem::is_regular_file(path, ec);
}

bool hasImageExtension(const std::string &name)
{
  static const char *const extensions[] = {"png", "jpg", "jpeg", "pgm", "ppm", "bmp", "tif", "tiff"};
  const std::string ext = lowerExtension(name);
  return std::find(std::begin(extensions), std::end(extensions), ext) != std::end(extensions);
}

bool hasVideoExtension(const std::string &name)
{
  // The containers OpenCV's VideoCapture (vpVideoReader's backend) usually opens.
  static const char *const extensions[] = {"avi", "mp4", "m4v", "mov", "mkv", "mpg", "mpeg", "ogv", "webm", "wmv"};
  const std::string ext = lowerExtension(name);
  return std::find(std::begin(extensions), std::end(extensions), ext) != std::end(extensions);
}

std::vector<std::string> listImageFiles(const std::string &folder)
{
  if (!pathIsDirectory(folder)) {
    throw vpHSlamException(vpHSlamException::fileNotFound, "image folder '" + folder + "' does not exist");
  }
  std::vector<std::string> names;
  std::error_code ec;
  for (std::filesystem::directory_iterator it(folder, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string name = it->path().filename().string();
    if (!name.empty() && name.front() != '.' && hasImageExtension(name) && it->is_regular_file(ec)) {
      names.push_back(name);
    }
  }
  if (ec) {
    throw vpHSlamException(vpHSlamException::fileUnreadable,
                           "cannot list image folder '" + folder + "': " + ec.message());
  }
  std::sort(names.begin(), names.end());
  return names;
}

void readGreyImage(const std::string &path, vpImage<unsigned char> &I)
{
  if (!pathIsFile(path)) {
    throw vpHSlamException(vpHSlamException::fileNotFound, "image '" + path + "' does not exist");
  }
  decodeGreyImage(readFileBytes(path), path, I);
}

void decodeGreyImage(const std::vector<unsigned char> &bytes, const std::string &name, vpImage<unsigned char> &I)
{
  requireCompleteJpeg(bytes, name);
  decodeGrey8(bytes.data(), bytes.size(), name, I);
}

std::vector<TextLine> readListLines(const std::string &path, const std::string &what)
{
  std::vector<TextLine> lines = readDataLines(path, what);
  std::ifstream in(path, std::ios::binary);
  const std::string content((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (lines.empty() || content.empty() || content.back() == '\n') {
    return lines;
  }
  const std::size_t lastLine = static_cast<std::size_t>(std::count(content.begin(), content.end(), '\n')) + 1;
  if (lines.back().number == lastLine) {
    throwAt(vpHSlamException::parseError, path, lastLine,
            "the last line '" + lines.back().text +
                "' has no end of line: the list looks truncated (cut during a copy or download?); if the line is "
                "complete, end it with a newline");
  }
  return lines;
}
} // namespace io
} // namespace hslam
