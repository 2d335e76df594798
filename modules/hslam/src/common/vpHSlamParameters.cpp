/*
 * H-SLAM for ViSP.
 */
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
using Params = vpHSlamParameters;

//! Where one setting lives inside a vpHSlamParameters; the alternative says its type (and so its YAML form).
using FieldRef = std::variant<int *, double *, bool *, std::vector<int> *, Params::Mode *, Params::TrackingMode *>;

constexpr double kInf = std::numeric_limits<double>::infinity();

//! Interval a number (or every element of a vector) must lie in. Bools and modes ignore it.
struct Range {
  double lo;
  double hi;
  bool loOpen;
  bool hiOpen;
};

constexpr Range anyValue()
{
  return {-kInf, kInf, false, false};
}
constexpr Range atLeast(double lo)
{
  return {lo, kInf, false, false};
}
constexpr Range positive()
{
  return {0., kInf, true, false};
}
constexpr Range between(double lo, double hi)
{
  return {lo, hi, false, false};
}
constexpr Range openInterval(double lo, double hi)
{
  return {lo, hi, true, true};
}

//! Address of p.*Section.*Member, for any field type of the table.
template <auto Section, auto Member> FieldRef refOf(Params &p)
{
  return &((p.*Section).*Member);
}

//! One row of the table: everything load, save, print and validate need to know about a setting.
struct Field {
  const char *section; //!< YAML top-level map, also the name of the member of vpHSlamParameters
  const char *key;     //!< YAML key, also the name of the member of the section struct
  FieldRef (*ref)(Params &);
  Range range;
  const char *doc; //!< one line, printed after the value
};

// The section and key strings come from the same tokens as the member pointer, so a row can never read one member
// and save it under another's name.
#define HSLAM_PARAM(section, member, range, doc)                                                                       \
  Field                                                                                                                \
  {                                                                                                                    \
#section, #member, &refOf < &Params::section, &decltype(Params::section)::member>, range, doc                      \
  }

// THE table: one row per field of vpHSlamParameters, in header order. Adding a field = adding one row here.
// clang-format off
const Field kFields[] = {
  HSLAM_PARAM(features, desiredPointDensity, atLeast(1), "target number of active points in the window"),
  HSLAM_PARAM(features, desiredImmatureDensity, atLeast(1), "candidates selected per new keyframe"),
  HSLAM_PARAM(features, selectionBlockSize, atLeast(1), "block side of the adaptive gradient threshold, pixels"),
  HSLAM_PARAM(features, gradientThresholdAdd, atLeast(0.), "threshold = block median |grad| + this, intensity"),
  HSLAM_PARAM(features, gradientThresholdLevelFactor, positive(), "threshold multiplier per coarser level"),
  HSLAM_PARAM(features, selectionLevels, atLeast(1), "pyramid levels used for point selection"),
  HSLAM_PARAM(features, fastThreshold, between(1, 255), "FAST intensity threshold"),
  HSLAM_PARAM(features, maxCorners, atLeast(0), "FAST corners kept per keyframe"),
  HSLAM_PARAM(features, cornerMinDistance, atLeast(0.), "non-maximum suppression radius of corners, pixels"),
  HSLAM_PARAM(features, cornerShare, between(0., 1.), "hybrid: corners added, at most this share of the budget"),

  HSLAM_PARAM(tracker, maxPyramidLevels, atLeast(1), "upper bound on pyramid levels"),
  HSLAM_PARAM(tracker, minCoarsestPixels, atLeast(1), "a level is added only while it keeps this many pixels"),
  HSLAM_PARAM(tracker, huberThreshold, positive(), "Huber threshold on photometric residuals, intensity"),
  HSLAM_PARAM(tracker, gradientWeightC, positive(), "c of the gradient weight c^2/(c^2+|g|^2), intensity"),
  HSLAM_PARAM(tracker, outlierEnergyPerPixel, positive(), "residual^2 above which a pattern pixel is an outlier"),
  HSLAM_PARAM(tracker, iterationsPerLevel, atLeast(0), "Gauss-Newton iterations per level, finest first"),
  HSLAM_PARAM(tracker, retrackResidualFactor, positive(), "try other motions when residual > this * last"),
  HSLAM_PARAM(tracker, affinePriorA, atLeast(0.), "prior weight on a without calibration (0 = free)"),
  HSLAM_PARAM(tracker, affinePriorB, atLeast(0.), "prior weight on b without calibration (0 = free)"),
  HSLAM_PARAM(tracker, affinePriorACalibrated, atLeast(0.), "prior weight on a with photometric calibration"),
  HSLAM_PARAM(tracker, affinePriorBCalibrated, atLeast(0.), "prior weight on b with photometric calibration"),
  HSLAM_PARAM(tracker, maxShiftWeightT, atLeast(0.), "keyframe: translation flow weight, per (w+h)"),
  HSLAM_PARAM(tracker, maxShiftWeightR, atLeast(0.), "keyframe: rotation flow weight, per (w+h)"),
  HSLAM_PARAM(tracker, maxShiftWeightRT, atLeast(0.), "keyframe: rotation+translation flow weight, per (w+h)"),
  HSLAM_PARAM(tracker, maxAffineWeight, atLeast(0.), "keyframe: brightness change weight"),
  HSLAM_PARAM(tracker, keyframeResidualFactor, positive(), "keyframe when RMSE > this * keyframe's first RMSE"),
  HSLAM_PARAM(tracker, maxFramesBetweenKeyframes, atLeast(0), "force a keyframe after this many frames (0 = never)"),
  HSLAM_PARAM(tracker, coarseCutoffResidual, positive(), "coarse tracking: residuals above this are saturated"),

  HSLAM_PARAM(mapper, windowSize, atLeast(2), "keyframes in the window"),
  HSLAM_PARAM(mapper, minWindowSize, atLeast(2), "marginalisation keeps at least this many keyframes"),
  HSLAM_PARAM(mapper, maxOptimizationIterations, atLeast(1), "LM iterations per new keyframe, at most"),
  HSLAM_PARAM(mapper, minOptimizationIterations, atLeast(0), "LM iterations per new keyframe, at least"),
  HSLAM_PARAM(mapper, initialLambda, atLeast(0.), "initial LM damping"),
  HSLAM_PARAM(mapper, stepConvergenceThreshold, atLeast(0.), "stop when the scaled update norm is below this"),
  HSLAM_PARAM(mapper, minPointsFractionKept, between(0., 1.), "marginalise a keyframe keeping fewer of its points"),
  HSLAM_PARAM(mapper, maxAffineChangeMarginalize, positive(), "marginalise when |a_ji| changes beyond this"),
  HSLAM_PARAM(mapper, minIdepthHessianActivate, atLeast(0.), "inverse-depth Hessian needed to keep a new point"),
  HSLAM_PARAM(mapper, minIdepthHessianMarginalize, atLeast(0.), "below: drop a point instead of marginalising"),
  HSLAM_PARAM(mapper, activationMinDistance, atLeast(0.), "initial distance-map radius for activation, pixels"),
  HSLAM_PARAM(mapper, traceMinImprovementFactor, positive(), "DSO setting_trace_minImprovementFactor"),
  HSLAM_PARAM(mapper, traceSlackInterval, atLeast(0.), "epipolar search interval slack, pixels"),
  HSLAM_PARAM(mapper, traceStepSize, positive(), "epipolar search step, pixels"),
  HSLAM_PARAM(mapper, traceGaussNewtonIterations, atLeast(0), "sub-pixel refinement iterations"),
  HSLAM_PARAM(mapper, traceGaussNewtonThreshold, positive(), "stop refinement below this step, pixels"),
  HSLAM_PARAM(mapper, traceExtraSlackOnThreshold, positive(), "outlier threshold slack for tracing"),
  HSLAM_PARAM(mapper, minTraceQuality, positive(), "quality (second best / best) required to activate"),
  HSLAM_PARAM(mapper, maxTraceInterval, positive(), "interval length below which a point may activate, pixels"),
  HSLAM_PARAM(mapper, outlierResidualFraction, between(0., 1.), "remove a point with more outlier residuals"),
  HSLAM_PARAM(mapper, traceMaxPixelSearch, positive(), "longest epipolar segment searched, per (w+h)"),

  HSLAM_PARAM(initializer, minMatches, atLeast(8), "ORB matches needed to attempt a two-view solution"),
  HSLAM_PARAM(initializer, minParallaxDeg, between(0., 90.), "median triangulation angle required, degrees"),
  HSLAM_PARAM(initializer, ransacThresholdPx, positive(), "RANSAC inlier threshold, pixels"),
  HSLAM_PARAM(initializer, ransacConfidence, openInterval(0., 1.), "RANSAC confidence"),
  HSLAM_PARAM(initializer, maxFramesToInitialize, atLeast(1), "restart with a new first frame after this many"),
  HSLAM_PARAM(initializer, initialIdepth, positive(), "median inverse depth of the first map, 1/m"),
  HSLAM_PARAM(initializer, orbFeatures, atLeast(8), "ORB features per frame while initialising"),

  HSLAM_PARAM(tracking, mode, anyValue(), "direct, indirect or hybrid pose tracking"),
  HSLAM_PARAM(tracking, frameFeatures, atLeast(0), "FAST corners described per new frame for matching"),
  HSLAM_PARAM(tracking, frameFastThreshold, between(1, 255), "FAST threshold on new frames"),
  HSLAM_PARAM(tracking, matchRadiusPx, positive(), "ORB search radius around a predicted pixel, pixels"),
  HSLAM_PARAM(tracking, matchMaxDistance, between(0, 256), "Hamming distance accepted at most"),
  HSLAM_PARAM(tracking, matchRatio, openInterval(0., 1.), "best match below this * second best"),
  HSLAM_PARAM(tracking, minMatchesBeforeWidening, atLeast(0), "fewer matches: search again, twice the radius"),
  HSLAM_PARAM(tracking, minGeometricInliers, atLeast(4), "inliers the indirect step needs to give a pose"),
  HSLAM_PARAM(tracking, relocalize, anyValue(), "relocalise in the same map before starting a new segment"),
  HSLAM_PARAM(tracking, relocalizationTimeout, atLeast(0.), "seconds seeing features unplaced before a new segment"),
  HSLAM_PARAM(tracking, relocalizationCandidates, atLeast(1), "keyframes tried per lost frame"),
  HSLAM_PARAM(tracking, relocalizationMinInliers, atLeast(6), "PnP inliers needed to accept a relocalisation"),

  HSLAM_PARAM(globalMap, covisibilityMinShared, atLeast(1), "points shared for a co-visibility edge"),
  HSLAM_PARAM(globalMap, cullObservedShare, between(0., 1.), "culling: share of points seen by enough others"),
  HSLAM_PARAM(globalMap, cullMinObservers, atLeast(1), "culling: other keyframes that must see a point"),
  HSLAM_PARAM(globalMap, reuseRadiusPx, positive(), "search radius of a projected global point, px at 640 wide"),
  HSLAM_PARAM(globalMap, reuseMaxDistance, between(0, 256), "Hamming distance accepted at most for re-use"),
  HSLAM_PARAM(globalMap, reuseRatio, openInterval(0., 1.), "re-use: best match below this * second best"),
  HSLAM_PARAM(globalMap, reuseMaxKeyframes, atLeast(1), "stored keyframes searched per new keyframe"),
  HSLAM_PARAM(globalMap, fusionSigmas, positive(), "late fusion: depths agree within this many sigmas"),
  HSLAM_PARAM(globalMap, reuse, anyValue(), "re-use global points in the window (off: kept, not re-used)"),
  HSLAM_PARAM(globalMap, priorVarianceScale, positive(), "global depth variances times this when re-used"),

  HSLAM_PARAM(loop, consistency, atLeast(1), "consecutive keyframes agreeing on a loop candidate"),
  HSLAM_PARAM(loop, minKeyframesBetween, atLeast(0), "keyframes after the start or the last loop first"),
  HSLAM_PARAM(loop, matchMaxDistance, between(0, 256), "Hamming distance accepted at most for loop matches"),
  HSLAM_PARAM(loop, matchRatio, openInterval(0., 1.), "loop matches: best below this * second best"),
  HSLAM_PARAM(loop, minMatches, atLeast(3), "ORB matches needed to try a Sim(3)"),
  HSLAM_PARAM(loop, minInliers, atLeast(3), "Sim(3) inliers needed to accept a loop"),
  HSLAM_PARAM(loop, ransacThresholdPx, positive(), "Sim(3) inlier reprojection error, pixels"),
  HSLAM_PARAM(loop, maxRotationCorrectionDeg, between(0., 180.), "loops rotating the map more are refused, deg"),

  HSLAM_PARAM(system, mode, anyValue(), "vo-strict, vo-reuse or slam"),
  HSLAM_PARAM(system, deterministic, anyValue(), "map in the caller's thread: identical output run to run"),
  HSLAM_PARAM(system, workerThreads, atLeast(0), "threads for residual accumulation (0 = caller only)"),
  HSLAM_PARAM(system, usePhotometricCalibration, anyValue(), "use G, V, exposure when the source has them"),
  HSLAM_PARAM(system, maxTrackingFailures, atLeast(0), "failed alignments in a row before tracking is lost"),
};
// clang-format on
#undef HSLAM_PARAM

//! Relations between two settings of the table: lower <= upper, both named "section.key".
struct Order {
  const char *lower;
  const char *upper;
};
const Order kOrders[] = {
    {"mapper.minWindowSize", "mapper.windowSize"},
    {"mapper.minOptimizationIterations", "mapper.maxOptimizationIterations"},
};

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
  }
  throw vpHSlamException(vpHSlamException::invalidArgument, "vpHSlamParameters::trackingModeName: unknown value " +
                                                                std::to_string(static_cast<int>(mode)));
}

vpHSlamParameters::TrackingMode vpHSlamParameters::parseTrackingMode(const std::string &name)
{
  for (TrackingMode mode : {trackingDirect, trackingIndirect, trackingHybrid}) {
    if (name == trackingModeName(mode)) {
      return mode;
    }
  }
  throw vpHSlamException(vpHSlamException::invalidArgument, "vpHSlamParameters::parseTrackingMode: unknown mode '" +
                                                                name + "' (expected direct, indirect, hybrid)");
}
