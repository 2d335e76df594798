#include <visp3/hslam/vpHSlamTag.h>

#include "common/TextParsing.h"

#include <visp3/hslam/vpHSlamException.h>

#include <algorithm>
#include <cmath>
#include <sstream>

namespace
{
const char *const kFamilies[] = {"tag36h11", "tag25h9", "tag16h5", "tagCircle21h7"};

std::string knownFamilies()
{
  std::string text;
  for (const char *f : kFamilies) {
    text += (text.empty() ? "" : ", ") + std::string(f);
  }
  return text;
}
} // namespace

vpHSlamTag::vpHSlamTag() = default;

vpHSlamTag::vpHSlamTag(const std::string &family, double size, int id) : m_family(family), m_size(size), m_id(id)
{
  const std::vector<std::string> names = familyNames();
  if (std::find(names.begin(), names.end(), family) == names.end()) {
    throw vpHSlamException(vpHSlamException::invalidArgument,
                           "tag: unknown family '" + family + "' (known: " + knownFamilies() + ")");
  }
  if (!(size > 0.) || !std::isfinite(size)) {
    std::ostringstream os;
    os << "tag: the size must be a positive number of metres (the side of the black square), not " << size;
    throw vpHSlamException(vpHSlamException::invalidArgument, os.str());
  }
  if (id < -1) {
    throw vpHSlamException(vpHSlamException::invalidArgument,
                           "tag: the id must be >= 0 (or -1 for any tag), not " + std::to_string(id));
  }
}

vpHSlamTag vpHSlamTag::parse(const std::string &text)
{
  const std::string form = "expected FAMILY:SIZE[:ID], e.g. tag36h11:0.16:0 (size in metres)";
  const std::vector<std::string> parts = hslam::splitFields(text, ':');
  if (parts.size() < 2 || parts.size() > 3) {
    throw vpHSlamException(vpHSlamException::invalidArgument, "tag '" + text + "': " + form);
  }
  double size = 0.;
  int id = -1;
  long long id64 = -1;
  if (!hslam::tryParseDouble(parts[1], size)) {
    throw vpHSlamException(vpHSlamException::invalidArgument,
                           "tag '" + text + "': size '" + parts[1] + "' is not a number; " + form);
  }
  if (parts.size() == 3) {
    if (!hslam::tryParseInt64(parts[2], id64) || id64 < 0 || id64 > 1000000) {
      throw vpHSlamException(vpHSlamException::invalidArgument,
                             "tag '" + text + "': id '" + parts[2] + "' is not a tag id (an integer >= 0); " + form);
    }
    id = static_cast<int>(id64);
  }
  return vpHSlamTag(parts[0], size, id);
}

std::vector<std::string> vpHSlamTag::familyNames()
{
  return std::vector<std::string>(std::begin(kFamilies), std::end(kFamilies));
}

std::string vpHSlamTag::toString() const
{
  if (!isSet()) {
    return "none";
  }
  std::ostringstream os;
  os << m_family << ":" << m_size;
  if (m_id >= 0) {
    os << ":" << m_id;
  }
  return os.str();
}
