// Synthetic sequences: the written ground truth is exact and consistent with the rendered images.
#include "HSlamTestData.h"

#include <visp3/core/vpIoTools.h>
#include <visp3/hslam/vpHSlamException.h>
#include <visp3/hslam/vpHSlamSyntheticScene.h>
#include <visp3/io/vpImageIo.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>
#include <vector>

namespace
{
// Small images and few frames keep the whole file fast.
constexpr unsigned int kWidth = 160, kHeight = 120, kFrames = 40;
constexpr int kHalfPatch = 3;               // 7x7 patches
constexpr double kMinPatchStd = 8.0;        // grey levels: skip flat patches, NCC is meaningless there
constexpr double kMinNcc = 0.9;             // for 99.5 % of the patches
constexpr double kMinNccAnyPatch = 0.75;    // for every patch
constexpr double kSamePointMetres = 1e-3;   // a surface point seen again (not occluded)
constexpr double kMaxPatchWarpPixels = 0.5; // patch corners may move this much relative to its centre

std::string tempDir(const std::string &name)
{
  const std::string dir = vpIoTools::getTempPath() + "/hslam_test_synthetic_" + name;
  if (vpIoTools::checkDirectory(dir)) {
    vpIoTools::remove(dir);
  }
  return dir;
}

std::string readFile(const std::string &path)
{
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

// A small TUM reader: "timestamp tx ty tz qx qy qz qw" per line, '#' comments.
std::vector<vpHomogeneousMatrix> readTum(const std::string &path, std::vector<double> &stamps)
{
  std::ifstream in(path);
  std::vector<vpHomogeneousMatrix> poses;
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') {
      continue;
    }
    std::istringstream ss(line);
    double t, tx, ty, tz, qx, qy, qz, qw;
    if (!(ss >> t >> tx >> ty >> tz >> qx >> qy >> qz >> qw)) {
      ADD_FAILURE() << "bad TUM line in " << path << ": " << line;
      continue;
    }
    stamps.push_back(t);
    poses.push_back(vpHomogeneousMatrix(vpTranslationVector(tx, ty, tz), vpQuaternionVector(qx, qy, qz, qw)));
  }
  return poses;
}

// DSO camera.txt, pinhole with absolute intrinsics: "Pinhole fx fy cx cy 0" then "w h".
vpCameraParameters readDsoPinhole(const std::string &path, unsigned int &w, unsigned int &h)
{
  std::ifstream in(path);
  std::string model;
  double fx = 0, fy = 0, cx = 0, cy = 0, omega = -1;
  in >> model >> fx >> fy >> cx >> cy >> omega >> w >> h;
  EXPECT_EQ(model, "Pinhole");
  EXPECT_EQ(omega, 0.0);
  vpCameraParameters cam;
  cam.initPersProjWithoutDistortion(fx, fy, cx, cy);
  return cam;
}

// Binomial [1 4 6 4 1] / 16 smoothing (sigma about 1 px), separable, borders clamped. The renderer is
// anti-aliased, so its images carry detail up to the pixel scale; a shift by half a pixel through bilinear
// interpolation blurs such detail in one image only. Smoothing both first compares geometry, not resampling.
vpImage<double> smooth(const vpImage<unsigned char> &I)
{
  const double k[5] = {1 / 16., 4 / 16., 6 / 16., 4 / 16., 1 / 16.};
  const int w = static_cast<int>(I.getWidth()), h = static_cast<int>(I.getHeight());
  vpImage<double> T(h, w, 0.0), O(h, w, 0.0);
  for (int v = 0; v < h; ++v) {
    for (int u = 0; u < w; ++u) {
      for (int d = -2; d <= 2; ++d) {
        T[v][u] += k[d + 2] * I[v][std::min(std::max(u + d, 0), w - 1)];
      }
    }
  }
  for (int v = 0; v < h; ++v) {
    for (int u = 0; u < w; ++u) {
      for (int d = -2; d <= 2; ++d) {
        O[v][u] += k[d + 2] * T[std::min(std::max(v + d, 0), h - 1)][u];
      }
    }
  }
  return O;
}

double bilinear(const vpImage<double> &I, double u, double v)
{
  const int u0 = static_cast<int>(std::floor(u)), v0 = static_cast<int>(std::floor(v));
  const double au = u - u0, av = v - v0;
  return (1 - av) * ((1 - au) * I[v0][u0] + au * I[v0][u0 + 1]) +
         av * ((1 - au) * I[v0 + 1][u0] + au * I[v0 + 1][u0 + 1]);
}

// NCC of the patch around integer (u, v) in A and around sub-pixel (u2, v2) in B; std of A's patch returned.
double ncc(const vpImage<double> &A, int u, int v, const vpImage<double> &B, double u2, double v2, double &stdA)
{
  std::vector<double> a, b;
  for (int dv = -kHalfPatch; dv <= kHalfPatch; ++dv) {
    for (int du = -kHalfPatch; du <= kHalfPatch; ++du) {
      a.push_back(A[v + dv][u + du]);
      b.push_back(bilinear(B, u2 + du, v2 + dv));
    }
  }
  const double n = static_cast<double>(a.size());
  double ma = 0, mb = 0;
  for (size_t k = 0; k < a.size(); ++k) {
    ma += a[k] / n;
    mb += b[k] / n;
  }
  double sab = 0, saa = 0, sbb = 0;
  for (size_t k = 0; k < a.size(); ++k) {
    sab += (a[k] - ma) * (b[k] - mb);
    saa += (a[k] - ma) * (a[k] - ma);
    sbb += (b[k] - mb) * (b[k] - mb);
  }
  stdA = std::sqrt(saa / n);
  return sab / std::sqrt(saa * sbb + 1e-12);
}

double rotationAngle(const vpHomogeneousMatrix &M)
{
  const vpThetaUVector tu(M.getRotationMatrix());
  return std::sqrt(tu[0] * tu[0] + tu[1] * tu[1] + tu[2] * tu[2]);
}

#define HSLAM_REQUIRE_VISP_IMAGES()                                                                                    \
  if (hslam_test::vispImagesDir().empty()) {                                                                           \
    GTEST_SKIP() << "visp-images-data not installed (/usr/share/visp-images-data/ViSP-images)";                        \
  }
} // namespace

// The 3D point behind a pixel of frame i, projected with the WRITTEN pose of frame j and the WRITTEN camera.txt,
// lands on a patch of frame j's WRITTEN image that looks like the patch of frame i.
TEST(SyntheticScene, WrittenGroundTruthMatchesImages)
{
  HSLAM_REQUIRE_VISP_IMAGES();
  vpHSlamSyntheticScene scene;
  scene.configure(kWidth, kHeight, kFrames, 30.0, 7);
  const std::string dir = tempDir("gt");
  scene.writeSequence(dir);

  std::vector<double> stamps;
  const std::vector<vpHomogeneousMatrix> wMc = readTum(dir + "/groundtruth.txt", stamps);
  ASSERT_EQ(wMc.size(), kFrames);
  EXPECT_NEAR(stamps[10], 10.0 / 30.0, 1e-6);
  unsigned int w = 0, h = 0;
  const vpCameraParameters cam = readDsoPinhole(dir + "/camera.txt", w, h);
  ASSERT_EQ(w, kWidth);
  ASSERT_EQ(h, kHeight);

  const unsigned int pairs[][2] = {{0, 4}, {12, 20}, {25, 38}, {3, 30}, {10, 31}};
  const int margin = kHalfPatch + 2;
  for (const auto &pair : pairs) {
    const unsigned int i = pair[0], j = pair[1];
    char name[64];
    vpImage<unsigned char> Ii, Ij;
    std::snprintf(name, sizeof(name), "/rgb/%06u.png", i);
    vpImageIo::read(Ii, dir + name);
    std::snprintf(name, sizeof(name), "/rgb/%06u.png", j);
    vpImageIo::read(Ij, dir + name);
    const vpImage<double> Si = smooth(Ii), Sj = smooth(Ij);
    const vpHomogeneousMatrix cjMw = wMc[j].inverse();
    int checked = 0, below = 0;
    double worstNcc = 1.0;
    for (int v = margin; v < static_cast<int>(kHeight) - margin; v += 4) {
      for (int u = margin; u < static_cast<int>(kWidth) - margin; u += 4) {
        const vpColVector wP = scene.worldPointAt(u, v, i);
        const vpColVector cP = cjMw * vpColVector({wP[0], wP[1], wP[2], 1.0});
        ASSERT_GT(cP[2], 0.1) << "point behind camera " << j;
        const double u2 = cam.get_px() * cP[0] / cP[2] + cam.get_u0();
        const double v2 = cam.get_py() * cP[1] / cP[2] + cam.get_v0();
        if (u2 < margin || v2 < margin || u2 > kWidth - 1 - margin || v2 > kHeight - 1 - margin) {
          continue; // left the field of view
        }
        // Occlusion and depth edges, creases, strong perspective: the patch is compared after a pure shift, so
        // its corners and edge midpoints must see the same surface points in both frames, shifted alike (< 0.5 px).
        bool shiftedAlike = true;
        for (int c = 0; c < 9 && shiftedAlike; ++c) {
          const int du = (c % 3 - 1) * kHalfPatch, dv = (c / 3 - 1) * kHalfPatch;
          const vpColVector wQ = scene.worldPointAt(u + du, v + dv, i);
          const vpColVector cQ = cjMw * vpColVector({wQ[0], wQ[1], wQ[2], 1.0});
          const double uq = cam.get_px() * cQ[0] / cQ[2] + cam.get_u0();
          const double vq = cam.get_py() * cQ[1] / cQ[2] + cam.get_v0();
          const vpColVector wQj = scene.worldPointAt(uq, vq, j);
          shiftedAlike = (wQj - wQ).frobeniusNorm() < kSamePointMetres &&
                         std::hypot(uq - (u2 + du), vq - (v2 + dv)) < kMaxPatchWarpPixels;
        }
        if (!shiftedAlike) {
          continue;
        }
        double stdI = 0;
        const double score = ncc(Si, u, v, Sj, u2, v2, stdI);
        if (stdI < kMinPatchStd) {
          continue;
        }
        ++checked;
        worstNcc = std::min(worstNcc, score);
        below += score <= kMinNcc ? 1 : 0;
        // A wrong pose or intrinsic would decorrelate whole regions; a single patch may lose a little to
        // resampling (mip level, supersampling) on high-contrast edges seen from another distance.
        EXPECT_GT(score, kMinNccAnyPatch)
            << "frames " << i << "->" << j << " pixel (" << u << "," << v << ") -> (" << u2 << "," << v2 << ")";
      }
    }
    EXPECT_GE(checked, 300) << "too few textured, visible patches for frames " << i << "->" << j;
    EXPECT_LE(below, checked / 200) << "more than 0.5 % of the patches have NCC <= " << kMinNcc << ", frames " << i
                                    << "->" << j;
    std::printf("frames %u->%u: %d patches, %d with NCC <= %.2f, worst NCC %.3f\n", i, j, checked, below, kMinNcc,
                worstNcc);
  }
  vpIoTools::remove(dir);
}

// The last pose equals the first (written file and API), and so do the images without noise.
TEST(SyntheticScene, LoopCloses)
{
  HSLAM_REQUIRE_VISP_IMAGES();
  vpHSlamSyntheticScene scene;
  scene.configure(kWidth, kHeight, kFrames, 30.0, 3);
  const std::string dir = tempDir("loop");
  scene.writeSequence(dir);
  std::vector<double> stamps;
  const std::vector<vpHomogeneousMatrix> wMc = readTum(dir + "/groundtruth.txt", stamps);
  ASSERT_EQ(wMc.size(), kFrames);
  const vpHomogeneousMatrix loop = wMc.front().inverse() * wMc.back();
  EXPECT_LT(loop.getTranslationVector().frobeniusNorm(), 1e-9);
  EXPECT_LT(rotationAngle(loop), 1e-9);
  const vpHomogeneousMatrix apiLoop = scene.getPose(0).inverse() * scene.getPose(kFrames - 1);
  EXPECT_LT(apiLoop.getTranslationVector().frobeniusNorm(), 1e-9);
  EXPECT_LT(rotationAngle(apiLoop), 1e-9);
  // It is a real loop, not a still camera: the half-way pose is away from the start.
  const vpHomogeneousMatrix half = scene.getPose(0).inverse() * scene.getPose(kFrames / 2);
  EXPECT_GT(half.getTranslationVector().frobeniusNorm(), 0.05);
  EXPECT_EQ(readFile(dir + "/rgb/000000.png"), readFile(dir + "/rgb/000039.png"));
  vpIoTools::remove(dir);
}

// Same seed: byte-identical files (all effects on, noise included); another seed: a different trajectory.
TEST(SyntheticScene, DeterministicForASeed)
{
  HSLAM_REQUIRE_VISP_IMAGES();
  vpHSlamSyntheticScene::Effects effects;
  effects.vignette = effects.response = effects.exposureChanges = effects.motionBlur = true;
  effects.noiseSigma = 2.0;
  const unsigned int frames = 6;
  const std::string dirs[3] = {tempDir("det_a"), tempDir("det_b"), tempDir("det_c")};
  const unsigned int seeds[3] = {11, 11, 12};
  for (int k = 0; k < 3; ++k) {
    vpHSlamSyntheticScene scene;
    scene.configure(kWidth, kHeight, frames, 30.0, seeds[k], effects);
    scene.writeSequence(dirs[k]);
  }
  std::vector<std::string> files = {"rgb.txt",    "groundtruth.txt", "times.txt",   "camera.txt",
                                    "camera.xml", "pcalib.txt",      "vignette.png"};
  for (unsigned int i = 0; i < frames; ++i) {
    char name[32];
    std::snprintf(name, sizeof(name), "rgb/%06u.png", i);
    files.push_back(name);
  }
  for (const std::string &f : files) {
    const std::string a = readFile(dirs[0] + "/" + f);
    EXPECT_FALSE(a.empty()) << f;
    EXPECT_EQ(a, readFile(dirs[1] + "/" + f)) << f << " differs between two runs with the same seed";
  }
  EXPECT_NE(readFile(dirs[0] + "/groundtruth.txt"), readFile(dirs[2] + "/groundtruth.txt"));
  EXPECT_NE(readFile(dirs[0] + "/rgb/000001.png"), readFile(dirs[2] + "/rgb/000001.png"));
  // Written again over another sequence (as `bash cmake/run.sh demo` run twice does): the same files as fresh.
  vpHSlamSyntheticScene again;
  again.configure(kWidth, kHeight, frames, 30.0, seeds[0], effects);
  ASSERT_NO_THROW(again.writeSequence(dirs[2]));
  for (const std::string &f : files) {
    EXPECT_EQ(readFile(dirs[0] + "/" + f), readFile(dirs[2] + "/" + f)) << f << " differs after writing over";
  }
  for (const std::string &d : dirs) {
    vpIoTools::remove(d);
  }
}

// Smooth enough for visual odometry at 30 Hz: < 2 cm and < 1 degree between consecutive frames, but moving.
TEST(SyntheticScene, MotionPerFrameWithinBounds)
{
  HSLAM_REQUIRE_VISP_IMAGES();
  for (unsigned int frames : {kFrames, 300u, 1000u}) {
    for (unsigned int seed : {1u, 2u, 99u}) {
      vpHSlamSyntheticScene scene;
      scene.configure(kWidth, kHeight, frames, 30.0, seed);
      double maxStep = 0, maxAngle = 0;
      for (unsigned int i = 0; i + 1 < frames; ++i) {
        const vpHomogeneousMatrix c1Mc2 = scene.getPose(i).inverse() * scene.getPose(i + 1);
        maxStep = std::max(maxStep, c1Mc2.getTranslationVector().frobeniusNorm());
        maxAngle = std::max(maxAngle, rotationAngle(c1Mc2));
      }
      EXPECT_LT(maxStep, 0.02) << frames << " frames, seed " << seed;
      EXPECT_LT(maxAngle, vpMath::rad(1.0)) << frames << " frames, seed " << seed;
      EXPECT_GT(maxStep, 0.002) << "the camera should move, " << frames << " frames";
    }
  }
}

// The photometric files are the exact truth: G^-1(I) = (t / t0) V B for unsaturated pixels.
TEST(SyntheticScene, PhotometricModelMatchesWrittenCalibration)
{
  HSLAM_REQUIRE_VISP_IMAGES();
  vpHSlamSyntheticScene plain, photometric;
  vpHSlamSyntheticScene::Effects effects;
  effects.vignette = effects.response = effects.exposureChanges = true;
  plain.configure(kWidth, kHeight, kFrames, 30.0, 5);
  photometric.configure(kWidth, kHeight, kFrames, 30.0, 5, effects);
  const std::vector<double> Ginv = photometric.getInverseResponse();
  ASSERT_EQ(Ginv.size(), 256u);
  for (size_t k = 1; k < Ginv.size(); ++k) {
    ASSERT_GE(Ginv[k], Ginv[k - 1]);
  }
  vpImage<float> V;
  photometric.getVignette(V);
  EXPECT_NEAR(V[kHeight / 2][kWidth / 2], 1.0, 1e-2);
  EXPECT_LT(V[0][0], 0.6);
  double minExposure = 1e9, maxExposure = 0;
  for (unsigned int i = 0; i < kFrames; ++i) {
    minExposure = std::min(minExposure, photometric.getExposure(i));
    maxExposure = std::max(maxExposure, photometric.getExposure(i));
  }
  EXPECT_GT(maxExposure / minExposure, 1.2) << "exposure should change over 40 frames";
  const double t0 = plain.getExposure(0);
  for (unsigned int i : {0u, 17u}) {
    vpImage<unsigned char> B, I;
    plain.render(i, B);
    photometric.render(i, I);
    const double ratio = photometric.getExposure(i) / t0;
    int checked = 0;
    for (unsigned int p = 0; p < B.getSize(); ++p) {
      if (I.bitmap[p] >= 250 || I.bitmap[p] < 30) {
        continue; // saturated, or too dark for the gamma curve's quantisation step
      }
      const unsigned int u = p % kWidth, v = p / kWidth;
      const double expected = ratio * V[v][u] * B.bitmap[p];
      // Two 8-bit roundings: of B, and of I (one grey level of I spans dG^-1/dI grey levels of energy).
      const double step = Ginv[I.bitmap[p] + 1] - Ginv[I.bitmap[p]];
      EXPECT_NEAR(Ginv[I.bitmap[p]], expected, ratio * V[v][u] * 0.5 + step * 0.5 + 1e-6) << "pixel " << u << "," << v;
      ++checked;
    }
    EXPECT_GT(checked, static_cast<int>(B.getSize() / 2));
  }
}

TEST(SyntheticScene, ErrorsNameThePath)
{
  HSLAM_REQUIRE_VISP_IMAGES();
  vpHSlamSyntheticScene missing;
  missing.setImagesDataPath("/nonexistent/visp-images");
  try {
    missing.configure(kWidth, kHeight, kFrames);
    FAIL() << "configure() should throw without textures";
  } catch (const vpHSlamException &e) {
    EXPECT_EQ(e.getCode(), vpHSlamException::fileNotFound);
    EXPECT_NE(e.getStringMessage().find("/nonexistent/visp-images"), std::string::npos) << e.getStringMessage();
  }

  vpHSlamSyntheticScene scene;
  scene.configure(kWidth, kHeight, 2);
  const std::string blocker = tempDir("blocker");
  std::ofstream(blocker) << "a file, not a folder";
  try {
    scene.writeSequence(blocker + "/seq");
    FAIL() << "writeSequence() should throw under a file";
  } catch (const vpHSlamException &e) {
    EXPECT_NE(e.getStringMessage().find(blocker), std::string::npos) << e.getStringMessage();
  }
  vpIoTools::remove(blocker);
  EXPECT_THROW(scene.configure(kWidth, kHeight, 1), vpHSlamException);
  EXPECT_THROW(scene.getPose(2), vpHSlamException);
}
