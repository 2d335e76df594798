/*
 * H-SLAM for ViSP.
 */
// Reading and writing the small text files of the module (calibrations, image lists, timestamp lists,
// trajectories): line reading, tokenising, locale-independent number parsing and printing, with errors that name
// the file and the line. Every failure is a vpHSlamException; nothing here prints.
#ifndef HSLAM_COMMON_TEXT_PARSING_H
#define HSLAM_COMMON_TEXT_PARSING_H

#include <visp3/core/vpConfig.h>
#include <visp3/hslam/vpHSlamException.h>

#include <charconv>
#include <cstddef>
#include <cstdint>
#include <fstream>
#include <string>
#include <vector>

namespace hslam
{
//! One line of a text file: its 1-based number in the file and its text (end-of-line characters removed).
struct TextLine {
  std::size_t number = 0;
  std::string text;
};

//! "path:line", the prefix of every parse error message.
VISP_EXPORT std::string fileLine(const std::string &path, std::size_t line);

//! Throw vpHSlamException(code, "<path>:<line>: <what>"); line 0 leaves the line out ("<path>: <what>").
[[noreturn]] VISP_EXPORT void throwAt(vpHSlamException::ErrorCode code, const std::string &path, std::size_t line,
                                      const std::string &what);

//! Throws vpHSlamException::fileNotFound "path: <what> not found" when \e path does not exist.
VISP_EXPORT void requireFileExists(const std::string &path, const std::string &what);

/*!
  Read every line of a text file, blank lines included. A trailing '\\r' (Windows line end) is removed.
  \param what : what the file should hold, for the message when it is missing ("camera file", "trajectory").
  \exception vpHSlamException::fileNotFound when \e path does not exist,
  vpHSlamException::fileUnreadable when it exists but cannot be read (e.g. a folder).
*/
VISP_EXPORT std::vector<TextLine> readTextLines(const std::string &path, const std::string &what = "file");

/*!
  The data lines of a list or table file (rgb.txt, times.txt, data.csv, trajectories): as readTextLines(), then
  everything from \e comment to the end of a line is dropped, the rest trimmed, and lines left empty are skipped.
  Line numbers stay those of the file.
*/
VISP_EXPORT std::vector<TextLine> readDataLines(const std::string &path, const std::string &what = "file",
                                                char comment = '#');

//! The whole content of a text file. \exception as readTextLines().
VISP_EXPORT std::string readTextFile(const std::string &path, const std::string &what = "file");

/*!
  Refuses \e text (the content of \e path) when it holds a NUL byte: not a text file. Called before text goes to
  OpenCV's YAML reader, which loops for ever on one (found by fuzz_parameters).
  \exception vpHSlamException::parseError naming the file and the line of the first NUL byte.
*/
VISP_EXPORT void requireNoNulByte(const std::string &text, const std::string &path);

/*!
  Refuses YAML \e text (the content of \e path) with a line outside any [...] or {...} that is neither a comment, a
  directive (%...), a document marker alone ("---" or "..."), a "key:" line nor a "- item" line, or less indented
  than the first key line. The files H-SLAM reads
  (settings, sensor.yaml, Kalibr camchains) never have one, and OpenCV's YAML reader can loop for ever on such a
  line (a bare "18, -0.5" after an indented map; found by fuzz_camera_yaml).
  \exception vpHSlamException::parseError naming the file and the line.
*/
VISP_EXPORT void requireYamlLineShapes(const std::string &text, const std::string &path);

//! \e text without leading and trailing blanks (space, tab, '\\r', '\\n', '\\f', '\\v').
VISP_EXPORT std::string trim(const std::string &text);

//! Tokens separated by runs of blanks (no empty token).
VISP_EXPORT std::vector<std::string> splitWhitespace(const std::string &text);

//! Fields separated by \e separator (empty fields kept), each trimmed: for CSV-like files.
VISP_EXPORT std::vector<std::string> splitFields(const std::string &text, char separator);

//! Split on any character of \e separators, each piece trimmed, empty pieces dropped (so "a  b" gives two).
VISP_EXPORT std::vector<std::string> splitTokens(const std::string &text, const std::string &separators);

//! True when \e text starts with \e prefix.
VISP_EXPORT bool startsWith(const std::string &text, const std::string &prefix);

//! Lower-case copy (ASCII).
VISP_EXPORT std::string toLower(const std::string &text);

/*!
  Parse a whole token as a finite double, independently of the C locale. A leading '+' is accepted.
  \return false when the token is empty, has trailing characters, or is not finite (nan, inf).
*/
VISP_EXPORT bool tryParseDouble(const std::string &token, double &value);

//! Parse a whole token as a signed 64-bit integer (no '+', no blanks).
VISP_EXPORT bool tryParseInt64(const std::string &token, long long &value);

//! As tryParseDouble(); throws vpHSlamException::parseError "path:line: <what>: 'token' is not a number".
VISP_EXPORT double parseDouble(const std::string &token, const std::string &path, std::size_t line,
                               const std::string &what);

//! A non-negative integer that fits in unsigned int; parseError otherwise (also for "1.5" or "-3").
VISP_EXPORT unsigned int parseUnsigned(const std::string &token, const std::string &path, std::size_t line,
                                       const std::string &what);

//! As parseUnsigned() for the full 64-bit range (e.g. EuRoC timestamps in nanoseconds).
VISP_EXPORT std::uint64_t parseUInt64(const std::string &token, const std::string &path, std::size_t line,
                                      const std::string &what);

//! Tokens [first, end) parsed with parseDouble(); \e what is the message's name for them.
VISP_EXPORT std::vector<double> parseDoubles(const std::vector<std::string> &tokens, std::size_t first,
                                             const std::string &path, std::size_t line, const std::string &what);

/*!
  Throws vpHSlamException::parseError "path:line: expected <expected> values for <what>, found <n>" unless
  tokens.size() == expected.
*/
VISP_EXPORT void expectTokenCount(const std::vector<std::string> &tokens, std::size_t expected, const std::string &path,
                                  std::size_t line, const std::string &what);

//! Append \e value printed with std::to_chars (locale-independent) in a given format and precision.
VISP_EXPORT void appendNumber(std::string &out, double value, std::chars_format format, int precision);

//! Open (truncate) \e path for writing; throws vpHSlamException::fileUnreadable naming it when that fails.
VISP_EXPORT void openForWriting(std::ofstream &file, const std::string &path);

//! Flush and close, turning any stream failure (disk full, I/O error) into an error: lines are never lost quietly.
VISP_EXPORT void flushAndClose(std::ofstream &file, const std::string &path);
} // namespace hslam

#endif
