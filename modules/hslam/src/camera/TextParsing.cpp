/*
 * H-SLAM for ViSP.
 */
#include "camera/TextParsing.h"

#include <visp3/hslam/vpHSlamException.h>

#include <cctype>
#include <charconv>
#include <cmath>
#include <fstream>
#include <limits>
#include <sstream>
#include <sys/stat.h>

namespace hslam
{
namespace
{
const char *const kBlank = " \t\r\n";

bool isDirectory(const std::string &path)
{
  struct stat st;
  return ::stat(path.c_str(), &st) == 0 && S_ISDIR(st.st_mode);
}

bool exists(const std::string &path)
{
  struct stat st;
  return ::stat(path.c_str(), &st) == 0;
}
} // namespace

std::string fileLine(const std::string &path, std::size_t line)
{
  return path + ":" + std::to_string(line);
}

void requireFileExists(const std::string &path, const std::string &what)
{
  if (!exists(path)) {
    throw vpHSlamException(vpHSlamException::fileNotFound, path + ": " + what + " not found");
  }
}

std::vector<TextLine> readTextLines(const std::string &path)
{
  requireFileExists(path, "file");
  if (isDirectory(path)) {
    throw vpHSlamException(vpHSlamException::fileUnreadable, path + ": is a folder, expected a text file");
  }
  std::ifstream in(path.c_str());
  if (!in) {
    throw vpHSlamException(vpHSlamException::fileUnreadable, path + ": cannot be opened for reading");
  }
  std::vector<TextLine> lines;
  std::string text;
  while (std::getline(in, text)) {
    if (!text.empty() && text.back() == '\r') {
      text.pop_back();
    }
    lines.push_back(TextLine{lines.size() + 1, text});
  }
  if (in.bad()) {
    throw vpHSlamException(vpHSlamException::fileUnreadable, fileLine(path, lines.size() + 1) + ": read error");
  }
  return lines;
}

std::string trim(const std::string &text)
{
  const std::size_t begin = text.find_first_not_of(kBlank);
  if (begin == std::string::npos) {
    return std::string();
  }
  const std::size_t end = text.find_last_not_of(kBlank);
  return text.substr(begin, end - begin + 1);
}

std::vector<std::string> splitWhitespace(const std::string &text)
{
  std::vector<std::string> tokens;
  std::size_t pos = text.find_first_not_of(kBlank);
  while (pos != std::string::npos) {
    const std::size_t end = text.find_first_of(kBlank, pos);
    tokens.push_back(text.substr(pos, end == std::string::npos ? std::string::npos : end - pos));
    pos = (end == std::string::npos) ? end : text.find_first_not_of(kBlank, end);
  }
  return tokens;
}

std::vector<std::string> splitFields(const std::string &text, char separator)
{
  std::vector<std::string> fields;
  std::size_t begin = 0;
  while (true) {
    const std::size_t end = text.find(separator, begin);
    fields.push_back(trim(text.substr(begin, end == std::string::npos ? std::string::npos : end - begin)));
    if (end == std::string::npos) {
      break;
    }
    begin = end + 1;
  }
  return fields;
}

bool startsWith(const std::string &text, const std::string &prefix)
{
  return text.size() >= prefix.size() && text.compare(0, prefix.size(), prefix) == 0;
}

std::string toLower(const std::string &text)
{
  std::string lower = text;
  for (char &c : lower) {
    c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  }
  return lower;
}

bool tryParseDouble(const std::string &token, double &value)
{
  // std::from_chars ignores the C locale (a "1,5" locale cannot change how calibration files read) but rejects a
  // leading '+', which some writers emit.
  const char *first = token.data();
  const char *last = token.data() + token.size();
  if (first != last && *first == '+') {
    ++first;
  }
  if (first == last) {
    return false;
  }
  double parsed = 0.0;
  const std::from_chars_result result = std::from_chars(first, last, parsed);
  if (result.ec != std::errc() || result.ptr != last || !std::isfinite(parsed)) {
    return false;
  }
  value = parsed;
  return true;
}

double parseDouble(const std::string &token, const std::string &path, std::size_t line, const std::string &what)
{
  double value = 0.0;
  if (!tryParseDouble(token, value)) {
    throw vpHSlamException(vpHSlamException::parseError,
                           fileLine(path, line) + ": " + what + ": '" + token + "' is not a number");
  }
  return value;
}

unsigned int parseUnsigned(const std::string &token, const std::string &path, std::size_t line, const std::string &what)
{
  unsigned long long parsed = 0;
  const char *first = token.data();
  const char *last = token.data() + token.size();
  const std::from_chars_result result = std::from_chars(first, last, parsed);
  if (first == last || result.ec != std::errc() || result.ptr != last ||
      parsed > std::numeric_limits<unsigned int>::max()) {
    throw vpHSlamException(vpHSlamException::parseError,
                           fileLine(path, line) + ": " + what + ": '" + token + "' is not a non-negative integer");
  }
  return static_cast<unsigned int>(parsed);
}

std::vector<double> parseDoubles(const std::vector<std::string> &tokens, std::size_t first, const std::string &path,
                                 std::size_t line, const std::string &what)
{
  std::vector<double> values;
  for (std::size_t i = first; i < tokens.size(); ++i) {
    values.push_back(parseDouble(tokens[i], path, line, what));
  }
  return values;
}

void expectTokenCount(const std::vector<std::string> &tokens, std::size_t expected, const std::string &path,
                      std::size_t line, const std::string &what)
{
  if (tokens.size() != expected) {
    std::ostringstream msg;
    msg << fileLine(path, line) << ": expected " << expected << " values for " << what << ", found " << tokens.size();
    throw vpHSlamException(vpHSlamException::parseError, msg.str());
  }
}
} // namespace hslam
