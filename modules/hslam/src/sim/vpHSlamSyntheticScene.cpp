#include <visp3/hslam/vpHSlamSyntheticScene.h>

#include "io/ImageCodec.h"
#include "sim/SyntheticRenderer.h"
#include "sim/SyntheticTrajectory.h"

#include <visp3/core/vpIoTools.h>
#include <visp3/core/vpMath.h>
#include <visp3/core/vpQuaternionVector.h>
#include <visp3/core/vpXmlParserCamera.h>
#include <visp3/hslam/vpHSlamException.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <random>

namespace
{
// Default location of Debian's visp-images-data.
const char *const kDebianImagesPath = "/usr/share/visp-images-data/ViSP-images";
// Focal length per image width: 500 px at 640 px (about 65 degrees horizontal field of view, like a webcam).
constexpr double kFocalPerWidth = 500.0 / 640.0;
constexpr unsigned int kMinImageSide = 16;
// Motion bounds per frame promised by the class documentation (2 cm, 1 degree) with a margin.
constexpr double kMaxStepMetres = 0.018;
constexpr double kMaxStepRadians = 0.9 * M_PI / 180.0;
constexpr unsigned int kSupersampling = 2;

// Photometric model (TUM monoVO: I = G(t V B)). Base exposure in milliseconds; irradiance is in grey levels at
// that exposure.
constexpr double kBaseExposureMs = 10.0;
// Exposure changes: log-exposure is a sum of two sinusoids (periods in seconds) whose amplitudes add up to
// ln(1.6), so t stays in [base / 1.6, base * 1.6] and changes by a few percent per frame at 30 Hz.
constexpr double kExposureLogAmp[2] = {0.75 * 0.47000362924573558, 0.25 * 0.47000362924573558};
constexpr double kExposurePeriodS[2] = {5.0, 1.7};
// Vignette V(r) = 1 + a r^2 + b r^4, r = distance to the image centre / half diagonal: 0.5 in the corners.
constexpr double kVignetteA = -0.3, kVignetteB = -0.2;
// Camera response: a gamma curve I = 255 (E / 255)^(1 / gamma), inverse written to pcalib.txt.
constexpr double kResponseGamma = 2.2;
constexpr double kGreyMax = 255.0;
// Motion blur: sub-frame renders averaged over the exposure time.
constexpr unsigned int kBlurSubFrames = 5;
constexpr double kTwoPi = 2.0 * M_PI;

void checkStream(const std::ofstream &out, const std::string &path)
{
  if (!out) {
    throw vpHSlamException(vpHSlamException::invalidArgument,
                           "synthetic scene: cannot write file '" + path + "' (folder not writable or disk full)");
  }
}
} // namespace

vpHSlamSyntheticScene::vpHSlamSyntheticScene()
    : m_width(0), m_height(0), m_frames(0), m_seed(0), m_fps(0.0), m_effects(), m_renderer(), m_trajectory()
{
}

vpHSlamSyntheticScene::~vpHSlamSyntheticScene() = default;

void vpHSlamSyntheticScene::setLaps(unsigned int laps)
{
  if (laps == 0) {
    throw vpHSlamException(vpHSlamException::invalidArgument, "synthetic scene: laps must be at least 1");
  }
  m_laps = laps;
}

void vpHSlamSyntheticScene::configure(unsigned int width, unsigned int height, unsigned int frames, double fps,
                                      unsigned int seed, const Effects &effects)
{
  if (width < kMinImageSide || height < kMinImageSide) {
    throw vpHSlamException(vpHSlamException::invalidArgument,
                           "synthetic scene: image size " + std::to_string(width) + "x" + std::to_string(height) +
                               " too small (at least " + std::to_string(kMinImageSide) + " px per side)");
  }
  if (frames < 2) {
    throw vpHSlamException(vpHSlamException::invalidArgument,
                           "synthetic scene: at least 2 frames are needed for a loop, got " + std::to_string(frames));
  }
  if (!(fps > 0.0)) {
    throw vpHSlamException(vpHSlamException::invalidArgument, "synthetic scene: frame rate must be positive");
  }
  if (!(effects.noiseSigma >= 0.0)) {
    throw vpHSlamException(vpHSlamException::invalidArgument, "synthetic scene: noise sigma must be >= 0");
  }

  std::string path = m_imagesDataPath;
  if (path.empty()) {
    path = vpIoTools::getViSPImagesDataPath();
    if (path.empty() || !vpIoTools::checkDirectory(path)) {
      path = kDebianImagesPath;
    }
  }
  if (!m_renderer || path != m_loadedPath) {
    std::unique_ptr<hslam::SyntheticRenderer> renderer(new hslam::SyntheticRenderer());
    renderer->load(path);
    renderer->setPictures(m_pictures);
    m_renderer = std::move(renderer);
    m_loadedPath = path;
  }

  m_width = width;
  m_height = height;
  m_frames = frames;
  m_fps = fps;
  m_seed = seed;
  m_effects = effects;
  m_trajectory.reset(
      new hslam::SyntheticTrajectory(frames, seed, kMaxStepMetres, kMaxStepRadians, m_laps, m_lookOutward));

  m_vignette.clear();
  if (effects.vignette) {
    m_vignette.resize(static_cast<size_t>(width) * height);
    const double cx = 0.5 * (width - 1), cy = 0.5 * (height - 1);
    const double halfDiagonal2 = cx * cx + cy * cy;
    for (unsigned int v = 0; v < height; ++v) {
      for (unsigned int u = 0; u < width; ++u) {
        const double r2 = ((u - cx) * (u - cx) + (v - cy) * (v - cy)) / halfDiagonal2;
        const double V = 1.0 + kVignetteA * r2 + kVignetteB * r2 * r2;
        // Quantised exactly as written to the 8-bit vignette.png, so the file is the exact truth.
        m_vignette[static_cast<size_t>(v) * width + u] = static_cast<float>(std::round(kGreyMax * V) / kGreyMax);
      }
    }
  }
  m_inverseResponse.resize(256);
  for (unsigned int I = 0; I < 256; ++I) {
    m_inverseResponse[I] =
        effects.response ? kGreyMax * std::pow(I / kGreyMax, kResponseGamma) : static_cast<double>(I);
  }
}

void vpHSlamSyntheticScene::requireConfigured(const char *what) const
{
  if (!m_trajectory) {
    throw vpHSlamException(vpHSlamException::invalidArgument,
                           std::string("vpHSlamSyntheticScene::") + what + ": call configure() first");
  }
}

void vpHSlamSyntheticScene::requireFrame(unsigned int i, const char *what) const
{
  requireConfigured(what);
  if (i >= m_frames) {
    throw vpHSlamException(vpHSlamException::invalidArgument, std::string("vpHSlamSyntheticScene::") + what +
                                                                  ": frame " + std::to_string(i) + " out of [0, " +
                                                                  std::to_string(m_frames) + ")");
  }
}

vpCameraParameters vpHSlamSyntheticScene::getCameraParameters() const
{
  requireConfigured("getCameraParameters");
  const double f = kFocalPerWidth * m_width;
  vpCameraParameters cam;
  cam.initPersProjWithoutDistortion(f, f, 0.5 * (m_width - 1), 0.5 * (m_height - 1));
  return cam;
}

vpHomogeneousMatrix vpHSlamSyntheticScene::getPose(unsigned int i) const
{
  requireFrame(i, "getPose");
  return m_trajectory->wMc(i);
}

double vpHSlamSyntheticScene::getTimestamp(unsigned int i) const
{
  requireFrame(i, "getTimestamp");
  return i / m_fps;
}

double vpHSlamSyntheticScene::getExposure(unsigned int i) const
{
  requireFrame(i, "getExposure");
  if (!m_effects.exposureChanges) {
    return kBaseExposureMs;
  }
  // Phases from the seed, drawn from their own generator so they do not depend on other uses of the seed.
  std::mt19937 rng(m_seed);
  std::uniform_real_distribution<double> phase(0.0, kTwoPi);
  double logExposure = 0.0;
  const double t = i / m_fps;
  for (int k = 0; k < 2; ++k) {
    logExposure += kExposureLogAmp[k] * std::sin(kTwoPi * t / kExposurePeriodS[k] + phase(rng));
  }
  return kBaseExposureMs * std::exp(logExposure);
}

std::vector<double> vpHSlamSyntheticScene::getInverseResponse() const
{
  requireConfigured("getInverseResponse");
  return m_inverseResponse;
}

void vpHSlamSyntheticScene::getVignette(vpImage<float> &V) const
{
  requireConfigured("getVignette");
  V.resize(m_height, m_width, 1.f);
  if (!m_vignette.empty()) {
    std::copy(m_vignette.begin(), m_vignette.end(), V.bitmap);
  }
}

vpHomogeneousMatrix vpHSlamSyntheticScene::addWallPicture(const vpImage<unsigned char> &picture,
                                                          const vpColVector &centre, double width)
{
  if (centre.size() != 3) {
    throw vpHSlamException(vpHSlamException::invalidArgument,
                           "vpHSlamSyntheticScene::addWallPicture: the centre must be a 3-vector (metres)");
  }
  hslam::SimPicture P;
  P.width = static_cast<int>(picture.getWidth());
  P.height = static_cast<int>(picture.getHeight());
  P.pixels.assign(picture.bitmap, picture.bitmap + picture.getSize());
  for (unsigned int k = 0; k < 3; ++k) {
    P.centre[k] = centre[k];
  }
  P.widthMetres = width;
  std::vector<hslam::SimPicture> pictures = m_pictures;
  pictures.push_back(P);
  if (m_renderer) {
    m_renderer->setPictures(pictures); // validates; throws before anything changed
  } else {
    hslam::SyntheticRenderer().setPictures({P});
  }
  m_pictures = std::move(pictures);
  double x[3], y[3], z[3];
  hslam::SyntheticRenderer::pictureAxes(P.centre, x, y, z);
  vpHomogeneousMatrix wMp;
  for (unsigned int r = 0; r < 3; ++r) {
    wMp[r][0] = x[r];
    wMp[r][1] = y[r];
    wMp[r][2] = z[r];
    wMp[r][3] = P.centre[r];
  }
  return wMp;
}

vpHomogeneousMatrix vpHSlamSyntheticScene::addWallTag(const vpImage<unsigned char> &tagImage, unsigned int blackCells,
                                                      const vpColVector &centre, double tagSize)
{
  if (blackCells == 0 || blackCells > tagImage.getWidth()) {
    throw vpHSlamException(vpHSlamException::invalidArgument,
                           "vpHSlamSyntheticScene::addWallTag: the black square must span 1 to the image's width "
                           "cells");
  }
  const vpHomogeneousMatrix wMp = addWallPicture(tagImage, centre, tagSize * tagImage.getWidth() / blackCells);
  return wMp * vpHomogeneousMatrix(0., 0., 0., M_PI, 0., 0.);
}

void vpHSlamSyntheticScene::clearWallPictures()
{
  m_pictures.clear();
  if (m_renderer) {
    m_renderer->setPictures(m_pictures);
  }
}

std::vector<std::string> vpHSlamSyntheticScene::getTextureFiles() const
{
  requireConfigured("getTextureFiles");
  return m_renderer->getTextureFiles();
}

void vpHSlamSyntheticScene::renderIrradiance(unsigned int i, std::vector<float> &E) const
{
  const vpCameraParameters cam = getCameraParameters();
  const hslam::SimIntrinsics K = {cam.get_px(), cam.get_py(), cam.get_u0(), cam.get_v0(), m_width, m_height};
  const size_t n = static_cast<size_t>(m_width) * m_height;
  E.assign(n, 0.f);
  if (!m_effects.motionBlur) {
    m_renderer->render(m_trajectory->pose(i), K, kSupersampling, E.data());
    return;
  }
  // Shutter open for the exposure time, centred on the frame's pose.
  const double shutterFrames = getExposure(i) * 1e-3 * m_fps;
  std::vector<float> sub(n);
  for (unsigned int s = 0; s < kBlurSubFrames; ++s) {
    const double frame = i + ((s + 0.5) / kBlurSubFrames - 0.5) * shutterFrames;
    m_renderer->render(m_trajectory->pose(frame), K, kSupersampling, sub.data());
    for (size_t p = 0; p < n; ++p) {
      E[p] += sub[p];
    }
  }
  const float inv = 1.f / kBlurSubFrames;
  for (size_t p = 0; p < n; ++p) {
    E[p] *= inv;
  }
}

void vpHSlamSyntheticScene::render(unsigned int i, vpImage<unsigned char> &I) const
{
  requireFrame(i, "render");
  std::vector<float> E;
  renderIrradiance(i, E);
  formImage(E, getExposure(i) / kBaseExposureMs, {m_seed, i}, I);
}

void vpHSlamSyntheticScene::renderAtPose(const vpHomogeneousMatrix &wMc, vpImage<unsigned char> &I,
                                         unsigned int noiseSeed) const
{
  requireConfigured("renderAtPose");
  hslam::SimPose P;
  for (unsigned int r = 0; r < 3; ++r) {
    for (unsigned int c = 0; c < 3; ++c) {
      P.wRc[3 * r + c] = wMc[r][c];
    }
    P.wtc[r] = wMc[r][3];
  }
  const vpCameraParameters cam = getCameraParameters();
  const hslam::SimIntrinsics K = {cam.get_px(), cam.get_py(), cam.get_u0(), cam.get_v0(), m_width, m_height};
  std::vector<float> E(static_cast<size_t>(m_width) * m_height, 0.f);
  m_renderer->render(P, K, kSupersampling, E.data());
  // A third seed value keeps this noise apart from that of frame noiseSeed in render() (two values).
  formImage(E, 1.0, {m_seed, noiseSeed, 1u}, I);
}

void vpHSlamSyntheticScene::formImage(const std::vector<float> &E, double exposureRatio,
                                      const std::vector<unsigned int> &seeds, vpImage<unsigned char> &I) const
{
  std::seed_seq seq(seeds.begin(), seeds.end());
  std::mt19937 rng(seq);
  std::normal_distribution<double> noise(0.0, m_effects.noiseSigma > 0.0 ? m_effects.noiseSigma : 1.0);
  I.resize(m_height, m_width);
  for (size_t p = 0; p < E.size(); ++p) {
    // TUM monoVO model: I = G(t V B), then sensor noise and 8-bit quantisation.
    double energy = E[p] * exposureRatio;
    if (!m_vignette.empty()) {
      energy *= m_vignette[p];
    }
    energy = std::min(std::max(energy, 0.0), kGreyMax);
    double value = m_effects.response ? kGreyMax * std::pow(energy / kGreyMax, 1.0 / kResponseGamma) : energy;
    if (m_effects.noiseSigma > 0.0) {
      value += noise(rng);
    }
    I.bitmap[p] = static_cast<unsigned char>(std::min(std::max(std::round(value), 0.0), kGreyMax));
  }
}

void vpHSlamSyntheticScene::surfaceAt(double u, double v, unsigned int i, const char *what, double Pw[3],
                                      double &depth) const
{
  requireFrame(i, what);
  const vpCameraParameters cam = getCameraParameters();
  const hslam::SimIntrinsics K = {cam.get_px(), cam.get_py(), cam.get_u0(), cam.get_v0(), m_width, m_height};
  if (!m_renderer->worldPoint(m_trajectory->pose(i), K, u, v, Pw, depth)) {
    throw vpHSlamException(vpHSlamException::invalidArgument,
                           std::string("vpHSlamSyntheticScene::") + what + ": no surface");
  }
}

vpColVector vpHSlamSyntheticScene::worldPointAt(double u, double v, unsigned int i) const
{
  double Pw[3], depth = 0.0;
  surfaceAt(u, v, i, "worldPointAt", Pw, depth);
  vpColVector wP(3);
  for (unsigned int a = 0; a < 3; ++a) {
    wP[a] = Pw[a];
  }
  return wP;
}

double vpHSlamSyntheticScene::depthAt(double u, double v, unsigned int i) const
{
  double Pw[3], depth = 0.0;
  surfaceAt(u, v, i, "depthAt", Pw, depth);
  return depth;
}

void vpHSlamSyntheticScene::writeSequence(const std::string &dir) const
{
  requireConfigured("writeSequence");
  const std::string rgbDir = dir + "/rgb";
  try {
    if (!vpIoTools::checkDirectory(rgbDir)) {
      vpIoTools::makeDirectory(rgbDir);
    }
  } catch (const vpException &e) {
    throw vpHSlamException(vpHSlamException::invalidArgument,
                           "synthetic scene: cannot create folder '" + rgbDir + "': " + e.getStringMessage());
  }
  if (!vpIoTools::checkDirectory(rgbDir)) {
    throw vpHSlamException(vpHSlamException::invalidArgument, "synthetic scene: cannot create folder '" + rgbDir + "'");
  }

  const std::string rgbList = dir + "/rgb.txt", gtFile = dir + "/groundtruth.txt", timesFile = dir + "/times.txt";
  std::ofstream rgb(rgbList), gt(gtFile), times(timesFile);
  checkStream(rgb, rgbList);
  checkStream(gt, gtFile);
  checkStream(times, timesFile);
  rgb << "# color images (8-bit grey), synthetic room sequence\n# timestamp filename\n";
  gt << "# ground truth trajectory: camera-to-world wMc, metres\n# timestamp tx ty tz qx qy qz qw\n";

  vpImage<unsigned char> I;
  char name[32], line[256];
  for (unsigned int i = 0; i < m_frames; ++i) {
    std::snprintf(name, sizeof(name), "rgb/%06u.png", i);
    render(i, I);
    const std::string imagePath = dir + "/" + name;
    try {
      hslam::io::writePng(imagePath, I);
    } catch (const vpHSlamException &e) {
      throw vpHSlamException(vpHSlamException::invalidArgument, "synthetic scene: " + e.getStringMessage());
    }
    const double t = getTimestamp(i);
    std::snprintf(line, sizeof(line), "%.6f %s\n", t, name);
    rgb << line;
    const vpHomogeneousMatrix wMc = getPose(i);
    vpQuaternionVector q(wMc.getRotationMatrix());
    const double sign = q.w() < 0.0 ? -1.0 : 1.0; // one of the two equivalent quaternions, w >= 0
    std::snprintf(line, sizeof(line), "%.6f %.9f %.9f %.9f %.9f %.9f %.9f %.9f\n", t, wMc[0][3], wMc[1][3], wMc[2][3],
                  sign * q.x(), sign * q.y(), sign * q.z(), sign * q.w());
    gt << line;
    std::snprintf(line, sizeof(line), "%06u %.6f %.6f\n", i, t, getExposure(i));
    times << line;
  }
  checkStream(rgb, rgbList);
  checkStream(gt, gtFile);
  checkStream(times, timesFile);

  // DSO camera.txt, absolute intrinsics (pixel centres at integer coordinates), no rectification.
  const vpCameraParameters cam = getCameraParameters();
  const std::string cameraFile = dir + "/camera.txt";
  std::ofstream camOut(cameraFile);
  std::snprintf(line, sizeof(line), "Pinhole %.6f %.6f %.6f %.6f 0\n%u %u\nnone\n%u %u\n", cam.get_px(), cam.get_py(),
                cam.get_u0(), cam.get_v0(), m_width, m_height, m_width, m_height);
  camOut << line;
  checkStream(camOut, cameraFile);

  const std::string xmlFile = dir + "/camera.xml";
  if (vpIoTools::checkFilename(xmlFile)) {
    vpIoTools::remove(xmlFile); // ViSP's writer refuses to replace a camera already in the file: write anew
  }
  vpXmlParserCamera xml;
  if (xml.save(cam, xmlFile, "Camera", m_width, m_height) != vpXmlParserCamera::SEQUENCE_OK) {
    throw vpHSlamException(vpHSlamException::invalidArgument, "synthetic scene: cannot write file '" + xmlFile + "'");
  }

  if (m_effects.response) {
    const std::string pcalibFile = dir + "/pcalib.txt";
    std::ofstream pcalib(pcalibFile);
    for (unsigned int k = 0; k < m_inverseResponse.size(); ++k) {
      std::snprintf(line, sizeof(line), k + 1 < m_inverseResponse.size() ? "%.6f " : "%.6f\n", m_inverseResponse[k]);
      pcalib << line;
    }
    checkStream(pcalib, pcalibFile);
  }
  if (!m_vignette.empty()) {
    vpImage<unsigned char> V(m_height, m_width);
    for (size_t p = 0; p < m_vignette.size(); ++p) {
      V.bitmap[p] = static_cast<unsigned char>(std::round(m_vignette[p] * kGreyMax));
    }
    const std::string vignetteFile = dir + "/vignette.png";
    try {
      hslam::io::writePng(vignetteFile, V);
    } catch (const vpHSlamException &e) {
      throw vpHSlamException(vpHSlamException::invalidArgument, "synthetic scene: " + e.getStringMessage());
    }
  }
}
