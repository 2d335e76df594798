// Geometric camera models: round trips over the whole image, Jacobians against numeric differences, agreement
// with OpenCV's projectPoints / fisheye::projectPoints, and calibration validation.
#include "CameraTestFixtures.h"
#include "HSlamTestData.h"

#include "camera/CameraModel.h"

#include <visp3/hslam/vpHSlamCamera.h>
#include <visp3/hslam/vpHSlamException.h>

#include <Eigen/Geometry>

#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>

#include <cmath>
#include <functional>
#include <limits>
#include <memory>
#include <random>

using hslam_test::eurocRadTan;
using hslam_test::pinholeVga;
using hslam_test::radTanK3;
using hslam_test::tumMonoFov;
using hslam_test::tumViEquidistant;

namespace
{
constexpr double kPi = 3.14159265358979323846;
constexpr unsigned int kGridStep = 4;    // every 4th pixel of the image
constexpr double kRoundTripTolPx = 1e-6; // required round-trip accuracy
constexpr double kOpenCvTolPx = 1e-6;    // agreement with OpenCV
constexpr double kNumericStep = 1e-6;    // central differences, relative to |p|
constexpr double kJacobianRelTol = 1e-5; // numeric vs analytic Jacobian, relative to the largest entry
constexpr int kRandomPoints = 2000;

struct RoundTripStats {
  unsigned int tested = 0;
  unsigned int unprojected = 0;
  double maxErrorPx = 0.0;
};

// pixel -> ray -> pixel over the image grid of the camera's model; also checks the ray has unit norm.
RoundTripStats pixelRoundTrip(const vpHSlamCamera &cam)
{
  const auto model = hslam::makeCameraModel(cam);
  RoundTripStats s;
  for (unsigned int v = 0; v < cam.getHeight(); v += kGridStep) {
    for (unsigned int u = 0; u < cam.getWidth(); u += kGridStep) {
      ++s.tested;
      const Eigen::Vector2d uv(u, v);
      Eigen::Vector3d ray;
      if (!model->unproject(uv, ray)) {
        continue;
      }
      ++s.unprojected;
      EXPECT_NEAR(ray.norm(), 1.0, 1e-12);
      Eigen::Vector2d back;
      if (!model->project(ray, back)) {
        ADD_FAILURE() << "pixel (" << u << ", " << v << ") unprojects but its ray does not project";
        continue;
      }
      s.maxErrorPx = std::max(s.maxErrorPx, (back - uv).norm());
    }
  }
  return s;
}

// Random rays whose projection lands in the image (and in the model's domain).
std::vector<Eigen::Vector3d> randomPointsInImage(const hslam::CameraModel &model, unsigned int width,
                                                 unsigned int height, std::mt19937 &rng, bool frontOnly)
{
  std::uniform_real_distribution<double> pu(0.0, width - 1.0), pv(0.0, height - 1.0), depth(0.5, 10.0);
  std::vector<Eigen::Vector3d> points;
  while (points.size() < static_cast<std::size_t>(kRandomPoints)) {
    Eigen::Vector3d ray;
    if (!model.unproject(Eigen::Vector2d(pu(rng), pv(rng)), ray) || (frontOnly && ray.z() < 0.1)) {
      continue;
    }
    points.push_back(depth(rng) * ray);
  }
  return points;
}

double jacobianError(const hslam::CameraModel &model, const Eigen::Vector3d &p)
{
  Eigen::Vector2d uv;
  Eigen::Matrix<double, 2, 3> J;
  EXPECT_TRUE(model.project(p, uv, &J));
  Eigen::Matrix<double, 2, 3> Jnum;
  const double h = kNumericStep * p.norm();
  for (int i = 0; i < 3; ++i) {
    Eigen::Vector3d dp = Eigen::Vector3d::Zero();
    dp[i] = h;
    Eigen::Vector2d up, um;
    EXPECT_TRUE(model.project(p + dp, up));
    EXPECT_TRUE(model.project(p - dp, um));
    Jnum.col(i) = (up - um) / (2.0 * h);
  }
  Eigen::Vector2d uvNoJ;
  model.project(p, uvNoJ);
  EXPECT_EQ(uv, uvNoJ) << "asking for the Jacobian must not change the projection";
  return (J - Jnum).cwiseAbs().maxCoeff() / J.cwiseAbs().maxCoeff();
}

cv::Matx33d cvK(const vpHSlamCamera &cam)
{
  return cv::Matx33d(cam.getFx(), 0, cam.getCx(), 0, cam.getFy(), cam.getCy(), 0, 0, 1);
}
} // namespace

TEST(CameraModels, PinholeRoundTripWholeImage)
{
  const vpHSlamCamera cam = pinholeVga();
  const auto model = hslam::makeCameraModel(cam);
  const RoundTripStats s = pixelRoundTrip(cam);
  EXPECT_EQ(s.unprojected, s.tested);
  EXPECT_LT(s.maxErrorPx, kRoundTripTolPx);
  Eigen::Vector2d uv;
  EXPECT_FALSE(model->project(Eigen::Vector3d(0.1, 0.2, -1.0), uv)) << "behind the camera";
}

TEST(CameraModels, RadTanEurocRoundTripWholeImage)
{
  const vpHSlamCamera cam = eurocRadTan();
  const RoundTripStats s = pixelRoundTrip(cam);
  EXPECT_EQ(s.unprojected, s.tested) << "every EuRoC pixel lies in the monotonic domain";
  EXPECT_LT(s.maxErrorPx, kRoundTripTolPx);
}

TEST(CameraModels, RadTanK3RoundTripWholeImage)
{
  const vpHSlamCamera cam = radTanK3();
  const RoundTripStats s = pixelRoundTrip(cam);
  EXPECT_EQ(s.unprojected, s.tested);
  EXPECT_LT(s.maxErrorPx, kRoundTripTolPx);
}

TEST(CameraModels, EquidistantTumViRoundTripWholeImage)
{
  const vpHSlamCamera cam = tumViEquidistant();
  const auto model = hslam::makeCameraModel(cam);
  const RoundTripStats s = pixelRoundTrip(cam);
  EXPECT_EQ(s.unprojected, s.tested) << "TUM-VI corners see beyond 90 degrees but stay in the domain";
  EXPECT_LT(s.maxErrorPx, kRoundTripTolPx);
  // The corners of this lens look behind the image plane: rays with z < 0 must exist and round-trip.
  Eigen::Vector3d ray;
  ASSERT_TRUE(model->unproject(Eigen::Vector2d(0.0, 0.0), ray));
  EXPECT_LT(ray.z(), 0.0);
}

TEST(CameraModels, FovTumMonoRoundTripWholeImage)
{
  const vpHSlamCamera cam = tumMonoFov();
  const RoundTripStats s = pixelRoundTrip(cam);
  EXPECT_LT(s.maxErrorPx, kRoundTripTolPx);
  // Independent count of the pixels inside the FOV model's 90 degree horizon: r_d * omega < pi / 2.
  const double omega = cam.getDistortion()[0];
  unsigned int inside = 0;
  for (unsigned int v = 0; v < cam.getHeight(); v += kGridStep) {
    for (unsigned int u = 0; u < cam.getWidth(); u += kGridStep) {
      const double mx = (u - cam.getCx()) / cam.getFx(), my = (v - cam.getCy()) / cam.getFy();
      inside += std::sqrt(mx * mx + my * my) * omega < 0.5 * kPi ? 1 : 0;
    }
  }
  EXPECT_EQ(s.unprojected, inside);
  EXPECT_LT(s.unprojected, s.tested) << "TUM monoVO corners are beyond the FOV model's horizon";
  EXPECT_GT(s.unprojected, s.tested * 9 / 10);
}

TEST(CameraModels, ProjectUnprojectRandomPoints)
{
  std::mt19937 rng(42);
  for (const vpHSlamCamera &cam : {pinholeVga(), eurocRadTan(), radTanK3(), tumViEquidistant(), tumMonoFov()}) {
    const auto model = hslam::makeCameraModel(cam);
    double maxAngle = 0.0;
    for (const Eigen::Vector3d &p : randomPointsInImage(*model, cam.getWidth(), cam.getHeight(), rng, false)) {
      Eigen::Vector2d uv;
      Eigen::Vector3d ray;
      ASSERT_TRUE(model->project(p, uv));
      ASSERT_TRUE(model->unproject(uv, ray));
      // sin of the angle between the ray and the point (acos is too imprecise near 0)
      maxAngle = std::max(maxAngle, ray.cross(p.normalized()).norm());
    }
    EXPECT_LT(maxAngle, 1e-9) << cam.toString();
  }
}

TEST(CameraModels, JacobiansMatchNumericDifferences)
{
  std::mt19937 rng(7);
  for (const vpHSlamCamera &cam : {pinholeVga(), eurocRadTan(), radTanK3(), tumViEquidistant(), tumMonoFov()}) {
    const auto model = hslam::makeCameraModel(cam);
    double worst = 0.0;
    for (const Eigen::Vector3d &p : randomPointsInImage(*model, cam.getWidth(), cam.getHeight(), rng, false)) {
      worst = std::max(worst, jacobianError(*model, p));
    }
    EXPECT_LT(worst, kJacobianRelTol) << cam.toString();
    // Near the optical axis (series / pinhole branches of the equidistant and FOV models).
    for (const Eigen::Vector3d &p : {Eigen::Vector3d(1e-5, -2e-5, 1.0), Eigen::Vector3d(3e-4, 1e-4, 2.0)}) {
      EXPECT_LT(jacobianError(*model, p), kJacobianRelTol) << cam.toString() << " at " << p.transpose();
    }
  }
}

TEST(CameraModels, RadTanMatchesOpenCvProjectPoints)
{
  std::mt19937 rng(3);
  for (const vpHSlamCamera &cam : {eurocRadTan(), radTanK3()}) {
    const auto model = hslam::makeCameraModel(cam);
    const std::vector<Eigen::Vector3d> points = randomPointsInImage(*model, cam.getWidth(), cam.getHeight(), rng, true);
    std::vector<cv::Point3d> object;
    for (const Eigen::Vector3d &p : points) {
      object.emplace_back(p.x(), p.y(), p.z());
    }
    std::vector<double> dist = cam.getDistortion();
    std::vector<cv::Point2d> image;
    cv::projectPoints(object, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), cvK(cam), dist, image);
    double worst = 0.0;
    for (std::size_t i = 0; i < points.size(); ++i) {
      Eigen::Vector2d uv;
      ASSERT_TRUE(model->project(points[i], uv));
      worst = std::max(worst, (uv - Eigen::Vector2d(image[i].x, image[i].y)).norm());
    }
    EXPECT_LT(worst, kOpenCvTolPx) << cam.toString();
  }
}

TEST(CameraModels, EquidistantMatchesOpenCvFisheyeProjectPoints)
{
  std::mt19937 rng(5);
  const vpHSlamCamera cam = tumViEquidistant();
  const auto model = hslam::makeCameraModel(cam);
  // OpenCV's fisheye model divides by z: compare in front of the camera only.
  const std::vector<Eigen::Vector3d> points = randomPointsInImage(*model, cam.getWidth(), cam.getHeight(), rng, true);
  std::vector<cv::Point3d> object;
  for (const Eigen::Vector3d &p : points) {
    object.emplace_back(p.x(), p.y(), p.z());
  }
  std::vector<cv::Point2d> image;
  cv::fisheye::projectPoints(
      object, image, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), cvK(cam),
      cv::Vec4d(cam.getDistortion()[0], cam.getDistortion()[1], cam.getDistortion()[2], cam.getDistortion()[3]));
  double worst = 0.0;
  for (std::size_t i = 0; i < points.size(); ++i) {
    Eigen::Vector2d uv;
    ASSERT_TRUE(model->project(points[i], uv));
    worst = std::max(worst, (uv - Eigen::Vector2d(image[i].x, image[i].y)).norm());
  }
  EXPECT_LT(worst, kOpenCvTolPx);
}

TEST(CameraModels, FovMatchesDsoFormula)
{
  // r_d = atan(2 r tan(omega / 2)) / omega (DSO UndistortFOV), evaluated by hand for one point.
  const vpHSlamCamera cam = tumMonoFov();
  const auto model = hslam::makeCameraModel(cam);
  const double omega = cam.getDistortion()[0];
  const Eigen::Vector3d p(0.3, -0.2, 1.0);
  const double r = std::hypot(p.x(), p.y());
  const double factor = std::atan(2.0 * r * std::tan(0.5 * omega)) / (omega * r);
  Eigen::Vector2d uv;
  ASSERT_TRUE(model->project(p, uv));
  EXPECT_NEAR(uv.x(), cam.getFx() * factor * p.x() + cam.getCx(), 1e-9);
  EXPECT_NEAR(uv.y(), cam.getFy() * factor * p.y() + cam.getCy(), 1e-9);
}

TEST(CameraModels, DomainLimits)
{
  // A radtan lens with strong barrel distortion folds at a finite radius: beyond it projection is refused.
  const hslam::RadTanModel folding(500, 500, 320, 240, -0.5, 0.0, 0.0, 0.0);
  const double expectedFold = std::sqrt(1.0 / 1.5); // 1 + 3 k1 r^2 = 0
  EXPECT_NEAR(folding.maxRadius(), expectedFold, 1e-9);
  Eigen::Vector2d uv;
  EXPECT_TRUE(folding.project(Eigen::Vector3d(0.99 * expectedFold, 0.0, 1.0), uv));
  EXPECT_FALSE(folding.project(Eigen::Vector3d(1.01 * expectedFold, 0.0, 1.0), uv));
  // Unprojection beyond the folded image radius is refused rather than answering a wrong ray.
  Eigen::Vector3d ray;
  const double rdMax = expectedFold * (1.0 - 0.5 * expectedFold * expectedFold);
  EXPECT_FALSE(folding.unproject(Eigen::Vector2d(320 + 500 * rdMax * 1.05, 240), ray));
  EXPECT_TRUE(folding.unproject(Eigen::Vector2d(320 + 500 * rdMax * 0.95, 240), ray));

  // FOV: nothing at or behind 90 degrees.
  const hslam::FovModel fovModel(400, 400, 320, 240, 0.93);
  EXPECT_FALSE(fovModel.project(Eigen::Vector3d(1.0, 0.0, 0.0), uv));
  EXPECT_FALSE(fovModel.project(Eigen::Vector3d(1.0, 0.0, -1.0), uv));

  // Equidistant without distortion sees up to 180 degrees.
  const hslam::EquidistantModel equi(200, 200, 256, 256, 0, 0, 0, 0);
  EXPECT_NEAR(equi.maxTheta(), kPi, 1e-9);
  ASSERT_TRUE(equi.project(Eigen::Vector3d(1.0, 0.0, -1.0), uv)); // 135 degrees
  EXPECT_NEAR(uv.x(), 256 + 200 * 0.75 * kPi, 1e-9);
}

TEST(CameraModels, FactoryBuildsEachModel)
{
  EXPECT_EQ(hslam::makeCameraModel(pinholeVga())->model(), vpHSlamCamera::pinhole);
  EXPECT_EQ(hslam::makeCameraModel(eurocRadTan())->model(), vpHSlamCamera::radialTangential);
  EXPECT_EQ(hslam::makeCameraModel(tumViEquidistant())->model(), vpHSlamCamera::equidistant);
  EXPECT_EQ(hslam::makeCameraModel(tumMonoFov())->model(), vpHSlamCamera::fov);
  const auto m = hslam::makeCameraModel(eurocRadTan());
  EXPECT_DOUBLE_EQ(m->fx(), 458.654);
  EXPECT_DOUBLE_EQ(m->cy(), 248.375);
}

// ---------------------------------------------------------------------------------------------------------------
// vpHSlamCamera

namespace
{
void expectInvalid(const std::function<void()> &build, const std::string &mustMention)
{
  try {
    build();
    ADD_FAILURE() << "expected vpHSlamException::invalidCalibration mentioning '" << mustMention << "'";
  } catch (const vpHSlamException &e) {
    EXPECT_EQ(e.getCode(), vpHSlamException::invalidCalibration);
    EXPECT_NE(e.getStringMessage().find(mustMention), std::string::npos) << e.getStringMessage();
  }
}
} // namespace

TEST(HSlamCamera, InvalidParametersThrow)
{
  using C = vpHSlamCamera;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  expectInvalid([] { C(C::pinhole, 0, 480, 500, 500, 320, 240); }, "0x480");
  expectInvalid([] { C(C::pinhole, 640, 1, 500, 500, 320, 240); }, "640x1");
  expectInvalid([] { C(C::pinhole, 640, 480, -500, 500, 320, 240); }, "focal");
  expectInvalid([] { C(C::pinhole, 640, 480, 500, 0, 320, 240); }, "focal");
  expectInvalid([nan] { C(C::pinhole, 640, 480, 500, 500, nan, 240); }, "principal point");
  expectInvalid([] { C(C::pinhole, 640, 480, 500, 500, 320, 240, {0.1}); }, "got 1");
  expectInvalid([] { C(C::radialTangential, 640, 480, 500, 500, 320, 240, {0.1, 0.1, 0.0}); }, "4 or 5");
  expectInvalid([] { C(C::radialTangential, 640, 480, 500, 500, 320, 240, {0.1, 0.1, 0, 0, 0, 0}); }, "got 6");
  expectInvalid([] { C(C::equidistant, 640, 480, 500, 500, 320, 240, {0.1, 0.1, 0.0, 0, 0}); }, "expects 4");
  expectInvalid([nan] { C(C::equidistant, 640, 480, 500, 500, 320, 240, {0.1, nan, 0, 0}); }, "not finite");
  expectInvalid([] { C(C::fov, 640, 480, 500, 500, 320, 240, {0.0}); }, "omega");
  expectInvalid([] { C(C::fov, 640, 480, 500, 500, 320, 240, {3.2}); }, "omega");
  expectInvalid([] { C(C::fov, 640, 480, 500, 500, 320, 240, {}); }, "FOV");
  expectInvalid([] { C(static_cast<C::Model>(17), 640, 480, 500, 500, 320, 240); }, "unknown camera model");
  // Positive but too small for ViSP to invert: refused at construction, so getIntrinsics() never throws later.
  expectInvalid([] { C(C::pinhole, 640, 480, 1e-320, 500, 320, 240); }, "refused by ViSP");

  C cam = eurocRadTan();
  expectInvalid([&cam] { cam.setRectification(C::rectifyNone, 640, 480); }, "752x480");
  vpCameraParameters negative;
  negative.initPersProjWithoutDistortion(-300.0, 300.0, 320.0, 240.0);
  expectInvalid([&cam, &negative] { cam.setRectification(C::rectifyExplicit, 640, 480, negative); }, "explicit");
  expectInvalid([&cam] { cam.setRectification(C::rectifyCrop, 1, 480); }, "1x480");
  EXPECT_EQ(cam.getRectificationMode(), C::rectifyCrop) << "a refused setRectification leaves the camera unchanged";
}

TEST(HSlamCamera, DefaultsAndAccessors)
{
  const vpHSlamCamera def;
  EXPECT_EQ(def.getModel(), vpHSlamCamera::pinhole);
  EXPECT_EQ(def.getWidth(), 640u);
  EXPECT_EQ(def.getHeight(), 480u);
  EXPECT_DOUBLE_EQ(def.getCx(), 319.5);
  EXPECT_EQ(def.getRectificationMode(), vpHSlamCamera::rectifyNone);

  vpHSlamCamera cam = eurocRadTan();
  EXPECT_EQ(cam.getRectificationMode(), vpHSlamCamera::rectifyCrop);
  EXPECT_EQ(cam.getRectifiedWidth(), 752u);
  EXPECT_EQ(cam.getRectifiedHeight(), 480u);
  const vpCameraParameters K = cam.getIntrinsics();
  EXPECT_EQ(K.get_projModel(), vpCameraParameters::perspectiveProjWithoutDistortion);
  EXPECT_DOUBLE_EQ(K.get_px(), 458.654);
  EXPECT_DOUBLE_EQ(K.get_py(), 457.296);
  EXPECT_DOUBLE_EQ(K.get_u0(), 367.215);
  EXPECT_DOUBLE_EQ(K.get_v0(), 248.375);

  vpCameraParameters target;
  target.initPersProjWithoutDistortion(300, 300, 200, 150);
  cam.setRectification(vpHSlamCamera::rectifyExplicit, 400, 300, target);
  EXPECT_EQ(cam.getRectificationMode(), vpHSlamCamera::rectifyExplicit);
  EXPECT_EQ(cam.getRectifiedWidth(), 400u);
  EXPECT_DOUBLE_EQ(cam.getExplicitRectifiedIntrinsics().get_u0(), 200.0);
  cam.setRectification(vpHSlamCamera::rectifyFull);
  EXPECT_EQ(cam.getRectifiedWidth(), 752u) << "0 keeps the input size";

  EXPECT_EQ(vpHSlamCamera::modelName(vpHSlamCamera::pinhole), "Pinhole");
  EXPECT_EQ(vpHSlamCamera::modelName(vpHSlamCamera::radialTangential), "RadTan");
  EXPECT_EQ(vpHSlamCamera::modelName(vpHSlamCamera::equidistant), "EquiDistant");
  EXPECT_EQ(vpHSlamCamera::modelName(vpHSlamCamera::fov), "FOV");
  const std::string text = tumMonoFov().toString();
  EXPECT_NE(text.find("FOV 1280x1024"), std::string::npos) << text;
  EXPECT_NE(text.find("0.932"), std::string::npos) << text;
  EXPECT_NE(text.find("crop"), std::string::npos) << text;
}

TEST(HSlamCamera, ProjectUnprojectThroughPublicApi)
{
  const vpHSlamCamera cam = eurocRadTan();
  vpColVector ray;
  ASSERT_TRUE(cam.unproject(vpImagePoint(400.25, 700.5), ray)); // (i, j) = (v, u)
  ASSERT_EQ(ray.size(), 3u);
  EXPECT_DOUBLE_EQ(ray[2], 1.0);
  vpImagePoint ip;
  vpColVector cP(3);
  cP[0] = 2.0 * ray[0];
  cP[1] = 2.0 * ray[1];
  cP[2] = 2.0;
  ASSERT_TRUE(cam.project(cP, ip));
  EXPECT_NEAR(ip.get_u(), 700.5, kRoundTripTolPx);
  EXPECT_NEAR(ip.get_v(), 400.25, kRoundTripTolPx);
  vpColVector cPh(4);
  cPh[0] = cP[0];
  cPh[1] = cP[1];
  cPh[2] = cP[2];
  cPh[3] = 1.0;
  ASSERT_TRUE(cam.project(cPh, ip));
  EXPECT_NEAR(ip.get_u(), 700.5, kRoundTripTolPx);
  cP[2] = -2.0;
  EXPECT_FALSE(cam.project(cP, ip)) << "behind the camera";
  EXPECT_THROW(cam.project(vpColVector(2), ip), vpHSlamException);

  // TUM-VI: a corner ray beyond 90 degrees cannot be normalised to z = 1.
  EXPECT_FALSE(tumViEquidistant().unproject(vpImagePoint(0, 0), ray));
  EXPECT_TRUE(tumViEquidistant().unproject(vpImagePoint(256, 256), ray));
}
