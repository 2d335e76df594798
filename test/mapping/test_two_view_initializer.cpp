// Two-view monocular initializer: exact synthetic scene, real sequences (7-Scenes, Tsukuba CG, KITTI 06) against
// their ground truth, degenerate inputs (static camera, pure rotation), the sub-pixel match refinement and the sparse
// inverse-depth interpolator.
#include "HSlamTestData.h"

#include "mapping/InitializationCheck.h"
#include "mapping/MatchRefinement.h"
#include "mapping/SparseIdepthInterpolator.h"
#include "mapping/TwoViewGeometry.h"
#include "mapping/TwoViewInitializer.h"
#include "math/ViSPConversions.h"

#include <visp3/hslam/vpHSlamException.h>
#include <visp3/hslam/vpHSlamSyntheticScene.h>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <Eigen/Geometry>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

using namespace hslam;

namespace
{
constexpr double kRadToDeg = 180. / M_PI;

//! Frames of a sequence with camera-to-world ground truth (wMc, any unit of length).
struct Sequence {
  std::vector<std::string> images;
  std::vector<SE3d> wMc;
  PinholeIntrinsics K;
};

std::vector<std::vector<std::string>> readTable(const std::string &path)
{
  std::ifstream in(path);
  std::vector<std::vector<std::string>> rows;
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') {
      continue;
    }
    std::istringstream ss(line);
    std::vector<std::string> fields;
    std::string f;
    while (ss >> f) {
      fields.push_back(f);
    }
    rows.push_back(fields);
  }
  return rows;
}

std::vector<SE3d> readTumPoses(const std::string &path)
{
  std::vector<SE3d> poses;
  for (const auto &r : readTable(path)) {
    const Eigen::Quaterniond q(std::stod(r[7]), std::stod(r[4]), std::stod(r[5]), std::stod(r[6]));
    poses.emplace_back(q, Eigen::Vector3d(std::stod(r[1]), std::stod(r[2]), std::stod(r[3])));
  }
  return poses;
}

//! TUM RGB-D layout: rgb.txt and groundtruth.txt share the index (timestamps index / 30 in both folders).
Sequence loadTumRgbd(const std::string &dir, double f, double cx, double cy)
{
  Sequence s;
  for (const auto &r : readTable(dir + "/rgb.txt")) {
    s.images.push_back(dir + "/" + r[1]);
  }
  s.wMc = readTumPoses(dir + "/groundtruth.txt");
  s.K = {f, f, cx, cy};
  return s;
}

Sequence loadKitti(const std::string &dir)
{
  Sequence s;
  s.wMc = readTumPoses(dir + "/groundtruth_tum.txt");
  for (size_t i = 0; i < s.wMc.size(); ++i) {
    char name[64];
    std::snprintf(name, sizeof(name), "/image_0/%06zu.png", i);
    s.images.push_back(dir + name);
  }
  for (const auto &r : readTable(dir + "/calib.txt")) {
    if (r[0] == "P0:") {
      s.K = {std::stod(r[1]), std::stod(r[6]), std::stod(r[3]), std::stod(r[7])};
    }
  }
  return s;
}

vpImage<unsigned char> loadGrey(const std::string &path)
{
  const cv::Mat m = cv::imread(path, cv::IMREAD_GRAYSCALE);
  vpImage<unsigned char> I(static_cast<unsigned int>(m.rows), static_cast<unsigned int>(m.cols));
  for (int y = 0; y < m.rows; ++y) {
    std::copy(m.ptr<unsigned char>(y), m.ptr<unsigned char>(y) + m.cols, I[static_cast<unsigned int>(y)]);
  }
  return I;
}

double rotationAngleDeg(const Eigen::Matrix3d &R)
{
  return Eigen::AngleAxisd(R).angle() * kRadToDeg;
}

double angleBetweenDeg(const Eigen::Vector3d &a, const Eigen::Vector3d &b)
{
  return std::acos(std::max(-1., std::min(1., a.normalized().dot(b.normalized())))) * kRadToDeg;
}

double median(std::vector<double> v)
{
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
  return v[v.size() / 2];
}

//! Errors of an initialisation against the true relative pose c2Mc1 (metric or any unit).
struct Errors {
  double rotationDeg = 0., translationDirDeg = 0., medianDepthRelErr = 0.;
};

/*!
  Pose errors, and depth errors after scale alignment (median ratio) against \e trueDepths (one per point;
  values <= 0 are skipped).
*/
Errors evaluate(const TwoViewInitialization &r, const SE3d &c2Mc1True, const std::vector<double> &trueDepths)
{
  Errors e;
  e.rotationDeg = rotationAngleDeg(r.c2Mc1.rotationMatrix() * c2Mc1True.rotationMatrix().transpose());
  e.translationDirDeg = angleBetweenDeg(r.c2Mc1.translation(), c2Mc1True.translation());
  std::vector<double> ratios;
  for (size_t i = 0; i < r.points.size(); ++i) {
    if (trueDepths[i] > 0.) {
      ratios.push_back(trueDepths[i] * r.points[i].idepth);
    }
  }
  const double scale = median(ratios);
  std::vector<double> relErr;
  for (size_t i = 0; i < r.points.size(); ++i) {
    if (trueDepths[i] > 0.) {
      relErr.push_back(std::abs(scale / r.points[i].idepth - trueDepths[i]) / trueDepths[i]);
    }
  }
  e.medianDepthRelErr = median(relErr);
  return e;
}

/*!
  Real sequences have no depth maps here: the reference depth of a point is its match triangulated with the TRUE
  relative pose. It shares the matching noise with the estimate, so this checks the pose and the triangulation,
  not the matcher.
*/
std::vector<double> depthsFromTruePose(const TwoViewInitialization &r, const SE3d &c2Mc1True,
                                       const PinholeIntrinsics &K)
{
  std::vector<double> depths;
  for (const InitialPoint &p : r.points) {
    Eigen::Vector3d X1;
    const Eigen::Vector2d x1((p.u - K.cx) / K.fx, (p.v - K.cy) / K.fy);
    const Eigen::Vector2d x2((p.uCur - K.cx) / K.fx, (p.vCur - K.cy) / K.fy);
    const bool ok = triangulateLinear(x1, x2, c2Mc1True.rotationMatrix(), c2Mc1True.translation(), X1);
    depths.push_back(ok && X1.z() > 0. ? X1.z() : -1.);
  }
  return depths;
}

//! Median epipolar (Sampson) error of the initial points' matches under the relative pose c2Mc1, pixels.
double medianSampsonErrorPx(const TwoViewInitialization &r, const SE3d &c2Mc1, const PinholeIntrinsics &K)
{
  const Eigen::Matrix3d Kinv = (Eigen::Matrix3d() << K.fx, 0, K.cx, 0, K.fy, K.cy, 0, 0, 1).finished().inverse();
  const Eigen::Vector3d t = c2Mc1.translation();
  Eigen::Matrix3d tx;
  tx << 0, -t.z(), t.y(), t.z(), 0, -t.x(), -t.y(), t.x(), 0;
  const Eigen::Matrix3d F = Kinv.transpose() * tx * c2Mc1.rotationMatrix() * Kinv;
  std::vector<double> e;
  for (const InitialPoint &p : r.points) {
    const Eigen::Vector3d x1(p.u, p.v, 1.), x2(p.uCur, p.vCur, 1.);
    const Eigen::Vector3d l2 = F * x1, l1 = F.transpose() * x2;
    e.push_back(std::abs(x2.dot(l2)) / std::sqrt(l2.head<2>().squaredNorm() + l1.head<2>().squaredNorm()));
  }
  return median(e);
}

struct RealRun {
  double sampsonEstimatePx = 0., sampsonTruthPx = 0.; //!< median epipolar error of the points under each pose
  bool initialized = false;
  std::vector<double> addFrameMs; //!< time of each addFrame() call
  int frame = -1;
  int firstFrame = -1;
  TwoViewInitialization result;
  Errors errors;
};

RealRun runOnSequence(const Sequence &seq, int lastFrame, const char *name, double minParallaxDeg = 1.0, int stride = 1)
{
  vpHSlamParameters params;
  params.initializer.minParallaxDeg = minParallaxDeg;
  TwoViewInitializer init(params.initializer, seq.K);
  RealRun run;
  for (int i = 0; i <= lastFrame && i < static_cast<int>(seq.images.size()); i += stride) {
    const vpImage<unsigned char> I = loadGrey(seq.images[static_cast<size_t>(i)]);
    const auto start = std::chrono::steady_clock::now();
    const TwoViewInitializer::State state = init.addFrame(I, i);
    run.addFrameMs.push_back(
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count());
    const TwoViewAttempt &a = init.lastAttempt();
    std::printf("[%s] frame %d: first %d, matches %d, flow %.1f px, R_H %.2f, inliers %d, parallax %.2f deg, "
                "tdir sigma %.2f deg, outcome %d\n",
                name, i, init.firstFrameId(), a.numMatches, a.medianFlowPx, a.scoreRatioH, a.numInliers, a.parallaxDeg,
                a.translationDirSigmaDeg, static_cast<int>(a.outcome));
    if (state == TwoViewInitializer::initialized) {
      run.initialized = true;
      run.frame = i;
      run.result = init.result();
      run.firstFrame = run.result.firstFrameId;
      const SE3d c2Mc1True = seq.wMc[static_cast<size_t>(i)].inverse() * seq.wMc[static_cast<size_t>(run.firstFrame)];
      run.errors = evaluate(run.result, c2Mc1True, depthsFromTruePose(run.result, c2Mc1True, seq.K));
      std::printf("[%s] initialised at frame %d from frame %d (%s): %zu points, %d inliers, parallax %.2f deg, "
                  "rotation error %.3f deg, translation direction error %.2f deg, median depth error %.1f %%\n",
                  name, i, run.firstFrame, run.result.fromHomography ? "homography" : "essential",
                  run.result.points.size(), run.result.numInliers, run.result.parallaxDeg, run.errors.rotationDeg,
                  run.errors.translationDirDeg, 100. * run.errors.medianDepthRelErr);
      std::printf("[%s] addFrame: median %.1f ms over %zu frames\n", name, median(run.addFrameMs),
                  run.addFrameMs.size());
      run.sampsonEstimatePx = medianSampsonErrorPx(run.result, run.result.c2Mc1, seq.K);
      run.sampsonTruthPx = medianSampsonErrorPx(run.result, c2Mc1True, seq.K);
      std::printf("[%s] median Sampson error of the points: estimate %.3f px, ground truth %.3f px\n", name,
                  run.sampsonEstimatePx, run.sampsonTruthPx);
      break;
    }
  }
  return run;
}
} // namespace

// ---------------------------------------------------------------------------------------------------------------
// Real sequences. Ground truth is camera-to-world (TUM); the reference depth of a point is its match triangulated
// with the true relative pose (no depth maps in these folders).

TEST(TwoViewInitializer, Kitti06InitialisesWithinFewFrames)
{
  HSLAM_REQUIRE_SHARED_DATA(dir, "kitti06_000-050/image_0");
  const RealRun run = runOnSequence(loadKitti(hslam_test::sharedData("kitti06_000-050")), 10, "kitti06");
  ASSERT_TRUE(run.initialized);
  // Measured: frame 2 (2.4 m forward), rotation 0.25 deg, direction 0.50 deg, depth 5.0 %, 176 points.
  EXPECT_EQ(run.firstFrame, 0);
  EXPECT_LE(run.frame, 4);
  EXPECT_LT(run.errors.rotationDeg, 1.0);
  EXPECT_LT(run.errors.translationDirDeg, 5.0);
  EXPECT_LT(run.errors.medianDepthRelErr, 0.10);
  EXPECT_GE(static_cast<int>(run.result.points.size()), 100);
}

TEST(TwoViewInitializer, TsukubaInitialisesWithinFifteenFrames)
{
  HSLAM_REQUIRE_SHARED_DATA(dir, "tsukuba_cg_000-149/rgb.txt");
  const RealRun run =
      runOnSequence(loadTumRgbd(hslam_test::sharedData("tsukuba_cg_000-149"), 615, 320, 240), 30, "tsukuba");
  ASSERT_TRUE(run.initialized);
  // Measured: frame 13, rotation 0.07 deg, direction 0.29 deg, depth 2.6 %, 341 points.
  EXPECT_EQ(run.firstFrame, 0);
  EXPECT_LE(run.frame, 15);
  EXPECT_LT(run.errors.rotationDeg, 0.5);
  EXPECT_LT(run.errors.translationDirDeg, 5.0);
  EXPECT_LT(run.errors.medianDepthRelErr, 0.10);
  EXPECT_GE(static_cast<int>(run.result.points.size()), 200);
}

/*
  7-Scenes starts with a slow hand-held motion: 1.2 cm of baseline after 12 frames, 3.8 cm after 25, for scene
  depths of 1-2 m, so a median parallax of 1 deg is first reached near frame 25. The ground truth (KinectFusion
  poses of the DEPTH camera, nominal RGB intrinsics, no distortion model) is itself inconsistent with the RGB
  images at this baseline: the true relative pose leaves a median epipolar error of ~0.8 px on our points, ours
  ~0.1 px, so the translation direction "error" at 1 deg of parallax (~25 deg) mostly measures the ground truth.
  With the default parameters the test therefore checks the initialisation frame, the rotation and that the
  estimate explains the images better than the ground truth does; with a 3-deg parallax requirement (frame ~50,
  12 cm of baseline) it checks the direction and depths too. A 10-15 frame start is not reachable here: by frame
  15 the camera has moved 1.5 cm, a median parallax of ~0.5 deg.
*/
TEST(TwoViewInitializer, SevenScenesDefaultParameters)
{
  HSLAM_REQUIRE_SHARED_DATA(dir, "7scenes_redkitchen_000-299/rgb.txt");
  const RealRun run =
      runOnSequence(loadTumRgbd(hslam_test::sharedData("7scenes_redkitchen_000-299"), 525, 320, 240), 30, "7scenes");
  ASSERT_TRUE(run.initialized);
  // Measured: frame 28, rotation 0.39 deg, direction 20.6 deg, Sampson 0.095 px (truth 0.95 px), 727 points.
  EXPECT_EQ(run.firstFrame, 0);
  EXPECT_LE(run.frame, 30);
  EXPECT_LT(run.errors.rotationDeg, 1.0);
  EXPECT_LT(run.sampsonEstimatePx, 0.5 * run.sampsonTruthPx);
  EXPECT_LT(run.errors.translationDirDeg, 35.0);
  EXPECT_GE(static_cast<int>(run.result.points.size()), 300);
}

TEST(TwoViewInitializer, SevenScenesLargerParallax)
{
  HSLAM_REQUIRE_SHARED_DATA(dir, "7scenes_redkitchen_000-299/rgb.txt");
  const RealRun run = runOnSequence(loadTumRgbd(hslam_test::sharedData("7scenes_redkitchen_000-299"), 525, 320, 240),
                                    60, "7scenes-3deg", 3.0);
  ASSERT_TRUE(run.initialized);
  // Measured: frame 50 (12 cm), rotation 0.82 deg, direction 8.0 deg, depth 5.0 %, 251 points.
  EXPECT_LE(run.frame, 60);
  EXPECT_LT(run.errors.rotationDeg, 1.0);
  EXPECT_LT(run.errors.translationDirDeg, 10.0);
  EXPECT_LT(run.errors.medianDepthRelErr, 0.10);
}

// ---------------------------------------------------------------------------------------------------------------
// Synthetic scene: exact poses and depths.

namespace
{
PinholeIntrinsics intrinsicsOf(const vpHSlamSyntheticScene &scene)
{
  const vpCameraParameters cam = scene.getCameraParameters();
  return {cam.get_px(), cam.get_py(), cam.get_u0(), cam.get_v0()};
}

bool syntheticSceneAvailable()
{
  return !hslam_test::vispImagesDir().empty();
}

//! Warp I by the homography K R K^-1 of a pure rotation R (the image a rotated camera sees).
vpImage<unsigned char> rotateView(const vpImage<unsigned char> &I, const PinholeIntrinsics &K, const Eigen::Matrix3d &R)
{
  Eigen::Matrix3d Km;
  Km << K.fx, 0., K.cx, 0., K.fy, K.cy, 0., 0., 1.;
  const Eigen::Matrix3d H = Km * R * Km.inverse();
  cv::Mat Hcv(3, 3, CV_64F);
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) {
      Hcv.at<double>(r, c) = H(r, c);
    }
  }
  const cv::Mat src(static_cast<int>(I.getHeight()), static_cast<int>(I.getWidth()), CV_8UC1,
                    const_cast<unsigned char *>(I.bitmap));
  cv::Mat dst;
  cv::warpPerspective(src, dst, Hcv, src.size(), cv::INTER_LINEAR, cv::BORDER_REPLICATE);
  vpImage<unsigned char> out(I.getHeight(), I.getWidth());
  std::copy(dst.data, dst.data + dst.total(), out.bitmap);
  return out;
}
} // namespace

TEST(TwoViewInitializer, SyntheticSceneExact)
{
  if (!syntheticSceneAvailable()) {
    GTEST_SKIP() << "ViSP image data (visp-images-data) not found";
  }
  vpHSlamSyntheticScene scene;
  scene.configure(320, 240, 300, 30.0, 1);
  const PinholeIntrinsics K = intrinsicsOf(scene);
  vpHSlamParameters params;
  TwoViewInitializer init(params.initializer, K);
  int frame = -1;
  vpImage<unsigned char> I;
  for (unsigned int i = 0; i < 60; ++i) {
    scene.render(i, I);
    if (init.addFrame(I, static_cast<int>(i)) == TwoViewInitializer::initialized) {
      frame = static_cast<int>(i);
      break;
    }
  }
  ASSERT_GE(frame, 0) << "no initialisation within 60 frames";
  const TwoViewInitialization &r = init.result();
  const SE3d c2Mc1True = toSE3(scene.getPose(static_cast<unsigned int>(frame))).inverse() * toSE3(scene.getPose(0));
  std::vector<double> trueDepths, idepths;
  for (const InitialPoint &p : r.points) {
    trueDepths.push_back(scene.depthAt(p.u, p.v, 0));
    idepths.push_back(p.idepth);
  }
  const Errors e = evaluate(r, c2Mc1True, trueDepths);
  // Depth scale: depth = s / idepth; the translation must carry the same scale.
  std::vector<double> ratios;
  for (size_t i = 0; i < trueDepths.size(); ++i) {
    ratios.push_back(trueDepths[i] * idepths[i]);
  }
  const double s = median(ratios);
  const double baselineErr =
      std::abs(s * r.c2Mc1.translation().norm() - c2Mc1True.translation().norm()) / c2Mc1True.translation().norm();
  std::printf("[synthetic] translation direction sigma %.2f deg, refined matches %d of %d, Sampson error: estimate "
              "%.3f px, truth %.3f px\n",
              init.lastAttempt().translationDirSigmaDeg, init.lastAttempt().numRefinedMatches,
              init.lastAttempt().numMatches, medianSampsonErrorPx(r, r.c2Mc1, K),
              medianSampsonErrorPx(r, c2Mc1True, K));
  std::printf("[synthetic] initialised at frame %d: %zu points, parallax %.2f deg, rotation error %.4f deg, "
              "translation direction error %.3f deg, median depth error %.2f %%, baseline error %.2f %%\n",
              frame, r.points.size(), r.parallaxDeg, e.rotationDeg, e.translationDirDeg, 100. * e.medianDepthRelErr,
              100. * baselineErr);
  EXPECT_LE(frame, 40);
  EXPECT_LT(e.rotationDeg, 0.1);
  EXPECT_LT(e.translationDirDeg, 1.0);
  EXPECT_LT(e.medianDepthRelErr, 0.02);
  EXPECT_LT(baselineErr, 0.02);
  // Scale convention: the median inverse depth of the returned points is initialIdepth.
  EXPECT_NEAR(median(idepths), params.initializer.initialIdepth, 1e-9);
  EXPECT_GE(static_cast<int>(r.points.size()), params.initializer.minMatches);
  for (const InitialPoint &p : r.points) {
    EXPECT_GE(p.parallaxDeg, 0.36);
    EXPECT_GT(p.idepth, 0.);
  }

  // Densification: inverse-depth priors for arbitrary pixels from the sparse points.
  std::vector<IdepthSample> samples;
  for (const InitialPoint &p : r.points) {
    samples.push_back({p.u, p.v, p.idepth});
  }
  const SparseIdepthInterpolator interp(samples, 320, 240);
  std::vector<double> relErr;
  int withinThreeSigma = 0, queries = 0;
  for (double v = 10.; v < 230.; v += 7.) {
    for (double u = 10.; u < 310.; u += 7.) {
      const IdepthPrior prior = interp.query(u, v);
      const double trueIdepth = s / scene.depthAt(u, v, 0); // in the estimate's scale
      relErr.push_back(std::abs(prior.idepth - trueIdepth) / trueIdepth);
      withinThreeSigma += std::abs(prior.idepth - trueIdepth) <= 3. * std::sqrt(prior.idepthVar) ? 1 : 0;
      ++queries;
    }
  }
  const double coverage = static_cast<double>(withinThreeSigma) / queries;
  std::printf("[synthetic] interpolated idepth: median relative error %.1f %%, 3-sigma coverage %.1f %% (%d pixels)\n",
              100. * median(relErr), 100. * coverage, queries);
  EXPECT_LT(median(relErr), 0.10);
  EXPECT_GT(coverage, 0.8);
}

// The second opinion on a young map (InitializationCheck.h): the true relative pose of two synthetic frames agrees with
// their two-view geometry; a pose 3 degrees off in rotation, or 20 degrees off in translation direction, does not.
TEST(InitializationCheck, TwoViewGeometryConfirmsTheTruePoseOnly)
{
  if (!syntheticSceneAvailable()) {
    GTEST_SKIP() << "ViSP image data (visp-images-data) not found";
  }
  vpHSlamSyntheticScene scene;
  scene.configure(320, 240, 300, 30.0, 1);
  const PinholeIntrinsics K = intrinsicsOf(scene);
  const vpHSlamParameters params;
  Frame a, b;
  a.id = 0;
  scene.render(0, a.raw);
  // The first frame whose geometry with frame 0 is well conditioned (the synthetic initialisation: frame 40 at most).
  SE3d bMa;
  TwoViewPoseCheck truth;
  for (b.id = 10; b.id <= 60 && !truth.measured; b.id += 5) {
    scene.render(static_cast<unsigned int>(b.id), b.raw);
    bMa = toSE3(scene.getPose(static_cast<unsigned int>(b.id))).inverse() * toSE3(scene.getPose(0));
    truth = checkPoseByTwoViews(params, K, a, b, bMa);
  }
  std::printf("[check] true pose, frame %d: measured %d, rotation %.3f deg, direction %.3f deg off\n", b.id - 5,
              truth.measured, truth.rotationErrorDeg, truth.directionErrorDeg);
  ASSERT_TRUE(truth.measured) << "outcome " << truth.outcome;
  EXPECT_TRUE(truth.agrees);
  const Eigen::Matrix3d tilt = Eigen::AngleAxisd(3. / kRadToDeg, Eigen::Vector3d::UnitY()).toRotationMatrix();
  const SE3d rotated(tilt * bMa.rotationMatrix(), bMa.translation());
  const TwoViewPoseCheck rotatedCheck = checkPoseByTwoViews(params, K, a, b, rotated);
  EXPECT_TRUE(rotatedCheck.measured);
  EXPECT_FALSE(rotatedCheck.agrees) << rotatedCheck.rotationErrorDeg;
  const Eigen::Matrix3d swing = Eigen::AngleAxisd(20. / kRadToDeg, Eigen::Vector3d::UnitX()).toRotationMatrix();
  const SE3d swung(bMa.rotationMatrix(), swing * bMa.translation());
  const TwoViewPoseCheck swungCheck = checkPoseByTwoViews(params, K, a, b, swung);
  EXPECT_TRUE(swungCheck.measured);
  EXPECT_FALSE(swungCheck.agrees) << swungCheck.directionErrorDeg;
  // Identical images: no geometry to measure, no opinion.
  EXPECT_FALSE(checkPoseByTwoViews(params, K, a, a, bMa).measured);
}

TEST(TwoViewInitializer, StaticCameraNeverInitialises)
{
  if (!syntheticSceneAvailable()) {
    GTEST_SKIP() << "ViSP image data (visp-images-data) not found";
  }
  vpHSlamSyntheticScene scene;
  scene.configure(320, 240, 300, 30.0, 1);
  vpImage<unsigned char> I;
  scene.render(0, I);
  vpHSlamParameters params;
  params.initializer.maxFramesToInitialize = 10;
  TwoViewInitializer init(params.initializer, intrinsicsOf(scene));
  EXPECT_EQ(init.state(), TwoViewInitializer::noFirstFrame);
  EXPECT_THROW(init.result(), vpHSlamException);
  EXPECT_EQ(init.addFrame(I, 0), TwoViewInitializer::waiting); // becomes the first frame
  EXPECT_EQ(init.firstFrameId(), 0);
  EXPECT_GT(init.firstFrameFeatureCount(), 500);
  for (int i = 1; i <= 25; ++i) {
    ASSERT_EQ(init.addFrame(I, i), TwoViewInitializer::waiting) << "frame " << i;
    EXPECT_EQ(init.lastAttempt().outcome, TwoViewAttempt::tooLittleMotion);
    EXPECT_GT(init.lastAttempt().numMatches, params.initializer.minMatches);
  }
  // maxFramesToInitialize rejected frames restart from a new first frame (frames 10 and 20).
  EXPECT_EQ(init.firstFrameId(), 20);
  EXPECT_THROW(init.result(), vpHSlamException);
  vpImage<unsigned char> other(120, 160, 0);
  EXPECT_THROW(init.addFrame(other, 26), vpHSlamException);
}

TEST(TwoViewInitializer, PureRotationNeverInitialises)
{
  if (!syntheticSceneAvailable()) {
    GTEST_SKIP() << "ViSP image data (visp-images-data) not found";
  }
  vpHSlamSyntheticScene scene;
  scene.configure(640, 480, 300, 30.0, 1);
  vpImage<unsigned char> I0;
  scene.render(0, I0);
  const PinholeIntrinsics K = intrinsicsOf(scene);
  vpHSlamParameters params;
  TwoViewInitializer init(params.initializer, K);
  init.setFirstFrame(I0, 0);
  int attempted = 0;
  for (int i = 1; i <= 16; ++i) {
    // Up to 8 deg about a tilted axis, so that the flow is far above the static-camera threshold.
    const Eigen::Matrix3d R =
        Eigen::AngleAxisd(0.5 * i / kRadToDeg, Eigen::Vector3d(0.3, 1., 0.2).normalized()).toRotationMatrix();
    ASSERT_EQ(init.addFrame(rotateView(I0, K, R), i), TwoViewInitializer::waiting) << "rotation " << 0.5 * i << " deg";
    const TwoViewAttempt &a = init.lastAttempt();
    std::printf("[rotation] %.1f deg: matches %d, flow %.1f px, R_H %.2f, inliers %d, parallax %.2f deg, outcome %d\n",
                0.5 * i, a.numMatches, a.medianFlowPx, a.scoreRatioH, a.numInliers, a.parallaxDeg,
                static_cast<int>(a.outcome));
    // A rotation-only homography decomposes with t ~ 0: its points have no parallax (lowParallax) or cannot be
    // triangulated at all (tooFewInliers); either way the rejection comes from the geometry, not from the matcher.
    EXPECT_TRUE(a.outcome == TwoViewAttempt::lowParallax || a.outcome == TwoViewAttempt::tooFewInliers);
    EXPECT_LT(a.parallaxDeg, params.initializer.minParallaxDeg);
    EXPECT_GT(a.numMatches, params.initializer.minMatches);
    attempted += a.medianFlowPx > 1. ? 1 : 0;
  }
  std::printf("[rotation] %d of 16 rotated views moved the matches and were rejected\n", attempted);
  EXPECT_EQ(attempted, 16);
}

// ---------------------------------------------------------------------------------------------------------------
// Sub-pixel match refinement (Lucas-Kanade).

namespace
{
//! A smooth textured image, the pattern moved by (shiftU, shiftV): pixel (u, v) shows the pattern at
//! (u - shiftU, v - shiftV).
vpImage<unsigned char> shiftedPattern(double shiftU, double shiftV)
{
  vpImage<unsigned char> I(120, 160);
  for (unsigned int v = 0; v < I.getHeight(); ++v) {
    for (unsigned int u = 0; u < I.getWidth(); ++u) {
      const double x = u - shiftU, y = v - shiftV;
      const double f = 128. + 60. * std::sin(0.31 * x + 0.11 * y) + 50. * std::cos(0.17 * y - 0.23 * x);
      I[v][u] = static_cast<unsigned char>(std::lround(std::min(255., std::max(0., f))));
    }
  }
  return I;
}
} // namespace

TEST(MatchRefinement, RecoversASubPixelShiftAndATemplateServesEveryFrame)
{
  const vpImage<unsigned char> I1 = shiftedPattern(0., 0.);
  const std::vector<std::pair<double, double>> shifts = {{1.3, -0.7}, {-2.4, 0.45}, {0.2, 2.9}};
  LucasKanadeTemplate t;
  ASSERT_TRUE(makeLucasKanadeTemplate(I1, 60.5, 50.25, t));
  for (const auto &s : shifts) {
    const vpImage<unsigned char> I2 = shiftedPattern(s.first, s.second);
    // Started from the integer pixel nearest the truth, as a matched keypoint would be.
    double u = std::round(60.5 + s.first), v = std::round(50.25 + s.second);
    double uOnce = u, vOnce = v;
    ASSERT_TRUE(refineMatchLucasKanade(t, I2, u, v, 3.));
    EXPECT_NEAR(u, 60.5 + s.first, 0.05);
    EXPECT_NEAR(v, 50.25 + s.second, 0.05);
    // The kept template gives exactly what a template made for this frame gives.
    ASSERT_TRUE(refineMatchLucasKanade(I1, 60.5, 50.25, I2, uOnce, vOnce, 3.));
    EXPECT_EQ(u, uOnce);
    EXPECT_EQ(v, vOnce);
  }
  // A flat patch has no template; a patch over the border neither.
  const vpImage<unsigned char> flat(120, 160, 90);
  EXPECT_FALSE(makeLucasKanadeTemplate(flat, 60., 50., t));
  EXPECT_FALSE(makeLucasKanadeTemplate(I1, 3., 50., t));
  // Too far a move is refused and leaves the position as it was.
  const vpImage<unsigned char> far = shiftedPattern(2.6, 0.);
  ASSERT_TRUE(makeLucasKanadeTemplate(I1, 60.5, 50.25, t));
  double u = 60.5, v = 50.25;
  EXPECT_FALSE(refineMatchLucasKanade(t, far, u, v, 1.));
  EXPECT_EQ(u, 60.5);
  EXPECT_EQ(v, 50.25);
}

// ---------------------------------------------------------------------------------------------------------------
// Sparse inverse-depth interpolator.

TEST(SparseIdepthInterpolator, MatchesBruteForceMedianOfNearest)
{
  std::vector<IdepthSample> samples;
  unsigned int state = 12345u;
  auto uniform = [&state](double lo, double hi) {
    state = state * 1664525u + 1013904223u; // LCG: deterministic without <random> distributions' variability
    return lo + (hi - lo) * (state >> 8) / static_cast<double>(1u << 24);
  };
  for (int i = 0; i < 500; ++i) {
    samples.push_back({uniform(-5., 645.), uniform(-5., 485.), uniform(0.2, 2.)});
  }
  const int k = 7;
  const SparseIdepthInterpolator interp(samples, 640, 480, k, 0.);
  for (int q = 0; q < 300; ++q) {
    const double u = uniform(0., 640.), v = uniform(0., 480.);
    std::vector<std::pair<double, double>> byDistance;
    for (const IdepthSample &s : samples) {
      byDistance.push_back({std::hypot(s.u - u, s.v - v), s.idepth});
    }
    std::sort(byDistance.begin(), byDistance.end());
    std::vector<double> nearest;
    for (int i = 0; i < k; ++i) {
      nearest.push_back(byDistance[static_cast<size_t>(i)].second);
    }
    const IdepthPrior prior = interp.query(u, v);
    ASSERT_EQ(prior.neighbours, k);
    EXPECT_DOUBLE_EQ(prior.idepth, median(nearest)) << "query (" << u << ", " << v << ")";
    EXPECT_NEAR(prior.farthestPx, byDistance[static_cast<size_t>(k - 1)].first, 1e-9);
  }
}

TEST(SparseIdepthInterpolator, KeepsDiscontinuitiesAndWidensVarianceAcrossThem)
{
  // Left half at idepth 1 (near), right half at 0.25 (far), samples every 10 px.
  std::vector<IdepthSample> samples;
  for (double v = 5.; v < 240.; v += 10.) {
    for (double u = 5.; u < 320.; u += 10.) {
      samples.push_back({u, v, u < 160. ? 1. : 0.25});
    }
  }
  const SparseIdepthInterpolator interp(samples, 320, 240, 8, 0.05);
  const IdepthPrior left = interp.query(60., 120.), right = interp.query(260., 120.), edge = interp.query(160., 120.);
  EXPECT_DOUBLE_EQ(left.idepth, 1.);
  EXPECT_DOUBLE_EQ(right.idepth, 0.25);
  EXPECT_NEAR(left.idepthVar, 0.05 * 0.05, 1e-12); // only the floor on a constant-depth region
  // At the edge the neighbours disagree: a wide prior, and an idepth taken from one side, not a blend.
  EXPECT_GT(std::sqrt(edge.idepthVar), 0.3);
  EXPECT_TRUE(edge.idepth == 1. || edge.idepth == 0.25 || edge.idepth == 0.625);
  EXPECT_THROW(SparseIdepthInterpolator({}, 320, 240), vpHSlamException);
  EXPECT_THROW(SparseIdepthInterpolator(samples, 320, 240, SparseIdepthInterpolator::kMaxNeighbours + 1),
               vpHSlamException);
}
