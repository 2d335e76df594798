/*
 * H-SLAM for ViSP.
 */
#include "common/TextParsing.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <limits>
#include <sstream>

namespace hslam
{
namespace
{
const char *const kBlank = " \t\r\n\f\v";

//! Opens \e path for reading after checking it is a readable file (not missing, not a folder).
std::ifstream openForReading(const std::string &path, const std::string &what)
{
  requireFileExists(path, what);
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) {
    throw vpHSlamException(vpHSlamException::fileUnreadable, path + ": is a folder, expected a text file");
  }
  std::ifstream in(path.c_str());
  if (!in) {
    throw vpHSlamException(vpHSlamException::fileUnreadable, path + ": cannot be opened for reading");
  }
  return in;
}

//! std::from_chars over the whole token: no sign, blank or trailing character accepted.
template <typename Integer> bool parseWholeInteger(const std::string &token, Integer &value)
{
  const char *first = token.data();
  const char *last = token.data() + token.size();
  Integer parsed = 0;
  const std::from_chars_result result = std::from_chars(first, last, parsed);
  if (first == last || result.ec != std::errc() || result.ptr != last) {
    return false;
  }
  value = parsed;
  return true;
}

template <typename Unsigned>
Unsigned parseUnsignedAs(const std::string &token, const std::string &path, std::size_t line, const std::string &what)
{
  unsigned long long parsed = 0;
  if (!parseWholeInteger(token, parsed) || parsed > std::numeric_limits<Unsigned>::max()) {
    throw vpHSlamException(vpHSlamException::parseError,
                           fileLine(path, line) + ": " + what + ": '" + token + "' is not a non-negative integer");
  }
  return static_cast<Unsigned>(parsed);
}
} // namespace

std::string fileLine(const std::string &path, std::size_t line)
{
  return path + ":" + std::to_string(line);
}

void throwAt(vpHSlamException::ErrorCode code, const std::string &path, std::size_t line, const std::string &what)
{
  throw vpHSlamException(code, (line > 0 ? fileLine(path, line) : path) + ": " + what);
}

void requireFileExists(const std::string &path, const std::string &what)
{
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) {
    throw vpHSlamException(vpHSlamException::fileNotFound, path + ": " + what + " not found");
  }
}

std::vector<TextLine> readTextLines(const std::string &path, const std::string &what)
{
  std::ifstream in = openForReading(path, what);
  std::vector<TextLine> lines;
  std::string text;
  while (std::getline(in, text)) {
    if (!text.empty() && text.back() == '\r') {
      text.pop_back();
    }
    TextLine line;
    line.number = lines.size() + 1;
    line.text = text;
    lines.push_back(line);
  }
  if (in.bad()) {
    throwAt(vpHSlamException::fileUnreadable, path, lines.size() + 1, "read error");
  }
  return lines;
}

std::vector<TextLine> readDataLines(const std::string &path, const std::string &what, char comment)
{
  std::vector<TextLine> lines = readTextLines(path, what);
  std::size_t kept = 0;
  for (std::size_t i = 0; i < lines.size(); ++i) {
    lines[i].text = trim(lines[i].text.substr(0, lines[i].text.find(comment)));
    if (lines[i].text.empty()) {
      continue;
    }
    if (kept != i) {
      lines[kept] = std::move(lines[i]);
    }
    ++kept;
  }
  lines.resize(kept);
  return lines;
}

std::string readTextFile(const std::string &path, const std::string &what)
{
  std::ifstream in = openForReading(path, what);
  std::stringstream buffer;
  buffer << in.rdbuf();
  if (in.bad()) {
    throwAt(vpHSlamException::fileUnreadable, path, 0, "read error");
  }
  return buffer.str();
}

void requireNoNulByte(const std::string &text, const std::string &path)
{
  const std::size_t nul = text.find('\0');
  if (nul != std::string::npos) {
    const std::size_t line = 1 + static_cast<std::size_t>(std::count(text.begin(), text.begin() + nul, '\n'));
    throwAt(vpHSlamException::parseError, path, line, "NUL byte: not a text file");
  }
}

void requireYamlLineShapes(const std::string &text, const std::string &path)
{
  int depth = 0;              // open [ and { not closed yet, over lines
  std::size_t openLine = 0;   // line of the outermost [ or { still open
  std::size_t rootIndent = 0; // indentation of the first key line: no line outside brackets may have less
  std::size_t rootLine = 0;   // its line number, 0 before it
  std::size_t breakLine = 0;  // first document marker after it, 0 before one
  std::size_t lineNumber = 0, begin = 0;
  while (begin < text.size()) {
    std::size_t end = text.find('\n', begin);
    if (end == std::string::npos) {
      end = text.size();
    }
    ++lineNumber;
    const std::string line = text.substr(begin, end - begin);
    begin = end + 1;
    const std::string content = trim(line);
    const bool outside = depth == 0;
    if (outside && (content.empty() || content[0] == '#')) {
      continue; // blank or comment
    }
    // A directive starts at the first column: an indented "%..." line is a key or a scalar (" %: 0" let a second
    // document through as a directive before the first key, and OpenCV hung on it; fuzz_camera_yaml).
    if (outside && line[0] == '%' && rootLine != 0) {
      // Directives come before the document; OpenCV can hang on one after it ("%2 -" after " d: 0"; fuzz_parameters).
      throwAt(vpHSlamException::parseError, path, lineNumber, "a directive after the first key or item");
    }
    if (outside && (line[0] == '%' || content == "---" || content == "...")) {
      breakLine = rootLine != 0 && breakLine == 0 ? lineNumber : breakLine;
      continue; // directive or document marker: no structure
    }
    if (outside && breakLine != 0) {
      // A second document sends OpenCV 4.6's YAML reader into an endless loop when the first one was indented
      // (" d: 0", "---", " - 1"; fuzz_parameters). H-SLAM's files hold one (a marker may end the file).
      throwAt(vpHSlamException::parseError, path, breakLine,
              "a document marker after the first key or item, then more content: one YAML document only");
    }
    if (outside && (startsWith(content, "...") || startsWith(content, "---"))) {
      // A document marker with text after it sends OpenCV 4.6's YAML reader into an endless loop (fuzz_parameters).
      throwAt(vpHSlamException::parseError, path, lineNumber, "'" + content + "': a document marker followed by text");
    }
    // Brackets and the key colon, outside quotes and comments. A [ or { opens a collection only where a value starts
    // (line start, after "key: ", "- ", or [, { and , inside one): elsewhere it is part of a plain scalar ("T[" is
    // text for YAML and OpenCV), and counting it would wave through the lines after it (fuzz_camera_yaml hung so).
    char quote = 0;
    bool keyColon = false;
    bool valueStart = true;
    for (std::size_t i = 0; i < line.size(); ++i) {
      const char c = line[i];
      const bool blankAfter = i + 1 == line.size() || std::isspace(static_cast<unsigned char>(line[i + 1]));
      if (quote != 0) {
        quote = c == quote ? 0 : quote;
      } else if (std::isspace(static_cast<unsigned char>(c))) {
        continue;
      } else if (c == '"' || c == '\'') {
        quote = c;
        valueStart = false;
      } else if (c == '#' && (i == 0 || std::isspace(static_cast<unsigned char>(line[i - 1])))) {
        break;
      } else if ((c == '[' || c == '{') && valueStart) {
        openLine = depth == 0 ? lineNumber : openLine;
        ++depth;
      } else if ((c == ']' || c == '}') && depth > 0) {
        --depth;
        valueStart = false;
      } else if (c == ',' && depth > 0) {
        valueStart = true;
      } else if (c == ':' && blankAfter) {
        keyColon = keyColon || depth == 0;
        valueStart = true;
      } else if (!(c == '-' && valueStart && blankAfter)) { // "- " keeps a value starting
        valueStart = false;
      }
    }
    if (!outside) {
      continue; // inside a flow sequence or map: any continuation
    }
    if (content != "-" && !startsWith(content, "- ") && !keyColon) {
      throwAt(vpHSlamException::parseError, path, lineNumber,
              "'" + content + "' is neither 'key: value' nor '- item' (nor inside [...] or {...})");
    }
    const std::size_t indent = line.find_first_not_of(" \t");
    if (rootLine == 0) {
      rootIndent = indent;
      rootLine = lineNumber;
    } else if (indent < rootIndent) {
      throwAt(vpHSlamException::parseError, path, lineNumber,
              "less indented than the first key (line " + std::to_string(rootLine) + ")");
    }
  }
  if (depth > 0) {
    throwAt(vpHSlamException::parseError, path, openLine, "a [ or { opened on this line is never closed");
  }
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
  return splitTokens(text, kBlank);
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

std::vector<std::string> splitTokens(const std::string &text, const std::string &separators)
{
  std::vector<std::string> tokens;
  std::size_t pos = 0;
  while (pos <= text.size()) {
    const std::size_t next = text.find_first_of(separators, pos);
    std::string token = trim(text.substr(pos, next == std::string::npos ? std::string::npos : next - pos));
    if (!token.empty()) {
      tokens.push_back(std::move(token));
    }
    if (next == std::string::npos) {
      break;
    }
    pos = next + 1;
  }
  return tokens;
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
  // std::from_chars ignores the C locale (a "1,5" locale cannot change how files read) but rejects a leading '+',
  // which some writers emit.
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

bool tryParseInt64(const std::string &token, long long &value)
{
  return parseWholeInteger(token, value);
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
  return parseUnsignedAs<unsigned int>(token, path, line, what);
}

std::uint64_t parseUInt64(const std::string &token, const std::string &path, std::size_t line, const std::string &what)
{
  return parseUnsignedAs<std::uint64_t>(token, path, line, what);
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

void appendNumber(std::string &out, double value, std::chars_format format, int precision)
{
  char buffer[64];
  const std::to_chars_result r = std::to_chars(buffer, buffer + sizeof(buffer), value, format, precision);
  out.append(buffer, r.ptr);
}

void openForWriting(std::ofstream &file, const std::string &path)
{
  file.open(path, std::ios::out | std::ios::trunc);
  if (!file.is_open()) {
    throwAt(vpHSlamException::fileUnreadable, path, 0, "cannot open the file for writing");
  }
}

void flushAndClose(std::ofstream &file, const std::string &path)
{
  file.flush();
  const bool ok = file.good();
  file.close();
  if (!ok || file.fail()) {
    throwAt(vpHSlamException::fileUnreadable, path, 0,
            "writing failed (disk full or I/O error): the file is incomplete");
  }
}
} // namespace hslam
