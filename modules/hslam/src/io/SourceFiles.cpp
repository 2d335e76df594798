/*
 * H-SLAM for ViSP.
 */
#include "io/SourceFiles.h"

#include <visp3/hslam/vpHSlamException.h>
#include <visp3/io/vpImageIo.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

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

std::string trim(const std::string &s)
{
  const char *blanks = " \t\r\n\f\v";
  const std::size_t first = s.find_first_not_of(blanks);
  if (first == std::string::npos) {
    return std::string();
  }
  const std::size_t last = s.find_last_not_of(blanks);
  return s.substr(first, last - first + 1);
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

std::vector<TextLine> readTextLines(const std::string &path, char comment)
{
  if (!pathIsFile(path)) {
    throw vpHSlamException(vpHSlamException::fileNotFound, "file '" + path + "' does not exist");
  }
  std::ifstream in(path);
  if (!in) {
    throw vpHSlamException(vpHSlamException::fileUnreadable, "cannot open '" + path + "'");
  }
  std::vector<TextLine> lines;
  std::string raw;
  unsigned int number = 0;
  while (std::getline(in, raw)) {
    ++number;
    const std::string text = trim(raw);
    if (text.empty() || text.front() == comment) {
      continue;
    }
    lines.push_back(TextLine{number, text});
  }
  if (in.bad()) {
    throw vpHSlamException(vpHSlamException::fileUnreadable,
                           "read error in '" + path + "' after line " + std::to_string(number));
  }
  return lines;
}

std::vector<std::string> splitFields(const std::string &text, const std::string &separators)
{
  std::vector<std::string> fields;
  std::size_t pos = 0;
  while (pos <= text.size()) {
    const std::size_t next = text.find_first_of(separators, pos);
    const std::string field = trim(text.substr(pos, next == std::string::npos ? std::string::npos : next - pos));
    if (!field.empty()) {
      fields.push_back(field);
    }
    if (next == std::string::npos) {
      break;
    }
    pos = next + 1;
  }
  return fields;
}

std::string fileLine(const std::string &path, unsigned int line)
{
  return path + ":" + std::to_string(line);
}

double parseDouble(const std::string &field, const std::string &path, unsigned int line, const std::string &what)
{
  const char *begin = field.c_str();
  char *end = nullptr;
  errno = 0;
  const double value = std::strtod(begin, &end);
  if (field.empty() || end != begin + field.size() || errno == ERANGE || !std::isfinite(value)) {
    throw vpHSlamException(vpHSlamException::parseError,
                           fileLine(path, line) + ": cannot parse " + what + " from '" + field + "'");
  }
  return value;
}

std::uint64_t parseUnsigned(const std::string &field, const std::string &path, unsigned int line,
                            const std::string &what)
{
  const char *begin = field.c_str();
  char *end = nullptr;
  errno = 0;
  const unsigned long long value = std::strtoull(begin, &end, 10);
  const bool digitsOnly =
      !field.empty() && std::all_of(field.begin(), field.end(), [](unsigned char c) { return std::isdigit(c) != 0; });
  if (!digitsOnly || end != begin + field.size() || errno == ERANGE) {
    throw vpHSlamException(vpHSlamException::parseError,
                           fileLine(path, line) + ": cannot parse " + what + " from '" + field + "'");
  }
  return static_cast<std::uint64_t>(value);
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
