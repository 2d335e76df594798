// vpHSlamRectifier: a synthetic pattern rendered through each distortion model must come back where the target
// pinhole camera puts it; crop has no invalid pixel and is tight; full keeps every input pixel; the pinhole/none
// case is the identity; misuse throws.
#include "CameraTestFixtures.h"
#include "HSlamTestData.h"

#include "camera/CameraModel.h"

#include <visp3/hslam/vpHSlamCamera.h>
#include <visp3/hslam/vpHSlamException.h>
#include <visp3/hslam/vpHSlamRectifier.h>

#include <cmath>
#include <iostream>
#include <random>
#include <vector>

using hslam_test::eurocRadTan;
using hslam_test::pincushionRadTan;
using hslam_test::pinholeVga;
using hslam_test::tumMonoFov;
using hslam_test::tumViEquidistant;

namespace
{
constexpr double kBackground = 30.0;
constexpr double kBlobAmplitude = 180.0;
constexpr double kBlobSigmaPx = 3.0;      // smallest blob size in rectified pixels
constexpr double kMinInputSigmaPx = 3.0;  // blobs are at least this wide in the input image (no aliasing)
constexpr double kBlobWindowSigmas = 4.0; // centroid window half-size
// Centroid accuracy, in input pixels (the rectified error mapped through the local input/rectified Jacobian: where
// a fisheye crop magnifies the input 5 times, bilinear interpolation errors are magnified too), and in rectified
// pixels.
constexpr double kCentroidTolInputPx = 0.05;
constexpr double kCentroidTolPx = 0.1;
constexpr unsigned int kMinBlobsChecked = 16;
constexpr double kPointTolPx = 1e-6;

vpHSlamCamera withMode(vpHSlamCamera cam, vpHSlamCamera::RectificationMode mode)
{
  cam.setRectification(mode);
  return cam;
}

struct Blob {
  double x, y;    // centre in rectified pixels
  double sigma;   // rectified pixels
  double J[2][2]; // d(input pixel)/d(rectified pixel) at the centre
};

// Blobs on an 8x6 grid of the rectified image at sub-pixel positions. Each is wide enough to be at least
// kMinInputSigmaPx input pixels wide where the rectified image magnifies the input (fisheye crops).
std::vector<Blob> blobGrid(const vpHSlamRectifier &r)
{
  std::vector<Blob> blobs;
  const int nx = 8, ny = 6;
  const double margin = 6.0 * kBlobSigmaPx;
  const unsigned int w = r.getWidth(), h = r.getHeight();
  for (int j = 0; j < ny; ++j) {
    for (int i = 0; i < nx; ++i) {
      Blob b;
      b.x = margin + (w - 1 - 2 * margin) * i / (nx - 1) + 0.37 * ((i + j) % 3) - 0.2;
      b.y = margin + (h - 1 - 2 * margin) * j / (ny - 1) + 0.29 * ((i + 2 * j) % 3) - 0.25;
      vpImagePoint c, cx, cy;
      if (!r.distortPoint(vpImagePoint(b.y, b.x), c) || !r.distortPoint(vpImagePoint(b.y, b.x + 1), cx) ||
          !r.distortPoint(vpImagePoint(b.y + 1, b.x), cy)) {
        continue;
      }
      // Smallest singular value of d(input)/d(target): the strongest compression, in any direction.
      const double ax = cx.get_u() - c.get_u(), ay = cx.get_v() - c.get_v();
      const double bx = cy.get_u() - c.get_u(), by = cy.get_v() - c.get_v();
      const double aa = ax * ax + ay * ay, bb = bx * bx + by * by, ab = ax * bx + ay * by;
      const double root = std::sqrt((aa - bb) * (aa - bb) + 4.0 * ab * ab);
      b.sigma = std::max(kBlobSigmaPx, kMinInputSigmaPx / std::sqrt(0.5 * (aa + bb - root)));
      b.J[0][0] = ax;
      b.J[1][0] = ay;
      b.J[0][1] = bx;
      b.J[1][1] = by;
      blobs.push_back(b);
    }
  }
  return blobs;
}

// Pattern intensity at rectified pixel (x, y): Gaussian blobs on a constant background, optionally without one.
double pattern(const std::vector<Blob> &blobs, double x, double y, const Blob *skip = nullptr)
{
  double value = kBackground;
  for (const Blob &b : blobs) {
    if (&b != skip) {
      const double dx = (x - b.x) / b.sigma, dy = (y - b.y) / b.sigma;
      value += kBlobAmplitude * std::exp(-0.5 * (dx * dx + dy * dy));
    }
  }
  return value;
}

// Render the pattern as the distorted camera sees it (one sample per pixel centre): the pattern lives on the
// z = 1 plane, where the target pinhole K maps it to rectified pixels.
vpImage<float> renderDistorted(const vpHSlamCamera &cam, const std::vector<Blob> &blobs, const vpCameraParameters &K)
{
  vpImage<float> I(cam.getHeight(), cam.getWidth(), static_cast<float>(kBackground));
  const auto model = hslam::makeCameraModel(cam);
  Eigen::Vector3d ray;
  for (unsigned int v = 0; v < cam.getHeight(); ++v) {
    for (unsigned int u = 0; u < cam.getWidth(); ++u) {
      if (model->unproject(Eigen::Vector2d(u, v), ray) && ray.z() > 0.0) {
        const double x = K.get_px() * ray.x() / ray.z() + K.get_u0();
        const double y = K.get_py() * ray.y() / ray.z() + K.get_v0();
        I[v][u] = static_cast<float>(pattern(blobs, x, y));
      }
    }
  }
  return I;
}

// Position error of one blob and the largest intensity error in its window; false when the window is not entirely
// made of valid rectified pixels. The other blobs' known contribution is removed, and the centroid is weighted by
// the blob's own Gaussian at its expected centre (a matched filter): a Gaussian shifted by e then has its weighted
// centroid at e / 2, while the far tails, where small interpolation errors have a long lever arm, barely count.
template <typename Type>
bool checkBlob(const vpImage<Type> &I, const vpImage<bool> &valid, const std::vector<Blob> &blobs, const Blob &b,
               double &centroidError, double &centroidErrorInput, double &intensityError)
{
  const int half = static_cast<int>(std::ceil(kBlobWindowSigmas * b.sigma));
  const int cx = static_cast<int>(std::lround(b.x)), cy = static_cast<int>(std::lround(b.y));
  if (cx - half < 0 || cy - half < 0 || cx + half >= static_cast<int>(I.getWidth()) ||
      cy + half >= static_cast<int>(I.getHeight())) {
    return false;
  }
  double sw = 0.0, sx = 0.0, sy = 0.0;
  intensityError = 0.0;
  for (int y = cy - half; y <= cy + half; ++y) {
    for (int x = cx - half; x <= cx + half; ++x) {
      if (!valid[y][x]) {
        return false;
      }
      const double dx = (x - b.x) / b.sigma, dy = (y - b.y) / b.sigma;
      const double wgt =
          (static_cast<double>(I[y][x]) - pattern(blobs, x, y, &b)) * std::exp(-0.5 * (dx * dx + dy * dy));
      intensityError = std::max(intensityError, std::abs(static_cast<double>(I[y][x]) - pattern(blobs, x, y)));
      sw += wgt;
      sx += wgt * x;
      sy += wgt * y;
    }
  }
  const double ex = 2.0 * (sx / sw - b.x), ey = 2.0 * (sy / sw - b.y);
  centroidError = std::hypot(ex, ey);
  centroidErrorInput = std::hypot(b.J[0][0] * ex + b.J[0][1] * ey, b.J[1][0] * ex + b.J[1][1] * ey);
  return true;
}

struct PatternResult {
  unsigned int blobsChecked = 0;
  double worstCentroidFloat = 0.0;      // rectified pixels
  double worstCentroidU8 = 0.0;         // rectified pixels
  double worstCentroidFloatInput = 0.0; // input pixels
  double worstCentroidU8Input = 0.0;    // input pixels
  double worstIntensityFloat = 0.0;     // |rectified - analytic| in the checked blobs' windows, intensity units
};

PatternResult measurePattern(const vpHSlamCamera &cam)
{
  const vpHSlamRectifier rectifier(cam);
  const vpCameraParameters K = rectifier.getCameraParameters();
  const std::vector<Blob> blobs = blobGrid(rectifier);
  const vpImage<float> If = renderDistorted(cam, blobs, K);
  vpImage<unsigned char> Iu8(If.getHeight(), If.getWidth());
  for (unsigned int k = 0; k < If.getSize(); ++k) {
    Iu8.bitmap[k] = static_cast<unsigned char>(std::lround(If.bitmap[k]));
  }
  vpImage<float> Rf;
  vpImage<unsigned char> Ru8;
  rectifier.rectify(If, Rf);
  rectifier.rectify(Iu8, Ru8);
  vpImage<bool> valid;
  rectifier.getValidMask(valid);

  PatternResult r;
  for (const Blob &b : blobs) {
    double errF = 0.0, errU8 = 0.0, errFInput = 0.0, errU8Input = 0.0, intensityF = 0.0, intensityU8 = 0.0;
    if (!checkBlob(Rf, valid, blobs, b, errF, errFInput, intensityF) ||
        !checkBlob(Ru8, valid, blobs, b, errU8, errU8Input, intensityU8)) {
      continue;
    }
    ++r.blobsChecked;
    r.worstCentroidFloat = std::max(r.worstCentroidFloat, errF);
    r.worstCentroidU8 = std::max(r.worstCentroidU8, errU8);
    r.worstCentroidFloatInput = std::max(r.worstCentroidFloatInput, errFInput);
    r.worstCentroidU8Input = std::max(r.worstCentroidU8Input, errU8Input);
    r.worstIntensityFloat = std::max(r.worstIntensityFloat, intensityF);
  }
  return r;
}

PatternResult checkPattern(const vpHSlamCamera &cam)
{
  PatternResult r = measurePattern(cam);
  std::cout << cam.toString() << ": " << r.blobsChecked << " blobs, centroid error float " << r.worstCentroidFloat
            << " px (" << r.worstCentroidFloatInput << " input px), 8-bit " << r.worstCentroidU8 << " px ("
            << r.worstCentroidU8Input << " input px), intensity error " << r.worstIntensityFloat << std::endl;
  return r;
}

bool insideInput(const vpHSlamCamera &cam, const vpImagePoint &ip, double tol)
{
  return ip.get_u() >= -tol && ip.get_u() <= cam.getWidth() - 1 + tol && ip.get_v() >= -tol &&
         ip.get_v() <= cam.getHeight() - 1 + tol;
}

// True when target pixel (x, y) maps inside the input image.
bool seesInput(const vpHSlamRectifier &r, double x, double y)
{
  vpImagePoint ip;
  return r.distortPoint(vpImagePoint(y, x), ip) && insideInput(r.getCamera(), ip, 1e-6);
}
} // namespace

TEST(Rectifier, PatternComesBackWherePinholeSaysRadTanCrop)
{
  const PatternResult r = checkPattern(eurocRadTan());
  EXPECT_GE(r.blobsChecked, kMinBlobsChecked);
  EXPECT_LT(r.worstCentroidFloat, kCentroidTolPx);
  EXPECT_LT(r.worstCentroidU8, kCentroidTolPx);
  EXPECT_LT(r.worstCentroidFloatInput, kCentroidTolInputPx);
  EXPECT_LT(r.worstCentroidU8Input, kCentroidTolInputPx);
  // Bilinear interpolation of 3 px Gaussians: a few percent of the amplitude at most.
  EXPECT_LT(r.worstIntensityFloat, 0.05 * kBlobAmplitude);
}

TEST(Rectifier, PatternComesBackWherePinholeSaysOtherModels)
{
  for (const vpHSlamCamera &cam :
       {pincushionRadTan(), tumViEquidistant(), tumMonoFov(), withMode(eurocRadTan(), vpHSlamCamera::rectifyFull)}) {
    const PatternResult r = checkPattern(cam);
    EXPECT_GE(r.blobsChecked, kMinBlobsChecked) << cam.toString();
    EXPECT_LT(r.worstCentroidFloat, kCentroidTolPx) << cam.toString();
    EXPECT_LT(r.worstCentroidU8, kCentroidTolPx) << cam.toString();
    EXPECT_LT(r.worstCentroidFloatInput, kCentroidTolInputPx) << cam.toString();
    EXPECT_LT(r.worstCentroidU8Input, kCentroidTolInputPx) << cam.toString();
    EXPECT_LT(r.worstIntensityFloat, 0.05 * kBlobAmplitude) << cam.toString();
  }
}

TEST(Rectifier, CropHasNoInvalidPixelAndIsTight)
{
  for (const vpHSlamCamera &cam : {eurocRadTan(), pincushionRadTan(), tumViEquidistant(), tumMonoFov()}) {
    const vpHSlamRectifier r(cam);
    EXPECT_EQ(r.getInvalidPixelCount(), 0u) << cam.toString();
    EXPECT_EQ(r.getWidth(), cam.getWidth());
    EXPECT_EQ(r.getHeight(), cam.getHeight());
    // Independent check through the point API: every target pixel sees the input image.
    unsigned int outside = 0;
    for (unsigned int y = 0; y < r.getHeight(); ++y) {
      for (unsigned int x = 0; x < r.getWidth(); ++x) {
        outside += seesInput(r, x, y) ? 0 : 1;
      }
    }
    EXPECT_EQ(outside, 0u) << cam.toString();
    // Tight: pushing any side out by 1 % of the image size uncovers a pixel outside the input.
    const double dx = 0.01 * r.getWidth(), dy = 0.01 * r.getHeight();
    bool leftTight = false, rightTight = false, topTight = false, bottomTight = false;
    for (unsigned int y = 0; y < r.getHeight(); ++y) {
      leftTight = leftTight || !seesInput(r, -dx, y);
      rightTight = rightTight || !seesInput(r, r.getWidth() - 1 + dx, y);
    }
    for (unsigned int x = 0; x < r.getWidth(); ++x) {
      topTight = topTight || !seesInput(r, x, -dy);
      bottomTight = bottomTight || !seesInput(r, x, r.getHeight() - 1 + dy);
    }
    EXPECT_TRUE(leftTight && rightTight && topTight && bottomTight) << cam.toString();
  }
}

TEST(Rectifier, CropShrinksWhereTheCornersAreInvalid)
{
  // For the pincushion lens the centre lines reach the image border but the corners do not: the crop must be
  // strictly inside the centre-line box on at least one dimension.
  const vpHSlamCamera cam = pincushionRadTan();
  const vpHSlamRectifier r(cam);
  vpImagePoint ip;
  ASSERT_TRUE(r.distortPoint(vpImagePoint(r.getCameraParameters().get_v0(), 0.0), ip));
  const bool leftShrunk = ip.get_u() > 1.0;
  ASSERT_TRUE(r.distortPoint(vpImagePoint(0.0, r.getCameraParameters().get_u0()), ip));
  const bool topShrunk = ip.get_v() > 1.0;
  EXPECT_TRUE(leftShrunk || topShrunk);
}

TEST(Rectifier, FullKeepsEveryInputPixel)
{
  const vpHSlamCamera cam = withMode(eurocRadTan(), vpHSlamCamera::rectifyFull);
  const vpHSlamRectifier r(cam);
  const double umax = r.getWidth() - 1.0, vmax = r.getHeight() - 1.0;
  double minU = 1e9, maxU = -1e9, minV = 1e9, maxV = -1e9;
  const auto check = [&](unsigned int u, unsigned int v) {
    vpImagePoint ip;
    ASSERT_TRUE(r.rectifyPoint(vpImagePoint(v, u), ip));
    minU = std::min(minU, ip.get_u());
    maxU = std::max(maxU, ip.get_u());
    minV = std::min(minV, ip.get_v());
    maxV = std::max(maxV, ip.get_v());
  };
  for (unsigned int u = 0; u < cam.getWidth(); ++u) {
    check(u, 0);
    check(u, cam.getHeight() - 1);
  }
  for (unsigned int v = 0; v < cam.getHeight(); ++v) {
    check(0, v);
    check(cam.getWidth() - 1, v);
  }
  // Every input border pixel (hence every input pixel) inside the target, and the box is tight.
  EXPECT_NEAR(minU, 0.0, kPointTolPx);
  EXPECT_NEAR(maxU, umax, kPointTolPx);
  EXPECT_NEAR(minV, 0.0, kPointTolPx);
  EXPECT_NEAR(maxV, vmax, kPointTolPx);
  // Barrel distortion: the full image has black regions along the sides, and the table's validity agrees with the
  // point API everywhere except within 1e-3 px of the input border.
  EXPECT_GT(r.getInvalidPixelCount(), 0u);
  vpImage<bool> valid;
  r.getValidMask(valid);
  unsigned int disagreements = 0;
  for (unsigned int y = 0; y < r.getHeight(); ++y) {
    for (unsigned int x = 0; x < r.getWidth(); ++x) {
      vpImagePoint ip;
      ASSERT_TRUE(r.distortPoint(vpImagePoint(y, x), ip));
      const bool inside = insideInput(cam, ip, 0.0);
      const bool nearBorder = insideInput(cam, ip, 1e-3) != insideInput(cam, ip, -1e-3);
      disagreements += (!nearBorder && inside != valid[y][x]) ? 1 : 0;
    }
  }
  EXPECT_EQ(disagreements, 0u);
}

TEST(Rectifier, FullRefusedBeyondNinetyDegrees)
{
  for (const vpHSlamCamera &cam :
       {withMode(tumViEquidistant(), vpHSlamCamera::rectifyFull), withMode(tumMonoFov(), vpHSlamCamera::rectifyFull)}) {
    try {
      vpHSlamRectifier r(cam);
      ADD_FAILURE() << "full rectification accepted for " << cam.toString();
    } catch (const vpHSlamException &e) {
      EXPECT_EQ(e.getCode(), vpHSlamException::unsupported);
      EXPECT_NE(e.getStringMessage().find("90 degrees"), std::string::npos) << e.getStringMessage();
    }
  }
}

TEST(Rectifier, PinholeNoneIsIdentity)
{
  const vpHSlamCamera cam = pinholeVga();
  const vpHSlamRectifier r(cam);
  EXPECT_TRUE(r.isPassThrough());
  const vpCameraParameters K = r.getCameraParameters();
  EXPECT_EQ(K.get_projModel(), vpCameraParameters::perspectiveProjWithoutDistortion);
  EXPECT_DOUBLE_EQ(K.get_px(), cam.getFx());
  EXPECT_DOUBLE_EQ(K.get_py(), cam.getFy());
  EXPECT_DOUBLE_EQ(K.get_u0(), cam.getCx());
  EXPECT_DOUBLE_EQ(K.get_v0(), cam.getCy());

  std::mt19937 rng(1);
  std::uniform_int_distribution<int> byte(0, 255);
  vpImage<unsigned char> I(cam.getHeight(), cam.getWidth());
  vpImage<float> If(cam.getHeight(), cam.getWidth());
  for (unsigned int k = 0; k < I.getSize(); ++k) {
    I.bitmap[k] = static_cast<unsigned char>(byte(rng));
    If.bitmap[k] = 0.25f * byte(rng);
  }
  vpImage<unsigned char> R;
  vpImage<float> Rf;
  r.rectify(I, R);
  r.rectify(If, Rf);
  EXPECT_TRUE(R == I);
  EXPECT_TRUE(Rf == If);
}

TEST(Rectifier, TableIsExactForPixelShifts)
{
  // Explicit targets of a pinhole input go through the remap table: a one-pixel shift is an exact copy and a
  // half-pixel shift the rounded mean of two neighbours.
  const vpHSlamCamera base = pinholeVga();
  std::mt19937 rng(2);
  std::uniform_int_distribution<int> byte(0, 255);
  vpImage<unsigned char> I(base.getHeight(), base.getWidth());
  vpImage<float> If(base.getHeight(), base.getWidth());
  for (unsigned int k = 0; k < I.getSize(); ++k) {
    I.bitmap[k] = static_cast<unsigned char>(byte(rng));
    If.bitmap[k] = static_cast<float>(I.bitmap[k]);
  }
  for (const double shift : {1.0, 0.5}) {
    vpHSlamCamera cam = base;
    vpCameraParameters K;
    K.initPersProjWithoutDistortion(cam.getFx(), cam.getFy(), cam.getCx() + shift, cam.getCy());
    cam.setRectification(vpHSlamCamera::rectifyExplicit, 0, 0, K);
    const vpHSlamRectifier r(cam);
    ASSERT_FALSE(r.isPassThrough());
    EXPECT_EQ(r.getInvalidPixelCount(), r.getHeight()) << "column 0 sees u = -shift";
    vpImage<unsigned char> R;
    vpImage<float> Rf;
    r.rectify(I, R);
    r.rectify(If, Rf);
    unsigned int wrong = 0, wrongF = 0;
    for (unsigned int y = 0; y < R.getHeight(); ++y) {
      EXPECT_EQ(R[y][0], 0) << "invalid pixels are 0";
      for (unsigned int x = 1; x < R.getWidth(); ++x) {
        const int a = I[y][x - 1], b = I[y][x];
        const int expected = shift == 1.0 ? a : (a + b + 1) / 2;
        wrong += R[y][x] == expected ? 0 : 1;
        const float expectedF = shift == 1.0 ? static_cast<float>(a) : 0.5f * (a + b);
        wrongF += std::abs(Rf[y][x] - expectedF) <= 1e-4f ? 0 : 1;
      }
    }
    EXPECT_EQ(wrong, 0u) << "shift " << shift;
    EXPECT_EQ(wrongF, 0u) << "shift " << shift;
  }
}

TEST(Rectifier, PointMapsRoundTrip)
{
  std::mt19937 rng(9);
  for (const vpHSlamCamera &cam : {eurocRadTan(), tumViEquidistant(), tumMonoFov()}) {
    const vpHSlamRectifier r(cam);
    std::uniform_real_distribution<double> ux(0.0, r.getWidth() - 1.0), uy(0.0, r.getHeight() - 1.0);
    double worst = 0.0;
    for (int k = 0; k < 1000; ++k) {
      const vpImagePoint target(uy(rng), ux(rng));
      vpImagePoint input, back;
      ASSERT_TRUE(r.distortPoint(target, input));
      ASSERT_TRUE(r.rectifyPoint(input, back));
      worst = std::max(worst, vpImagePoint::distance(target, back));
    }
    EXPECT_LT(worst, kPointTolPx) << cam.toString();
  }
}

TEST(Rectifier, WrongInputSizeThrowsNamingBothSizes)
{
  const vpHSlamRectifier r(eurocRadTan());
  vpImage<unsigned char> I(481, 640), R;
  try {
    r.rectify(I, R);
    ADD_FAILURE() << "wrong size accepted";
  } catch (const vpHSlamException &e) {
    EXPECT_EQ(e.getCode(), vpHSlamException::invalidImage);
    EXPECT_NE(e.getStringMessage().find("640x481"), std::string::npos) << e.getStringMessage();
    EXPECT_NE(e.getStringMessage().find("752x480"), std::string::npos) << e.getStringMessage();
  }
  vpImage<float> If(480, 751), Rf;
  EXPECT_THROW(r.rectify(If, Rf), vpHSlamException);
  vpImage<unsigned char> J(480, 752);
  EXPECT_THROW(r.rectify(J, J), vpHSlamException) << "in place";
}

TEST(Rectifier, NoReallocationAndCopiesAgree)
{
  const vpHSlamRectifier r(eurocRadTan());
  vpImage<unsigned char> I(480, 752, 77), R;
  r.rectify(I, R);
  ASSERT_EQ(R.getWidth(), r.getWidth());
  const unsigned char *before = R.bitmap;
  r.rectify(I, R);
  EXPECT_EQ(R.bitmap, before) << "an output of the right size is reused";
  for (unsigned int k = 0; k < R.getSize(); ++k) {
    ASSERT_EQ(R.bitmap[k], 77) << "a constant image stays constant";
  }
  const vpHSlamRectifier copy(r);
  vpHSlamRectifier assigned(vpHSlamCamera{});
  assigned = copy;
  vpImage<unsigned char> R2;
  assigned.rectify(I, R2);
  EXPECT_TRUE(R2 == R);
  EXPECT_DOUBLE_EQ(assigned.getCameraParameters().get_px(), r.getCameraParameters().get_px());
}

TEST(Rectifier, NoneOnDistortedInputKeepsInputIntrinsics)
{
  // DSO "none" with a distorted input: the target is the input's own pinhole intrinsics, still undistorted.
  const vpHSlamCamera cam = withMode(eurocRadTan(), vpHSlamCamera::rectifyNone);
  const vpHSlamRectifier r(cam);
  EXPECT_FALSE(r.isPassThrough());
  const vpCameraParameters K = r.getCameraParameters();
  EXPECT_DOUBLE_EQ(K.get_px(), cam.getFx());
  EXPECT_DOUBLE_EQ(K.get_v0(), cam.getCy());
  vpImagePoint ip;
  ASSERT_TRUE(r.distortPoint(vpImagePoint(cam.getCy(), cam.getCx()), ip));
  EXPECT_NEAR(ip.get_u(), cam.getCx(), kPointTolPx);
  EXPECT_NEAR(ip.get_v(), cam.getCy(), kPointTolPx);
  // Barrel distortion: the same-focal pinhole image is a zoom into the input, every pixel is valid.
  EXPECT_EQ(r.getInvalidPixelCount(), 0u);
}
