/*
 * H-SLAM for ViSP.
 */
#include "common/ParameterTable.h"
#include "common/TextParsing.h"

#include <visp3/hslam/vpHSlamException.h>
#include <visp3/hslam/vpHSlamParameters.h>

#include <opencv2/core.hpp>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <fstream>
#include <iterator>
#include <limits>
#include <ostream>
#include <set>
#include <sstream>
#include <string>
#include <variant>
#include <vector>

namespace hslam
{
namespace
{
using namespace parameter_table;

std::string fullName(const Field &field)
{
  return std::string(field.section) + "." + field.key;
}

//! Read-only view of a field; the table's accessors are written once, for non-const objects.
FieldRef refIn(const Params &params, const Field &field)
{
  return field.ref(const_cast<Params &>(params));
}

//! Shortest text that reads back to exactly \e value (std::to_chars), always with a '.' or exponent so YAML
//! readers keep it a real number.
std::string formatReal(double value)
{
  char buffer[64];
  const std::to_chars_result result = std::to_chars(buffer, buffer + sizeof(buffer), value);
  std::string text(buffer, result.ptr);
  if (text.find_first_of(".eEn") == std::string::npos) {
    text += ".0";
  }
  return text;
}

//! The value as written in YAML and by print().
std::string formatValue(const FieldRef &ref)
{
  struct Formatter {
    std::string operator()(const int *v) const { return std::to_string(*v); }
    std::string operator()(const double *v) const { return formatReal(*v); }
    std::string operator()(const bool *v) const { return *v ? "true" : "false"; }
    std::string operator()(const Params::Mode *v) const { return Params::modeName(*v); }
    std::string operator()(const Params::TrackingMode *v) const { return Params::trackingModeName(*v); }
    std::string operator()(const std::vector<int> *v) const
    {
      std::string text = "[";
      for (std::size_t i = 0; i < v->size(); ++i) {
        text += (i == 0 ? " " : ", ") + std::to_string((*v)[i]);
      }
      return text + " ]";
    }
  };
  return std::visit(Formatter(), ref);
}

//! The range as a reader would write it: ">= 2", "> 0", "[0, 1]", "(0, 1)", "any".
std::string describeRange(const Range &range)
{
  const auto number = [](double value) {
    char buffer[64];
    return std::string(buffer, std::to_chars(buffer, buffer + sizeof(buffer), value).ptr);
  };
  if (std::isinf(range.hi)) {
    return std::isinf(range.lo) ? std::string("any") : (range.loOpen ? "> " : ">= ") + number(range.lo);
  }
  return (range.loOpen ? "(" : "[") + number(range.lo) + ", " + number(range.hi) + (range.hiOpen ? ")" : "]");
}

bool inRange(double value, const Range &range)
{
  if (!std::isfinite(value)) {
    return false;
  }
  const bool aboveLo = range.loOpen ? value > range.lo : value >= range.lo;
  const bool belowHi = range.hiOpen ? value < range.hi : value <= range.hi;
  return aboveLo && belowHi;
}

//! Throws invalidArgument "<where>section.key = value is out of range ..." when the value breaks its row's range.
void checkRange(const Params &params, const Field &field, const std::string &where)
{
  const FieldRef ref = refIn(params, field);
  bool ok = true;
  const std::string range = describeRange(field.range);
  const std::string requirement = (range[0] == '[' || range[0] == '(' ? "in " : "") + range;
  std::string rule = "must be " + requirement;
  if (int *const *i = std::get_if<int *>(&ref)) {
    ok = inRange(**i, field.range);
  } else if (double *const *d = std::get_if<double *>(&ref)) {
    ok = inRange(**d, field.range);
  } else if (std::vector<int> *const *v = std::get_if<std::vector<int> *>(&ref)) {
    const std::vector<int> &values = **v;
    ok = !values.empty() && std::all_of(values.begin(), values.end(), [&](int e) { return inRange(e, field.range); });
    rule = "must be non-empty with every element " + requirement;
  }
  if (!ok) {
    throw vpHSlamException(vpHSlamException::invalidArgument,
                           where + fullName(field) + " = " + formatValue(ref) + " is out of range: it " + rule);
  }
}

const Field *findField(const std::string &section, const std::string &key)
{
  for (const Field &field : kFields) {
    if (section == field.section && key == field.key) {
      return &field;
    }
  }
  return nullptr;
}

double numericValue(const Params &params, const std::string &name)
{
  const std::size_t dot = name.find('.');
  const Field *field = findField(name.substr(0, dot), name.substr(dot + 1));
  if (field) {
    const FieldRef ref = refIn(params, *field);
    if (int *const *i = std::get_if<int *>(&ref)) {
      return **i;
    }
    if (double *const *d = std::get_if<double *>(&ref)) {
      return **d;
    }
  }
  // Only reachable when kOrders names a field that is not a number of the table: a programming error.
  throw vpHSlamException(vpHSlamException::invalidArgument,
                         "vpHSlamParameters: internal ordering rule names '" + name + "', not a numeric setting");
}

//! Ranges of every row then the ordering rules; \e where prefixes messages (e.g. the file being loaded).
void checkAll(const Params &params, const std::string &where)
{
  for (const Field &field : kFields) {
    checkRange(params, field, where);
  }
  for (const Order &order : kOrders) {
    const double lower = numericValue(params, order.lower);
    const double upper = numericValue(params, order.upper);
    if (lower > upper) {
      throw vpHSlamException(vpHSlamException::invalidArgument, where + order.lower + " = " + formatReal(lower) +
                                                                    " must not exceed " + order.upper + " = " +
                                                                    formatReal(upper));
    }
  }
}

//! "; valid: ..." for the documentation line of a numeric field in save(), ordering rules included.
std::string validityNote(const Field &field, const FieldRef &ref)
{
  if (std::holds_alternative<bool *>(ref) || std::holds_alternative<Params::Mode *>(ref) ||
      std::holds_alternative<Params::TrackingMode *>(ref)) {
    return std::string();
  }
  std::string note = "; valid: ";
  note += std::holds_alternative<std::vector<int> *>(ref) ? "non-empty, each " : "";
  note += describeRange(field.range);
  for (const Order &order : kOrders) {
    if (fullName(field) == order.lower) {
      note += std::string(", <= ") + order.upper;
    } else if (fullName(field) == order.upper) {
      note += std::string(", >= ") + order.lower;
    }
  }
  return note;
}

//! Section names in table order, each once.
std::vector<std::string> sectionNames()
{
  std::vector<std::string> names;
  for (const Field &field : kFields) {
    if (std::find(names.begin(), names.end(), field.section) == names.end()) {
      names.emplace_back(field.section);
    }
  }
  return names;
}

std::string joined(const std::vector<std::string> &names)
{
  std::string text;
  for (const std::string &name : names) {
    text += (text.empty() ? "" : ", ") + name;
  }
  return text;
}

//! Text of a string node. OpenCV's YAML reader keeps an end-of-line comment inside an unquoted string
//! ("slam  # note" reads as that whole text), so everything from a '#' after a blank is dropped: no value of the
//! table (true, false, mode names) contains '#'.
std::string nodeText(const cv::FileNode &node)
{
  std::string text = static_cast<std::string>(node);
  for (std::size_t hash = text.find('#'); hash != std::string::npos; hash = text.find('#', hash + 1)) {
    if (hash > 0 && (text[hash - 1] == ' ' || text[hash - 1] == '\t')) {
      text.erase(hash);
      break;
    }
  }
  text.erase(text.find_last_not_of(" \t") + 1);
  return text;
}

//! Store a YAML node into a field; parseError naming \e where and the key when the node has the wrong type.
void readNode(const cv::FileNode &node, const Field &field, Params &params, const std::string &where)
{
  const std::string prefix = where + fullName(field) + ": ";
  const FieldRef ref = field.ref(params);
  if (int *const *i = std::get_if<int *>(&ref)) {
    if (!node.isInt()) {
      throw vpHSlamException(vpHSlamException::parseError, prefix + "expected an integer");
    }
    **i = static_cast<int>(node);
  } else if (double *const *d = std::get_if<double *>(&ref)) {
    if (!node.isInt() && !node.isReal()) {
      throw vpHSlamException(vpHSlamException::parseError, prefix + "expected a number");
    }
    **d = static_cast<double>(node);
  } else if (bool *const *b = std::get_if<bool *>(&ref)) {
    // "true"/"false" as save() writes them; 0/1 as cv::FileStorage writes a C++ bool.
    const std::string text = node.isString() ? nodeText(node) : std::string();
    const int number = node.isInt() ? static_cast<int>(node) : -1;
    if (text != "true" && text != "false" && number != 0 && number != 1) {
      throw vpHSlamException(vpHSlamException::parseError, prefix + "expected true or false");
    }
    **b = text == "true" || number == 1;
  } else if (std::vector<int> *const *v = std::get_if<std::vector<int> *>(&ref)) {
    if (!node.isSeq()) {
      throw vpHSlamException(vpHSlamException::parseError, prefix + "expected a sequence of integers, [ 1, 2 ]");
    }
    std::vector<int> values;
    for (cv::FileNodeIterator it = node.begin(); it != node.end(); ++it) {
      if (!(*it).isInt()) {
        throw vpHSlamException(vpHSlamException::parseError, prefix + "every element must be an integer");
      }
      values.push_back(static_cast<int>(*it));
    }
    **v = values;
  } else if (Params::Mode *const *m = std::get_if<Params::Mode *>(&ref)) {
    if (!node.isString()) {
      throw vpHSlamException(vpHSlamException::parseError, prefix + "expected a mode name");
    }
    try {
      **m = Params::parseMode(nodeText(node));
    } catch (const vpHSlamException &e) {
      throw vpHSlamException(vpHSlamException::invalidArgument, prefix + e.getStringMessage());
    }
  } else if (Params::TrackingMode *const *t = std::get_if<Params::TrackingMode *>(&ref)) {
    if (!node.isString()) {
      throw vpHSlamException(vpHSlamException::parseError, prefix + "expected a tracking mode name");
    }
    try {
      **t = Params::parseTrackingMode(nodeText(node));
    } catch (const vpHSlamException &e) {
      throw vpHSlamException(vpHSlamException::invalidArgument, prefix + e.getStringMessage());
    }
  }
}

//! Every section and key of \e root into \e params; unknown or repeated names are parse errors.
void readRoot(const cv::FileNode &root, Params &params, const std::string &where)
{
  if (root.isNone() || root.empty()) {
    return; // a file holding only the %YAML line: nothing to change
  }
  if (!root.isMap()) {
    throw vpHSlamException(vpHSlamException::parseError, where + "the top level must be a map of sections");
  }
  const std::vector<std::string> sections = sectionNames();
  std::set<std::string> seen;
  for (cv::FileNodeIterator s = root.begin(); s != root.end(); ++s) {
    const cv::FileNode section = *s;
    const std::string name = section.name();
    if (std::find(sections.begin(), sections.end(), name) == sections.end()) {
      throw vpHSlamException(vpHSlamException::parseError,
                             where + "unknown section '" + name + "' (expected one of " + joined(sections) + ")");
    }
    if (!seen.insert(name).second) {
      throw vpHSlamException(vpHSlamException::parseError, where + "section '" + name + "' appears twice");
    }
    if (!section.isMap()) {
      throw vpHSlamException(vpHSlamException::parseError, where + "section '" + name + "' must be a map of keys");
    }
    for (cv::FileNodeIterator k = section.begin(); k != section.end(); ++k) {
      const cv::FileNode node = *k;
      const Field *field = findField(name, node.name());
      if (!field) {
        throw vpHSlamException(vpHSlamException::parseError,
                               where + "unknown key '" + node.name() + "' in section '" + name + "'");
      }
      if (!seen.insert(fullName(*field)).second) {
        throw vpHSlamException(vpHSlamException::parseError, where + "key '" + fullName(*field) + "' appears twice");
      }
      readNode(node, *field, params, where);
    }
  }
}
} // namespace
} // namespace hslam

void vpHSlamParameters::load(const std::string &path)
{
  const std::string where = "vpHSlamParameters::load: " + path + ": ";
  std::ifstream probe(path);
  if (!probe) {
    throw vpHSlamException(vpHSlamException::fileNotFound, where + "settings file not found or not readable");
  }
  // cv::FileStorage rejects a YAML file without its directive with an obscure message; say what is expected.
  std::string firstLine;
  if (!std::getline(probe, firstLine) || firstLine.compare(0, 5, "%YAML") != 0) {
    throw vpHSlamException(vpHSlamException::parseError,
                           where + "line 1 must be the YAML directive '%YAML:1.0' (OpenCV FileStorage format)");
  }
  const std::string text = hslam::readTextFile(path, "settings file");
  hslam::requireNoNulByte(text, path);
  hslam::requireYamlLineShapes(text, path); // before OpenCV's reader, which can hang on other lines
  cv::FileStorage storage;
  try {
    storage.open(path, cv::FileStorage::READ | cv::FileStorage::FORMAT_YAML);
  } catch (const cv::Exception &e) {
    throw vpHSlamException(vpHSlamException::parseError, where + "malformed YAML: " + e.err);
  } catch (const std::exception &e) {
    // OpenCV's YAML reader lets standard exceptions out on some malformed input (std::length_error).
    throw vpHSlamException(vpHSlamException::parseError, where + "malformed YAML (" + e.what() + ")");
  }
  if (!storage.isOpened()) {
    throw vpHSlamException(vpHSlamException::fileUnreadable, where + "cannot be opened as YAML");
  }
  // Parse into a copy and validate it whole: on any error *this is left as it was.
  vpHSlamParameters loaded = *this;
  hslam::readRoot(storage.root(), loaded, where);
  hslam::checkAll(loaded, where);
  *this = loaded;
}

void vpHSlamParameters::save(const std::string &path) const
{
  // Written as text rather than through cv::FileStorage, which prints reals as "4.0000000000000001e-02": this keeps
  // the file readable (shortest exact numbers) and cv::FileStorage still reads it. Each doc stands on its own line
  // above its key because OpenCV's reader keeps an end-of-line comment inside an unquoted word (true, vo-strict).
  std::ostringstream text;
  text << "%YAML:1.0\n---\n"
       << "# H-SLAM settings (vpHSlamParameters::save). A file may hold any subset of these keys; the others keep\n"
       << "# their defaults. Unknown keys are errors. Put comments on their own line, not after a value.\n";
  for (const std::string &section : hslam::sectionNames()) {
    text << "\n" << section << ":\n";
    for (const hslam::Field &field : hslam::kFields) {
      if (section != field.section) {
        continue;
      }
      const hslam::FieldRef ref = hslam::refIn(*this, field);
      text << "  # " << field.doc << hslam::validityNote(field, ref) << "\n  " << field.key << ": "
           << hslam::formatValue(ref) << "\n";
    }
  }
  std::ofstream file(path, std::ios::out | std::ios::trunc);
  file << text.str();
  file.close();
  if (!file) {
    throw vpHSlamException(vpHSlamException::fileUnreadable,
                           "vpHSlamParameters::save: " + path + ": cannot be written");
  }
}

void vpHSlamParameters::print(std::ostream &os) const
{
  std::size_t nameWidth = 0;
  std::size_t valueWidth = 0;
  for (const hslam::Field &field : hslam::kFields) {
    nameWidth = std::max(nameWidth, hslam::fullName(field).size());
    valueWidth = std::max(valueWidth, hslam::formatValue(hslam::refIn(*this, field)).size());
  }
  for (const hslam::Field &field : hslam::kFields) {
    const std::string name = hslam::fullName(field);
    const std::string value = hslam::formatValue(hslam::refIn(*this, field));
    os << name << std::string(nameWidth - name.size(), ' ') << " = " << value
       << std::string(valueWidth - value.size(), ' ') << "  # " << field.doc << "\n";
  }
}

void vpHSlamParameters::validate() const
{
  hslam::checkAll(*this, "vpHSlamParameters: ");
}

std::string vpHSlamParameters::modeName(Mode mode)
{
  switch (mode) {
  case modeVoStrict:
    return "vo-strict";
  case modeVoReuse:
    return "vo-reuse";
  case modeSlam:
    return "slam";
  }
  throw vpHSlamException(vpHSlamException::invalidArgument,
                         "vpHSlamParameters::modeName: unknown mode value " + std::to_string(static_cast<int>(mode)));
}

vpHSlamParameters::Mode vpHSlamParameters::parseMode(const std::string &name)
{
  for (Mode mode : {modeVoStrict, modeVoReuse, modeSlam}) {
    if (name == modeName(mode)) {
      return mode;
    }
  }
  throw vpHSlamException(vpHSlamException::invalidArgument, "vpHSlamParameters::parseMode: unknown mode '" + name +
                                                                "' (expected vo-strict, vo-reuse, slam)");
}

std::string vpHSlamParameters::trackingModeName(TrackingMode mode)
{
  switch (mode) {
  case trackingDirect:
    return "direct";
  case trackingIndirect:
    return "indirect";
  case trackingHybrid:
    return "hybrid";
  case trackingAdaptive:
    return "adaptive";
  }
  throw vpHSlamException(vpHSlamException::invalidArgument, "vpHSlamParameters::trackingModeName: unknown value " +
                                                                std::to_string(static_cast<int>(mode)));
}

vpHSlamParameters::TrackingMode vpHSlamParameters::parseTrackingMode(const std::string &name)
{
  for (TrackingMode mode : {trackingDirect, trackingIndirect, trackingHybrid, trackingAdaptive}) {
    if (name == trackingModeName(mode)) {
      return mode;
    }
  }
  throw vpHSlamException(vpHSlamException::invalidArgument, "vpHSlamParameters::parseTrackingMode: unknown mode '" +
                                                                name +
                                                                "' (expected direct, indirect, hybrid, adaptive)");
}
