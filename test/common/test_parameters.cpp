// vpHSlamParameters: YAML load/save round trip of every field, errors (unknown key, wrong type, out of range,
// missing or malformed file), partial files, print(), validate(), mode names, and the committed default file.
//
// How a field forgotten in the table is caught: the table in common/ParameterTable.h builds each row's YAML key
// from the same token as its member pointer, so a row cannot read one member and save it under another name; what
// remains possible is a header field WITHOUT a row. The tests therefore take the list of fields from the header
// itself (HeaderFields() parses the struct bodies of vpHSlamParameters.h: every declaration there is a setting
// with a default) and require every one of them in save(), print() and the round trip. A hand-kept key list in
// this file would drift exactly like the table; a sizeof() count breaks on padding and says nothing about names.
#include "HSlamTestData.h"

#include <visp3/hslam/vpHSlamException.h>
#include <visp3/hslam/vpHSlamParameters.h>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>

#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <functional>
#include <limits>
#include <map>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

namespace
{
const std::string kHeaderPath =
    std::string(HSLAM_SOURCE_DIR) + "/modules/hslam/include/visp3/hslam/vpHSlamParameters.h";
const std::string kDefaultYamlPath = std::string(HSLAM_SOURCE_DIR) + "/data/hslam-default.yaml";

std::string readText(const std::string &path)
{
  std::ifstream file(path);
  std::stringstream text;
  text << file.rdbuf();
  return text.str();
}

void writeText(const std::string &path, const std::string &text)
{
  std::ofstream file(path);
  file << text;
}

//! Files the tests wrote; removed when the test program exits so runs leave nothing behind in the temp folder.
struct TempFiles {
  std::vector<std::string> paths;
  ~TempFiles()
  {
    for (const std::string &path : paths) {
      std::remove(path.c_str());
    }
  }
};

//! A file name private to the running test (each TEST is its own ctest process, possibly run in parallel).
std::string tempPath(const std::string &suffix)
{
  static TempFiles written;
  const ::testing::TestInfo *info = ::testing::UnitTest::GetInstance()->current_test_info();
  written.paths.push_back(::testing::TempDir() + "hslam_params_" + info->name() + "_" + suffix);
  return written.paths.back();
}

//! "section.key" of every field declared in the header, in order (see the file comment for why).
std::vector<std::string> HeaderFields()
{
  std::ifstream header(kHeaderPath);
  EXPECT_TRUE(header.good()) << "cannot read " << kHeaderPath;
  const std::regex structBegin(R"(^\s*struct\s+(\w+)\s*\{)");
  const std::regex structEnd(R"(^\s*\};)");
  const std::regex declaration(R"(^\s*[\w:<>,\s]+?\s+(\w+)\s*(=|\{|;))");
  std::vector<std::string> fields;
  std::string section;
  std::string statement;
  std::string line;
  std::smatch match;
  while (std::getline(header, line)) {
    if (section.empty()) {
      if (std::regex_search(line, match, structBegin)) {
        section = match[1].str();
        section[0] = static_cast<char>(std::tolower(section[0]));
      }
      continue;
    }
    if (std::regex_search(line, match, structEnd)) {
      section.clear();
      continue;
    }
    statement += " " + line.substr(0, line.find("//"));
    if (statement.find(';') != std::string::npos) {
      if (std::regex_search(statement, match, declaration)) {
        fields.push_back(section + "." + match[1].str());
      } else {
        ADD_FAILURE() << "cannot read a field name in '" << statement << "' of " << kHeaderPath;
      }
      statement.clear();
    }
  }
  return fields;
}

//! A string node without the end-of-line comment OpenCV's YAML reader keeps inside unquoted strings.
std::string StringValue(const cv::FileNode &node)
{
  const std::string text = static_cast<std::string>(node);
  return text.substr(0, text.find_last_not_of(" ", text.find(" #")) + 1);
}

//! Every "section.key" of a YAML file with its value in a canonical text form, as cv::FileStorage reads it.
std::map<std::string, std::string> Flatten(const std::string &path)
{
  std::map<std::string, std::string> values;
  cv::FileStorage storage(path, cv::FileStorage::READ);
  const cv::FileNode root = storage.root();
  for (cv::FileNodeIterator s = root.begin(); s != root.end(); ++s) {
    const cv::FileNode section = *s;
    for (cv::FileNodeIterator k = section.begin(); k != section.end(); ++k) {
      const cv::FileNode node = *k;
      std::ostringstream text;
      text.precision(17);
      if (node.isInt()) {
        text << "int " << static_cast<int>(node);
      } else if (node.isReal()) {
        text << "real " << static_cast<double>(node);
      } else if (node.isString()) {
        text << "string " << StringValue(node);
      } else if (node.isSeq()) {
        text << "seq";
        for (cv::FileNodeIterator e = node.begin(); e != node.end(); ++e) {
          text << " " << static_cast<int>(*e);
        }
      } else {
        text << "other";
      }
      const std::string name = section.name() + "." + node.name();
      EXPECT_EQ(values.count(name), 0u) << name << " appears twice in " << path;
      values[name] = text.str();
    }
  }
  return values;
}

std::map<std::string, std::string> FlattenParams(const vpHSlamParameters &params, const std::string &suffix)
{
  const std::string path = tempPath(suffix + ".yaml");
  params.save(path);
  return Flatten(path);
}

std::string RealText(double value)
{
  char buffer[64];
  std::snprintf(buffer, sizeof(buffer), "%.17g", value);
  std::string text = buffer;
  return text.find_first_of(".e") == std::string::npos ? text + ".0" : text;
}

/*!
  A YAML file where every value of the saved file \e path is changed while staying valid: integers + 1, reals
  times 0.9 (0 becomes 0.5), booleans flipped, the mode moved to the next one, sequences with every element + 1
  and one more element. Values are only moved a little and upwards for integers because every range of the table is
  a lower bound or an interval containing the change (a new field with a tighter range must keep this true).
*/
std::string PerturbedYaml(const std::string &path)
{
  std::ostringstream out;
  out << "%YAML:1.0\n---\n";
  cv::FileStorage storage(path, cv::FileStorage::READ);
  const cv::FileNode root = storage.root();
  for (cv::FileNodeIterator s = root.begin(); s != root.end(); ++s) {
    const cv::FileNode section = *s;
    out << section.name() << ":\n";
    for (cv::FileNodeIterator k = section.begin(); k != section.end(); ++k) {
      const cv::FileNode node = *k;
      out << "  " << node.name() << ": ";
      if (node.isInt()) {
        out << static_cast<int>(node) + 1;
      } else if (node.isReal()) {
        const double value = static_cast<double>(node);
        out << RealText(value == 0. ? 0.5 : value * 0.9);
      } else if (node.isString() && (StringValue(node) == "true" || StringValue(node) == "false")) {
        out << (StringValue(node) == "true" ? "false" : "true");
      } else if (node.isString() && std::string(section.name()) == "tracking") {
        const int mode = static_cast<int>(vpHSlamParameters::parseTrackingMode(StringValue(node)));
        out << vpHSlamParameters::trackingModeName(static_cast<vpHSlamParameters::TrackingMode>((mode + 1) % 3));
      } else if (node.isString()) {
        const int mode = static_cast<int>(vpHSlamParameters::parseMode(StringValue(node)));
        out << vpHSlamParameters::modeName(static_cast<vpHSlamParameters::Mode>((mode + 1) % 3));
      } else if (node.isSeq()) {
        out << "[";
        for (cv::FileNodeIterator e = node.begin(); e != node.end(); ++e) {
          out << static_cast<int>(*e) + 1 << ", ";
        }
        out << "1]";
      } else {
        ADD_FAILURE() << "unexpected node type for " << node.name();
      }
      out << "\n";
    }
  }
  return out.str();
}

//! Runs \e action, expects a vpHSlamException with \e code whose message contains every string of \e parts.
void ExpectError(const std::function<void()> &action, vpHSlamException::ErrorCode code,
                 const std::vector<std::string> &parts)
{
  try {
    action();
    ADD_FAILURE() << "no exception, expected code " << code;
  } catch (const vpHSlamException &e) {
    EXPECT_EQ(e.getCode(), code) << e.getStringMessage();
    for (const std::string &part : parts) {
      EXPECT_NE(e.getStringMessage().find(part), std::string::npos)
          << "message '" << e.getStringMessage() << "' does not name '" << part << "'";
    }
  }
}

//! Loads a YAML body (the %YAML line is added) and expects an error; the parameters must be left unchanged.
void ExpectLoadError(const std::string &body, vpHSlamException::ErrorCode code, const std::vector<std::string> &parts)
{
  static int counter = 0;
  const std::string path = tempPath("bad" + std::to_string(counter++) + ".yaml");
  writeText(path, "%YAML:1.0\n---\n" + body);
  vpHSlamParameters params;
  std::vector<std::string> expected = parts;
  expected.push_back(path);
  ExpectError([&] { params.load(path); }, code, expected);
  EXPECT_EQ(FlattenParams(params, "after_error"), FlattenParams(vpHSlamParameters(), "defaults")) << body;
}
} // namespace

TEST(Parameters, DefaultsAreValid)
{
  const vpHSlamParameters params;
  EXPECT_NO_THROW(params.validate());
  EXPECT_EQ(params.mapper.windowSize, 6);
  EXPECT_EQ(params.system.mode, vpHSlamParameters::modeSlam);
}

TEST(Parameters, SaveHasExactlyTheHeaderFields)
{
  const std::vector<std::string> header = HeaderFields();
  // Sanity of the header reader itself (57 fields when this test was written; fields are only ever added).
  ASSERT_GE(header.size(), 57u) << "the header reader found too few fields: did the header layout change?";
  const std::map<std::string, std::string> saved = FlattenParams(vpHSlamParameters(), "saved");
  std::set<std::string> headerSet(header.begin(), header.end());
  EXPECT_EQ(headerSet.size(), header.size());
  for (const std::string &name : header) {
    EXPECT_EQ(saved.count(name), 1u) << name << " is declared in the header but missing from the table";
  }
  for (const auto &entry : saved) {
    EXPECT_EQ(headerSet.count(entry.first), 1u) << entry.first << " is saved but not declared in the header";
  }
  EXPECT_EQ(saved.size(), header.size());
}

TEST(Parameters, RoundTripChangesEveryField)
{
  const std::string defaultsPath = tempPath("defaults.yaml");
  vpHSlamParameters().save(defaultsPath);
  const std::string perturbedPath = tempPath("perturbed.yaml");
  writeText(perturbedPath, PerturbedYaml(defaultsPath));

  vpHSlamParameters params;
  ASSERT_NO_THROW(params.load(perturbedPath));
  const std::map<std::string, std::string> defaults = Flatten(defaultsPath);
  const std::map<std::string, std::string> perturbed = Flatten(perturbedPath);
  const std::map<std::string, std::string> reloaded = FlattenParams(params, "reloaded");
  ASSERT_EQ(perturbed.size(), defaults.size());
  for (const std::string &name : HeaderFields()) {
    ASSERT_EQ(perturbed.count(name), 1u) << name;
    EXPECT_NE(perturbed.at(name), defaults.at(name)) << name << " was not changed by the test";
    EXPECT_EQ(reloaded.at(name), perturbed.at(name)) << name << " did not survive load() then save()";
  }
  // The YAML keys reach the C++ members, one per value type.
  EXPECT_EQ(params.mapper.windowSize, 7);
  EXPECT_DOUBLE_EQ(params.tracker.huberThreshold, 9. * 0.9);
  EXPECT_EQ(params.tracker.iterationsPerLevel, (std::vector<int>{11, 21, 51, 51, 51, 1}));
  EXPECT_TRUE(params.system.deterministic);
  EXPECT_FALSE(params.system.usePhotometricCalibration);
  EXPECT_EQ(params.system.mode, vpHSlamParameters::modeVoStrict);
  EXPECT_DOUBLE_EQ(params.tracker.affinePriorA, 0.5);
  EXPECT_DOUBLE_EQ(params.initializer.ransacConfidence, 0.999 * 0.9);
}

TEST(Parameters, PartialFileKeepsDefaults)
{
  const std::string path = tempPath("partial.yaml");
  // An integer for a real and 1 for a bool are accepted (cv::FileStorage writes a C++ bool as 1).
  writeText(path, "%YAML:1.0\n---\nmapper:\n  windowSize: 9\ntracker:\n  huberThreshold: 7\n"
                  "system:\n  mode: vo-reuse\n  deterministic: 1\n# a comment\n");
  vpHSlamParameters params;
  params.load(path);
  EXPECT_EQ(params.mapper.windowSize, 9);
  EXPECT_DOUBLE_EQ(params.tracker.huberThreshold, 7.);
  EXPECT_EQ(params.system.mode, vpHSlamParameters::modeVoReuse);
  EXPECT_TRUE(params.system.deterministic);

  std::map<std::string, std::string> loaded = FlattenParams(params, "loaded");
  std::map<std::string, std::string> defaults = FlattenParams(vpHSlamParameters(), "defaults");
  for (const char *changed : {"mapper.windowSize", "tracker.huberThreshold", "system.mode", "system.deterministic"}) {
    EXPECT_NE(loaded.at(changed), defaults.at(changed)) << changed;
    loaded.erase(changed);
    defaults.erase(changed);
  }
  EXPECT_EQ(loaded, defaults);

  // A file with the YAML directive only changes nothing.
  writeText(path, "%YAML:1.0\n");
  vpHSlamParameters untouched;
  untouched.load(path);
  EXPECT_EQ(FlattenParams(untouched, "untouched"), FlattenParams(vpHSlamParameters(), "defaults"));
}

TEST(Parameters, UnknownKeyIsParseError)
{
  ExpectLoadError("mapper:\n  windowSise: 6\n", vpHSlamException::parseError, {"mapper", "windowSise"});
  ExpectLoadError("mapping:\n  windowSize: 6\n", vpHSlamException::parseError, {"mapping"});
  ExpectLoadError("mapper:\n  windowSize: 6\n  windowSize: 7\n", vpHSlamException::parseError,
                  {"mapper.windowSize", "twice"});
}

TEST(Parameters, WrongTypeIsParseError)
{
  ExpectLoadError("mapper:\n  windowSize: 6.5\n", vpHSlamException::parseError, {"mapper.windowSize"});
  ExpectLoadError("tracker:\n  huberThreshold: nine\n", vpHSlamException::parseError, {"tracker.huberThreshold"});
  ExpectLoadError("system:\n  deterministic: maybe\n", vpHSlamException::parseError, {"system.deterministic"});
  ExpectLoadError("system:\n  deterministic: 2\n", vpHSlamException::parseError, {"system.deterministic"});
  ExpectLoadError("system:\n  mode: 2\n", vpHSlamException::parseError, {"system.mode"});
  ExpectLoadError("tracker:\n  iterationsPerLevel: 5\n", vpHSlamException::parseError, {"tracker.iterationsPerLevel"});
  ExpectLoadError("tracker:\n  iterationsPerLevel: [1, x]\n", vpHSlamException::parseError,
                  {"tracker.iterationsPerLevel"});
  ExpectLoadError("mapper: 5\n", vpHSlamException::parseError, {"mapper"});
}

TEST(Parameters, OutOfRangeIsInvalidArgument)
{
  ExpectLoadError("mapper:\n  windowSize: 1\n", vpHSlamException::invalidArgument, {"mapper.windowSize"});
  ExpectLoadError("mapper:\n  minWindowSize: 8\n", vpHSlamException::invalidArgument,
                  {"mapper.minWindowSize", "mapper.windowSize"});
  ExpectLoadError("tracker:\n  huberThreshold: 0\n", vpHSlamException::invalidArgument, {"tracker.huberThreshold"});
  ExpectLoadError("tracker:\n  gradientWeightC: -3.\n", vpHSlamException::invalidArgument, {"tracker.gradientWeightC"});
  ExpectLoadError("initializer:\n  ransacConfidence: 1.0\n", vpHSlamException::invalidArgument,
                  {"initializer.ransacConfidence"});
  ExpectLoadError("tracker:\n  iterationsPerLevel: []\n", vpHSlamException::invalidArgument,
                  {"tracker.iterationsPerLevel"});
  ExpectLoadError("tracker:\n  iterationsPerLevel: [10, -1]\n", vpHSlamException::invalidArgument,
                  {"tracker.iterationsPerLevel"});
  ExpectLoadError("system:\n  mode: fast\n", vpHSlamException::invalidArgument, {"system.mode", "fast"});

  // validate() on values set in code.
  vpHSlamParameters params;
  params.mapper.windowSize = 1;
  ExpectError([&] { params.validate(); }, vpHSlamException::invalidArgument, {"mapper.windowSize"});
  params = vpHSlamParameters();
  params.tracker.gradientWeightC = std::numeric_limits<double>::quiet_NaN();
  ExpectError([&] { params.validate(); }, vpHSlamException::invalidArgument, {"tracker.gradientWeightC"});
  params = vpHSlamParameters();
  params.mapper.minOptimizationIterations = 10;
  ExpectError([&] { params.validate(); }, vpHSlamException::invalidArgument,
              {"mapper.minOptimizationIterations", "mapper.maxOptimizationIterations"});
}

TEST(Parameters, MissingOrMalformedFile)
{
  vpHSlamParameters params;
  const std::string missing = tempPath("does-not-exist.yaml");
  ExpectError([&] { params.load(missing); }, vpHSlamException::fileNotFound, {missing});

  const std::string noDirective = tempPath("no-directive.yaml");
  writeText(noDirective, "mapper:\n  windowSize: 6\n");
  ExpectError([&] { params.load(noDirective); }, vpHSlamException::parseError, {noDirective, "%YAML"});

  const std::string empty = tempPath("empty.yaml");
  writeText(empty, "");
  ExpectError([&] { params.load(empty); }, vpHSlamException::parseError, {empty});

  const std::string broken = tempPath("broken.yaml");
  writeText(broken, "%YAML:1.0\n---\ntracker:\n  iterationsPerLevel: [1, \n");
  ExpectError([&] { params.load(broken); }, vpHSlamException::parseError, {broken});

  const std::string unwritable = tempPath("no-such-folder") + "/settings.yaml";
  ExpectError([&] { params.save(unwritable); }, vpHSlamException::fileUnreadable, {unwritable});
}

TEST(Parameters, PrintShowsEveryKeyAlignedWithSavedValueAndDoc)
{
  vpHSlamParameters params;
  params.tracker.huberThreshold = 0.04; // a value whose text form matters: shortest exact form in both outputs
  std::ostringstream printed;
  params.print(printed);
  const std::string savedPath = tempPath("saved.yaml");
  params.save(savedPath);

  // "  key: value" lines of the saved file (docs are on comment lines of their own), by key within the section.
  std::map<std::string, std::string> savedText;
  std::istringstream saved(readText(savedPath));
  std::string line;
  std::string section;
  const std::regex sectionLine(R"(^(\w+):\s*$)");
  const std::regex keyLine(R"(^\s+(\w+):\s+(.*?)\s*$)");
  std::smatch match;
  while (std::getline(saved, line)) {
    if (std::regex_match(line, match, sectionLine)) {
      section = match[1].str();
    } else if (std::regex_match(line, match, keyLine)) {
      savedText[section + "." + match[1].str()] = match[2].str();
    }
  }

  std::map<std::string, int> seen;
  std::istringstream lines(printed.str());
  const std::regex printLine(R"(^(\S+)\s+= (.*?)\s+# (.+)$)");
  std::size_t equalsColumn = std::string::npos;
  std::size_t hashColumn = std::string::npos;
  while (std::getline(lines, line)) {
    ASSERT_TRUE(std::regex_match(line, match, printLine)) << "badly formed line: '" << line << "'";
    const std::string name = match[1].str();
    ++seen[name];
    EXPECT_EQ(match[2].str(), savedText[name]) << name << ": print() and save() disagree";
    if (equalsColumn == std::string::npos) {
      equalsColumn = line.find(" = ");
      hashColumn = line.find("  # ");
    }
    EXPECT_EQ(line.find(" = "), equalsColumn) << "'=' not aligned: '" << line << "'";
    EXPECT_EQ(line.find("  # "), hashColumn) << "'#' not aligned: '" << line << "'";
  }
  EXPECT_EQ(savedText["tracker.huberThreshold"], "0.04");
  const std::vector<std::string> header = HeaderFields();
  EXPECT_EQ(seen.size(), header.size());
  for (const std::string &name : header) {
    EXPECT_EQ(seen[name], 1) << name << " should be printed exactly once";
  }
}

TEST(Parameters, ModeNames)
{
  for (vpHSlamParameters::Mode mode :
       {vpHSlamParameters::modeVoStrict, vpHSlamParameters::modeVoReuse, vpHSlamParameters::modeSlam}) {
    EXPECT_EQ(vpHSlamParameters::parseMode(vpHSlamParameters::modeName(mode)), mode);
  }
  EXPECT_EQ(vpHSlamParameters::modeName(vpHSlamParameters::modeVoStrict), "vo-strict");
  EXPECT_EQ(vpHSlamParameters::modeName(vpHSlamParameters::modeVoReuse), "vo-reuse");
  EXPECT_EQ(vpHSlamParameters::modeName(vpHSlamParameters::modeSlam), "slam");
  ExpectError([] { vpHSlamParameters::parseMode("SLAM"); }, vpHSlamException::invalidArgument, {"SLAM"});
  for (vpHSlamParameters::TrackingMode mode :
       {vpHSlamParameters::trackingDirect, vpHSlamParameters::trackingIndirect, vpHSlamParameters::trackingHybrid,
        vpHSlamParameters::trackingAdaptive}) {
    EXPECT_EQ(vpHSlamParameters::parseTrackingMode(vpHSlamParameters::trackingModeName(mode)), mode);
  }
  EXPECT_EQ(vpHSlamParameters::trackingModeName(vpHSlamParameters::trackingHybrid), "hybrid");
  EXPECT_EQ(vpHSlamParameters::trackingModeName(vpHSlamParameters::trackingAdaptive), "adaptive");
  EXPECT_EQ(vpHSlamParameters().tracking.mode, vpHSlamParameters::trackingAdaptive);
  ExpectError([] { vpHSlamParameters::parseTrackingMode("dso"); }, vpHSlamException::invalidArgument, {"dso"});
}

// data/hslam-default.yaml is the documented default configuration. It must be exactly what save() writes for the
// defaults, so the file and the code cannot drift. After changing a field or its doc, regenerate it with
//   HSLAM_REGENERATE_DEFAULT_YAML=1 ctest -R DefaultYamlMatchesDefaults
TEST(Parameters, DefaultYamlMatchesDefaults)
{
  const char *regenerate = std::getenv("HSLAM_REGENERATE_DEFAULT_YAML");
  if (regenerate && *regenerate) {
    vpHSlamParameters().save(kDefaultYamlPath);
  }
  ASSERT_TRUE(hslam_test::pathExists(kDefaultYamlPath)) << kDefaultYamlPath;

  // Loading it over parameters where every value differs must give back every default.
  const std::string defaultsPath = tempPath("defaults.yaml");
  vpHSlamParameters().save(defaultsPath);
  const std::string perturbedPath = tempPath("perturbed.yaml");
  writeText(perturbedPath, PerturbedYaml(defaultsPath));
  vpHSlamParameters params;
  params.load(perturbedPath);
  params.load(kDefaultYamlPath);
  EXPECT_EQ(FlattenParams(params, "loaded"), Flatten(defaultsPath));

  EXPECT_EQ(readText(kDefaultYamlPath), readText(defaultsPath))
      << kDefaultYamlPath << " is out of date: regenerate it with HSLAM_REGENERATE_DEFAULT_YAML=1 ctest -R "
      << "DefaultYamlMatchesDefaults";
}
