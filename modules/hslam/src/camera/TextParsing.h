/*
 * H-SLAM for ViSP.
 */
// Line-oriented parsing of small text files (calibrations, timestamp lists, trajectories) with errors that name
// the file and the line. Every failure is a vpHSlamException; nothing here prints.
#ifndef HSLAM_TEXT_PARSING_H
#define HSLAM_TEXT_PARSING_H

#include <visp3/core/vpConfig.h>

#include <cstddef>
#include <string>
#include <vector>

namespace hslam
{
//! One physical line of a text file: its 1-based number and its text (end-of-line characters removed).
struct TextLine {
  std::size_t number;
  std::string text;
};

//! "path:line", the prefix of every parse error message.
VISP_EXPORT std::string fileLine(const std::string &path, std::size_t line);

/*!
  Read every line of a text file. A trailing '\r' (Windows line end) is removed from each line.
  \exception vpHSlamException::fileNotFound when \e path does not exist,
  vpHSlamException::fileUnreadable when it exists but cannot be read (e.g. a folder).
*/
VISP_EXPORT std::vector<TextLine> readTextLines(const std::string &path);

//! Throws vpHSlamException::fileNotFound (naming \e path and \e what it should hold) when \e path does not exist.
VISP_EXPORT void requireFileExists(const std::string &path, const std::string &what);

//! \e text without leading and trailing spaces, tabs, '\r' and '\n'.
VISP_EXPORT std::string trim(const std::string &text);

//! Tokens separated by runs of spaces or tabs (no empty token).
VISP_EXPORT std::vector<std::string> splitWhitespace(const std::string &text);

//! Fields separated by \e separator (empty fields kept), each trimmed: for CSV-like files.
VISP_EXPORT std::vector<std::string> splitFields(const std::string &text, char separator);

//! True when \e text starts with \e prefix.
VISP_EXPORT bool startsWith(const std::string &text, const std::string &prefix);

//! Lower-case copy (ASCII).
VISP_EXPORT std::string toLower(const std::string &text);

/*!
  Parse a whole token as a finite double, independently of the C locale. A leading '+' is accepted.
  \return false when the token is empty, has trailing characters, or is not finite (nan, inf).
*/
VISP_EXPORT bool tryParseDouble(const std::string &token, double &value);

//! As tryParseDouble(); throws vpHSlamException::parseError "path:line: <what>: 'token' is not a number".
VISP_EXPORT double parseDouble(const std::string &token, const std::string &path, std::size_t line,
                               const std::string &what);

//! A non-negative integer that fits in unsigned int; parseError otherwise (also for "1.5" or "-3").
VISP_EXPORT unsigned int parseUnsigned(const std::string &token, const std::string &path, std::size_t line,
                                       const std::string &what);

//! Tokens [first, end) parsed with parseDouble().
VISP_EXPORT std::vector<double> parseDoubles(const std::vector<std::string> &tokens, std::size_t first,
                                             const std::string &path, std::size_t line, const std::string &what);

/*!
  Throws vpHSlamException::parseError "path:line: expected <expected> values for <what>, found <n>" unless
  tokens.size() == expected.
*/
VISP_EXPORT void expectTokenCount(const std::vector<std::string> &tokens, std::size_t expected, const std::string &path,
                                  std::size_t line, const std::string &what);
} // namespace hslam

#endif
