/*
 * H-SLAM for ViSP.
 */
// vpHSlamCamera::loadViSPXml(): ViSP camera XML through vpXmlParserCamera.
//
// A light scan of the file comes first: vpXmlParserCamera only returns a camera whose name, image size and model
// type are all given exactly, so the scan finds them (first <camera>, or the one named), then ViSP parses.
// The three ViSP 3.5 projection models are read exactly:
// - perspectiveProjWithoutDistortion -> pinhole;
// - perspectiveProjWithDistortion -> radialTangential {kud, 0, 0, 0}: ViSP projects with u = u0 + px x (1 + kud r^2)
//   (vpMeterPixelConversion), which is OpenCV's radial-tangential model with k1 = kud and every other coefficient 0.
//   ViSP's kdu is a separately fitted approximate inverse; it is dropped because vpHSlamCamera inverts numerically;
// - ProjWithKannalaBrandtDistortion -> equidistant {k1..k4}: ViSP 3.5 projects with the first four coefficients only
//   (vpMeterPixelConversion), so its k5 is ignored here as it is there.
// When one <camera> lists several models, the distorted one is taken (Kannala-Brandt first, then kud): a ViSP
// calibration that reports both describes the raw, distorted images.
// vpXmlParserCamera 3.5 writes progress ("Found camera with name") to std::cout and errors to std::cerr; library
// code must not print, so both streams are muted for the duration of the call (ScopedStreamMute).
#include <visp3/hslam/vpHSlamCamera.h>
#include <visp3/hslam/vpHSlamException.h>

#include <visp3/core/vpXmlParserCamera.h>

#include "camera/CameraLoaderSupport.h"
#include "common/TextParsing.h"

#include <algorithm>
#include <cctype>
#include <iostream>
#include <mutex>
#include <streambuf>

namespace
{
using hslam::kIntrinsicCount;
using hslam::makeCamera;
using hslam::setDefaultRectification;

// Mutes std::cout and std::cerr for its lifetime. Only used around vpXmlParserCamera, which prints; calibration is
// loaded before the SLAM threads start, and the mutex keeps concurrent loaders from restoring each other's buffers.
class ScopedStreamMute
{
public:
  ScopedStreamMute() : m_lock(mutex()), m_cout(std::cout.rdbuf(&m_null)), m_cerr(std::cerr.rdbuf(&m_null)) {}
  ~ScopedStreamMute()
  {
    std::cout.rdbuf(m_cout);
    std::cerr.rdbuf(m_cerr);
  }
  ScopedStreamMute(const ScopedStreamMute &) = delete;
  ScopedStreamMute &operator=(const ScopedStreamMute &) = delete;

private:
  class NullBuffer : public std::streambuf
  {
  protected:
    int overflow(int c) override { return traits_type::not_eof(c); }
  };
  static std::mutex &mutex()
  {
    static std::mutex m;
    return m;
  }
  std::lock_guard<std::mutex> m_lock;
  NullBuffer m_null;
  std::streambuf *m_cout;
  std::streambuf *m_cerr;
};

// ---- light scan of a ViSP camera XML: enough to choose the camera, its size and model before vpXmlParserCamera.

struct XmlElement {
  bool found = false;
  std::size_t contentBegin = 0, contentEnd = 0, end = 0; // end: just past the closing tag
};

// First <tag>...</tag> (or <tag attr...>...</tag>) in xml[from, to).
XmlElement findElement(const std::string &xml, const std::string &tag, std::size_t from, std::size_t to)
{
  XmlElement element;
  const std::string open = "<" + tag;
  const std::string close = "</" + tag + ">";
  std::size_t pos = xml.find(open, from);
  while (pos != std::string::npos && pos < to) {
    const std::size_t after = pos + open.size();
    if (after < xml.size() && (xml[after] == '>' || std::isspace(static_cast<unsigned char>(xml[after])))) {
      const std::size_t gt = xml.find('>', after);
      const std::size_t closePos = gt == std::string::npos ? gt : xml.find(close, gt);
      if (closePos == std::string::npos || closePos + close.size() > to) {
        return element;
      }
      element.found = true;
      element.contentBegin = gt + 1;
      element.contentEnd = closePos;
      element.end = closePos + close.size();
      return element;
    }
    pos = xml.find(open, after);
  }
  return element;
}

std::size_t lineOf(const std::string &xml, std::size_t offset)
{
  return 1 + static_cast<std::size_t>(std::count(xml.begin(), xml.begin() + static_cast<long>(offset), '\n'));
}

struct XmlCamera {
  std::string name;
  unsigned int width = 0, height = 0; // 0: not stored
  std::vector<std::string> modelTypes;
};

// Comments may hold example blocks (ViSP writes one): blank them, keeping offsets and line numbers.
void blankComments(std::string &xml)
{
  std::size_t pos = xml.find("<!--");
  while (pos != std::string::npos) {
    const std::size_t end = xml.find("-->", pos);
    const std::size_t stop = end == std::string::npos ? xml.size() : end + 3;
    for (std::size_t i = pos; i < stop; ++i) {
      if (xml[i] != '\n') {
        xml[i] = ' ';
      }
    }
    pos = xml.find("<!--", stop);
  }
}

unsigned int xmlUnsigned(const std::string &xml, const XmlElement &e, const std::string &path, const char *what)
{
  if (!e.found) {
    return 0;
  }
  const std::string text = hslam::trim(xml.substr(e.contentBegin, e.contentEnd - e.contentBegin));
  return hslam::parseUnsigned(text, path, lineOf(xml, e.contentBegin), what);
}

std::vector<XmlCamera> scanViSPXml(const std::string &path)
{
  std::string xml = hslam::readTextFile(path, "ViSP camera XML");
  blankComments(xml);

  std::vector<XmlCamera> cameras;
  XmlElement block = findElement(xml, "camera", 0, xml.size());
  while (block.found) {
    XmlCamera camera;
    const XmlElement name = findElement(xml, "name", block.contentBegin, block.contentEnd);
    if (name.found) {
      camera.name = hslam::trim(xml.substr(name.contentBegin, name.contentEnd - name.contentBegin));
    }
    camera.width =
        xmlUnsigned(xml, findElement(xml, "image_width", block.contentBegin, block.contentEnd), path, "<image_width>");
    camera.height = xmlUnsigned(xml, findElement(xml, "image_height", block.contentBegin, block.contentEnd), path,
                                "<image_height>");
    XmlElement model = findElement(xml, "model", block.contentBegin, block.contentEnd);
    while (model.found) {
      const XmlElement type = findElement(xml, "type", model.contentBegin, model.contentEnd);
      if (type.found) {
        camera.modelTypes.push_back(hslam::trim(xml.substr(type.contentBegin, type.contentEnd - type.contentBegin)));
      }
      model = findElement(xml, "model", model.end, block.contentEnd);
    }
    cameras.push_back(camera);
    block = findElement(xml, "camera", block.end, xml.size());
  }
  return cameras;
}

bool contains(const std::vector<std::string> &list, const std::string &value)
{
  return std::find(list.begin(), list.end(), value) != list.end();
}
} // namespace

vpHSlamCamera vpHSlamCamera::loadViSPXml(const std::string &path, const std::string &cameraName, unsigned int width,
                                         unsigned int height)
{
  hslam::requireFileExists(path, "ViSP camera XML");
  const std::vector<XmlCamera> cameras = scanViSPXml(path);
  if (cameras.empty()) {
    throw vpHSlamException(vpHSlamException::parseError, path + ": no <camera> element");
  }
  const XmlCamera *chosen = nullptr;
  std::string names;
  for (const XmlCamera &c : cameras) {
    if (!chosen && (cameraName.empty() || c.name == cameraName)) {
      chosen = &c;
    }
    names += (names.empty() ? "'" : ", '") + c.name + "'";
  }
  if (!chosen) {
    throw vpHSlamException(vpHSlamException::invalidArgument,
                           path + ": no camera named '" + cameraName + "' (the file has " + names + ")");
  }

  const bool sizeStored = chosen->width > 0 && chosen->height > 0;
  if (sizeStored && (width != 0 || height != 0) && (width != chosen->width || height != chosen->height)) {
    throw vpHSlamException(vpHSlamException::invalidArgument,
                           path + ": camera '" + chosen->name + "' is calibrated for " + std::to_string(chosen->width) +
                               "x" + std::to_string(chosen->height) + ", not the requested " + std::to_string(width) +
                               "x" + std::to_string(height));
  }
  if (!sizeStored && (width == 0 || height == 0)) {
    throw vpHSlamException(vpHSlamException::invalidArgument,
                           path + ": camera '" + chosen->name +
                               "' stores no <image_width>/<image_height>: the image size must be given");
  }
  const unsigned int camWidth = sizeStored ? chosen->width : width;
  const unsigned int camHeight = sizeStored ? chosen->height : height;

  vpCameraParameters::vpCameraParametersProjType projModel;
  if (contains(chosen->modelTypes, "ProjWithKannalaBrandtDistortion")) {
    projModel = vpCameraParameters::ProjWithKannalaBrandtDistortion;
  } else if (contains(chosen->modelTypes, "perspectiveProjWithDistortion")) {
    projModel = vpCameraParameters::perspectiveProjWithDistortion;
  } else if (contains(chosen->modelTypes, "perspectiveProjWithoutDistortion")) {
    projModel = vpCameraParameters::perspectiveProjWithoutDistortion;
  } else {
    throw vpHSlamException(vpHSlamException::unsupported,
                           path + ": camera '" + chosen->name + "' has no model of a known ViSP type (" +
                               (chosen->modelTypes.empty() ? std::string("none") : chosen->modelTypes.front()) + ")");
  }

  vpCameraParameters K;
  int status = vpXmlParserCamera::SEQUENCE_ERROR;
  {
    ScopedStreamMute mute;
    vpXmlParserCamera parser;
    // Stored sizes are passed as stored (0 when absent) so that ViSP's own size match selects this very camera.
    try {
      status = parser.parse(K, path, chosen->name, projModel, sizeStored ? camWidth : 0, sizeStored ? camHeight : 0);
    } catch (const vpException &e) {
      // ViSP refuses some values itself (e.g. "Camera parameter px = 0", found by fuzz_camera_xml).
      throw vpHSlamException(vpHSlamException::invalidCalibration,
                             path + ": camera '" + chosen->name + "': " + e.getStringMessage());
    }
  }
  if (status != vpXmlParserCamera::SEQUENCE_OK) {
    throw vpHSlamException(vpHSlamException::parseError,
                           path + ": vpXmlParserCamera cannot read camera '" + chosen->name +
                               "' (missing or unknown fields, or several cameras with this name and size)");
  }

  Model model = pinhole;
  std::vector<double> distortion;
  if (projModel == vpCameraParameters::perspectiveProjWithDistortion) {
    model = radialTangential; // exact: ViSP's u = u0 + px x (1 + kud r^2) is radtan with k1 = kud
    distortion = {K.get_kud(), 0.0, 0.0, 0.0};
  } else if (projModel == vpCameraParameters::ProjWithKannalaBrandtDistortion) {
    model = equidistant; // ViSP 3.5 projects with k1..k4 only
    const std::vector<double> k = K.getKannalaBrandtDistortionCoefficients();
    distortion.assign(k.begin(), k.begin() + std::min<std::size_t>(k.size(), kIntrinsicCount));
  }
  vpHSlamCamera cam =
      makeCamera(path, model, camWidth, camHeight, K.get_px(), K.get_py(), K.get_u0(), K.get_v0(), distortion);
  setDefaultRectification(cam, path);
  return cam;
}
