// Small text helpers shared by the trajectory readers and writers: locale-independent number parsing and
// printing (std::from_chars / std::to_chars, so a user locale with ',' decimals cannot corrupt a file), and
// errors that name file:line.
#ifndef HSLAM_IO_TRAJECTORY_TEXT_H
#define HSLAM_IO_TRAJECTORY_TEXT_H

#include <visp3/hslam/vpHSlamException.h>

#include <charconv>
#include <cmath>
#include <fstream>
#include <string>
#include <vector>

namespace hslam
{
namespace trajectory_text
{
//! Throw a vpHSlamException whose message reads "<path>:<line>: <what>" (line 0: no line part).
[[noreturn]] inline void fail(vpHSlamException::ErrorCode code, const std::string &path, size_t line,
                              const std::string &what)
{
  std::string where = path;
  if (line > 0) {
    where += ":" + std::to_string(line);
  }
  throw vpHSlamException(code, where + ": " + what);
}

//! Strip a '#' comment and surrounding blanks (spaces, tabs, CR of Windows line ends).
inline std::string stripComment(const std::string &line)
{
  std::string s = line.substr(0, line.find('#'));
  const char *blanks = " \t\r\n";
  const size_t first = s.find_first_not_of(blanks);
  if (first == std::string::npos) {
    return std::string();
  }
  const size_t last = s.find_last_not_of(blanks);
  return s.substr(first, last - first + 1);
}

//! Split on any of the separator characters, dropping empty fields (tolerates repeated blanks).
inline std::vector<std::string> splitFields(const std::string &s, const char *separators)
{
  std::vector<std::string> fields;
  size_t pos = 0;
  while (pos < s.size()) {
    const size_t begin = s.find_first_not_of(separators, pos);
    if (begin == std::string::npos) {
      break;
    }
    size_t end = s.find_first_of(separators, begin);
    if (end == std::string::npos) {
      end = s.size();
    }
    fields.push_back(s.substr(begin, end - begin));
    pos = end;
  }
  return fields;
}

//! Parse a whole field as a finite double; false on trailing garbage, NaN or infinity.
inline bool parseDouble(const std::string &field, double &value)
{
  const char *first = field.data();
  const char *last = field.data() + field.size();
  if (first != last && *first == '+') {
    ++first;
  }
  const std::from_chars_result r = std::from_chars(first, last, value);
  return r.ec == std::errc() && r.ptr == last && std::isfinite(value);
}

//! Parse a whole field as a signed 64-bit integer.
inline bool parseInt64(const std::string &field, long long &value)
{
  const char *first = field.data();
  const char *last = field.data() + field.size();
  const std::from_chars_result r = std::from_chars(first, last, value);
  return r.ec == std::errc() && r.ptr == last;
}

//! Append a number printed in a given format and precision.
inline void appendNumber(std::string &out, double value, std::chars_format format, int precision)
{
  char buffer[64];
  const std::to_chars_result r = std::to_chars(buffer, buffer + sizeof(buffer), value, format, precision);
  out.append(buffer, r.ptr);
}

//! Open a file for writing or throw.
inline void openForWriting(std::ofstream &file, const std::string &path)
{
  file.open(path, std::ios::out | std::ios::trunc);
  if (!file.is_open()) {
    fail(vpHSlamException::fileUnreadable, path, 0, "cannot open the file for writing");
  }
}

//! Flush and close, turning any stream failure (disk full, I/O error) into an error: lines are never lost quietly.
inline void flushAndClose(std::ofstream &file, const std::string &path)
{
  file.flush();
  const bool ok = file.good();
  file.close();
  if (!ok || file.fail()) {
    fail(vpHSlamException::fileUnreadable, path, 0, "writing failed (disk full or I/O error): the file is incomplete");
  }
}
} // namespace trajectory_text
} // namespace hslam

#endif
