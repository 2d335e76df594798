/*
 * H-SLAM for ViSP.
 */
#include "io/SourceFiles.h"

#include <visp3/hslam/vpHSlamException.h>
#include <visp3/io/vpImageIo.h>

#include <algorithm>
#include <cctype>
#include <filesystem>

namespace hslam
{
namespace io
{
namespace
{
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
  try {
    vpImageIo::read(I, path);
  } catch (const vpException &e) {
    throw vpHSlamException(vpHSlamException::fileUnreadable,
                           "cannot decode image '" + path + "': " + e.getStringMessage());
  } catch (const std::exception &e) {
    throw vpHSlamException(vpHSlamException::fileUnreadable, "cannot decode image '" + path + "': " + e.what());
  }
  if (I.getWidth() == 0 || I.getHeight() == 0) {
    throw vpHSlamException(vpHSlamException::fileUnreadable, "image '" + path + "' decoded to an empty image");
  }
}
} // namespace io
} // namespace hslam
