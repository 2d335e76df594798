/*
 * H-SLAM for ViSP.
 */
#include "mapping/TwoViewInitializer.h"

#include "mapping/EpipolarMatching.h"
#include "mapping/TwoViewGeometry.h"

#include <visp3/hslam/vpHSlamException.h>

#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>

namespace hslam
{
namespace
{
//! ORB-SLAM2 (Mur-Artal et al. 2015, sec. IV): homography when R_H = S_H / (S_H + S_F) exceeds this.
constexpr double kHomographyScoreRatio = 0.45;
//! Hamming distance above which two ORB descriptors do not match (ORB-SLAM2 ORBmatcher TH_LOW).
constexpr int kMaxHammingDistance = 50;
//! An ORB descriptor is 256 bits: four 64-bit words.
constexpr int kOrbDescriptorWords = 4;
//! Lowe's ratio test: best distance must be below this fraction of the second best.
constexpr double kMatchRatio = 0.8;
/*!
  Median displacement of the matches (pixels) below which the frame is not even tried: a camera that has not moved
  cannot produce parallax, and RANSAC on near-identical points returns arbitrary essential matrices.
*/
constexpr double kMinMedianFlowPx = 1.0;
//! ORB-SLAM2 CheckRT: reprojection error bound, 4 sigma^2 (pixels^2, sigma = the RANSAC threshold).
constexpr double kReprojErrFactorSq = 4.;
/*!
  ORB-SLAM2 ReconstructF/H: the motion is ambiguous when another decomposition explains more than this fraction of
  the best one's points.
*/
constexpr double kMaxSecondBestRatio = 0.75;
/*!
  ORB-SLAM2 ReconstructF: the best decomposition must explain this fraction of the model's inliers; fewer means
  the model is wrong (RANSAC locked onto outliers or a degenerate set).
*/
constexpr double kMinGoodFractionOfInliers = 0.9;
//! A triangulated point is returned only with at least this parallax (ORB-SLAM2: cos < 0.99998, ~0.36 deg).
constexpr double kMinPointParallaxDeg = 0.36;
//! Huber width of the Sampson refinement, in units of the RANSAC threshold.
constexpr double kRefineHuberFactor = 2.;
/*!
  Lucas-Kanade may move a match at most this far (pixels): the quantisation of ORB's coarsest octaves (1.2^7 = 3.6
  for 8 levels) is the error it corrects; a longer move means it locked onto another structure.
*/
constexpr double kMaxRefinementShiftPx = 3.;
//! minMatches must at least allow the 8-point homography / fundamental estimates to be over-determined.
constexpr int kMinMatchesLowerBound = 8;
/*!
  Matches of a failed attempt that must agree on an essential matrix (and be at least half of them) before the
  unmatched keypoints are searched along its epipolar lines: fewer, and a wrong matrix would recruit matches that
  agree with it.
*/
constexpr int kMinSeedInliers = 20;
//! OpenCV findHomography RANSAC iteration cap (its default).
constexpr int kHomographyMaxIters = 2000;

std::string where(int line)
{
  return std::string(__FILE__) + ":" + std::to_string(line) + ": ";
}

Eigen::Matrix3d intrinsicsMatrix(const PinholeIntrinsics &K)
{
  Eigen::Matrix3d M;
  M << K.fx, 0., K.cx, 0., K.fy, K.cy, 0., 0., 1.;
  return M;
}

struct Hypothesis {
  Eigen::Matrix3d R;
  Eigen::Vector3d t;
};

/*!
  Every (current, first) descriptor pair: best and second-best first-frame distance per current descriptor, best
  current descriptor per first-frame one. Compiled twice (function multi-versioning): with the POPCNT instruction
  and for the baseline x86-64 the build targets, where __builtin_popcountll is a libgcc call several times slower;
  the loader picks the version the CPU supports. Not under ThreadSanitizer: the loader runs the (instrumented)
  version resolver while it relocates the library, before the TSan runtime is initialised, and the program crashes
  before main().
*/
#if defined(__GNUC__) && defined(__x86_64__) && defined(__linux__) && !defined(__SANITIZE_THREAD__)
__attribute__((target_clones("popcnt", "default")))
#endif
void bruteForceHamming(const uint64_t *cur, int nCur, const uint64_t *first, int nFirst, int *bestFirstOfCur,
                       int *bestDistOfCur, int *secondDistOfCur, int *bestCurOfFirst, int *bestDistOfFirst)
{
  for (int i = 0; i < nCur; ++i) {
    const uint64_t *di = cur + static_cast<size_t>(i) * kOrbDescriptorWords;
    int best = std::numeric_limits<int>::max(), second = best, bestJ = -1;
    for (int j = 0; j < nFirst; ++j) {
      const uint64_t *dj = first + static_cast<size_t>(j) * kOrbDescriptorWords;
      int dist = 0;
      for (int w = 0; w < kOrbDescriptorWords; ++w) {
        dist += __builtin_popcountll(di[w] ^ dj[w]);
      }
      if (dist < best) {
        second = best;
        best = dist;
        bestJ = j;
      } else if (dist < second) {
        second = dist;
      }
      if (dist < bestDistOfFirst[j]) {
        bestDistOfFirst[j] = dist;
        bestCurOfFirst[j] = i;
      }
    }
    bestFirstOfCur[i] = bestJ;
    bestDistOfCur[i] = best;
    secondDistOfCur[i] = second;
  }
}
} // namespace

TwoViewInitializer::TwoViewInitializer(const vpHSlamParameters::Initializer &params, const PinholeIntrinsics &K,
                                       const OrbExtractorOptions &orbOptions)
    : m_params(params), m_K(K), m_orb(orbOptions)
{
  if (params.minMatches < kMinMatchesLowerBound || params.minParallaxDeg <= 0. || params.ransacThresholdPx <= 0. ||
      params.ransacConfidence <= 0. || params.ransacConfidence >= 1. || params.maxFramesToInitialize < 1 ||
      params.initialIdepth <= 0.) {
    throw vpHSlamException(vpHSlamException::invalidArgument, where(__LINE__) + "invalid initializer parameters");
  }
  if (K.fx <= 0. || K.fy <= 0.) {
    throw vpHSlamException(vpHSlamException::invalidArgument, where(__LINE__) + "non-positive focal length");
  }
}

void TwoViewInitializer::reset()
{
  m_state = noFirstFrame;
  m_firstId = -1;
  m_framesSinceFirst = 0;
  m_firstKeypoints.clear();
  m_firstDescriptors.release();
  m_firstImage = vpImage<unsigned char>();
  forgetTemplates();
  m_result = TwoViewInitialization();
  m_lastAttempt = TwoViewAttempt();
}

void TwoViewInitializer::setFirstFrame(const vpImage<unsigned char> &I, int frameId)
{
  reset();
  m_orb.extract(I, m_firstKeypoints, m_firstDescriptors);
  m_firstImage = I;
  m_width = I.getWidth();
  m_height = I.getHeight();
  m_firstId = frameId;
  m_state = waiting;
}

const TwoViewInitialization &TwoViewInitializer::result() const
{
  if (m_state != initialized) {
    throw vpHSlamException(vpHSlamException::invalidArgument, where(__LINE__) + "result() before initialisation");
  }
  return m_result;
}

OrbExtractorOptions twoViewOrbOptions(const vpHSlamParameters::Initializer &params)
{
  OrbExtractorOptions options;
  options.maxFeatures = params.orbFeatures;
  return options;
}

TwoViewAttempt TwoViewInitializer::attemptOn(const std::vector<Match> &matches)
{
  TwoViewAttempt attempt;
  attempt.numMatches = static_cast<int>(matches.size());
  attempt.numRefinedMatches =
      static_cast<int>(std::count_if(matches.begin(), matches.end(), [](const Match &m) { return m.refined; }));
  attempt.outcome = solve(matches, attempt);
  return attempt;
}

TwoViewInitializer::State TwoViewInitializer::addFrame(const vpImage<unsigned char> &I, int frameId)
{
  if (m_state == initialized) {
    return m_state;
  }
  if (m_state == noFirstFrame) {
    setFirstFrame(I, frameId);
    return m_state;
  }
  if (I.getWidth() != m_width || I.getHeight() != m_height) {
    throw vpHSlamException(vpHSlamException::invalidImage,
                           where(__LINE__) + "frame " + std::to_string(frameId) + " is " +
                               std::to_string(I.getWidth()) + "x" + std::to_string(I.getHeight()) +
                               ", the first frame " + std::to_string(m_width) + "x" + std::to_string(m_height));
  }
  std::vector<cv::KeyPoint> keypoints;
  cv::Mat descriptors;
  m_orb.extract(I, keypoints, descriptors);
  std::vector<Match> matches;
  matchToFirst(keypoints, descriptors, matches);
  refineMatches(I, matches);
  ++m_framesSinceFirst;

  TwoViewAttempt attempt = attemptOn(matches);
  // More matches help where waiting does not: matches only get fewer as the view moves on, while parallax grows (a
  // low-parallax attempt waits for the next frame, as before; densifying it would start maps on shorter baselines).
  const bool worthDensifying =
      attempt.outcome == TwoViewAttempt::tooFewMatches || attempt.outcome == TwoViewAttempt::tooFewInliers;
  if (worthDensifying && addEpipolarMatches(keypoints, descriptors, I, matches) > 0) {
    attempt = attemptOn(matches);
  }
  if (attempt.outcome == TwoViewAttempt::initialized) {
    m_result.firstFrameId = m_firstId;
    m_result.currentFrameId = frameId;
    m_state = initialized;
  } else if (attempt.outcome == TwoViewAttempt::tooFewMatches || m_framesSinceFirst >= m_params.maxFramesToInitialize) {
    // Matches only get fewer as the view moves on: start again from this frame (ORB-SLAM2 does the same).
    m_firstKeypoints.swap(keypoints);
    m_firstDescriptors = descriptors;
    m_firstImage = I;
    forgetTemplates();
    m_firstId = frameId;
    m_framesSinceFirst = 0;
  }
  m_lastAttempt = attempt;
  return m_state;
}

TwoViewInitializer::Match TwoViewInitializer::matchOf(int firstIndex, int currentIndex,
                                                      const std::vector<cv::KeyPoint> &keypoints) const
{
  const cv::Point2f &a = m_firstKeypoints[static_cast<size_t>(firstIndex)].pt;
  const cv::Point2f &b = keypoints[static_cast<size_t>(currentIndex)].pt;
  Match m;
  m.p1 = cv::Point2d(a.x, a.y);
  m.p2 = cv::Point2d(b.x, b.y);
  m.firstIndex = firstIndex;
  m.currentIndex = currentIndex;
  return m;
}

void TwoViewInitializer::matchToFirst(const std::vector<cv::KeyPoint> &keypoints, const cv::Mat &descriptors,
                                      std::vector<Match> &matches) const
{
  matches.clear();
  if (keypoints.empty() || m_firstKeypoints.empty()) {
    return;
  }
  // One brute-force pass over all pairs gives each current descriptor its best and second-best first-frame
  // distances (ratio test) and each first-frame descriptor its best current one (mutual check). Twice as fast as
  // cv::BFMatcher's knnMatch + match, which computes every distance twice.
  if (descriptors.cols != kOrbDescriptorWords * static_cast<int>(sizeof(uint64_t)) || descriptors.type() != CV_8U ||
      !descriptors.isContinuous() || !m_firstDescriptors.isContinuous() ||
      m_firstDescriptors.cols != descriptors.cols) {
    throw vpHSlamException(vpHSlamException::unsupported, where(__LINE__) + "ORB descriptors must be 32 bytes");
  }
  const int nCur = descriptors.rows, nFirst = m_firstDescriptors.rows;
  std::vector<int> bestCurOfFirst(static_cast<size_t>(nFirst), -1);
  std::vector<int> bestDistOfFirst(static_cast<size_t>(nFirst), std::numeric_limits<int>::max());
  std::vector<int> bestFirstOfCur(static_cast<size_t>(nCur), -1);
  std::vector<int> bestDistOfCur(static_cast<size_t>(nCur)), secondDistOfCur(static_cast<size_t>(nCur));
  bruteForceHamming(descriptors.ptr<uint64_t>(0), nCur, m_firstDescriptors.ptr<uint64_t>(0), nFirst,
                    bestFirstOfCur.data(), bestDistOfCur.data(), secondDistOfCur.data(), bestCurOfFirst.data(),
                    bestDistOfFirst.data());
  for (int i = 0; i < nCur; ++i) {
    const int j = bestFirstOfCur[static_cast<size_t>(i)];
    const int best = bestDistOfCur[static_cast<size_t>(i)];
    if (j < 0 || best > kMaxHammingDistance) {
      continue;
    }
    if (best >= kMatchRatio * secondDistOfCur[static_cast<size_t>(i)]) {
      continue;
    }
    if (bestCurOfFirst[static_cast<size_t>(j)] != i) {
      continue;
    }
    matches.push_back(matchOf(j, i, keypoints));
  }
}

int TwoViewInitializer::addEpipolarMatches(const std::vector<cv::KeyPoint> &keypoints, const cv::Mat &descriptors,
                                           const vpImage<unsigned char> &I, std::vector<Match> &matches)
{
  if (static_cast<int>(matches.size()) < kMinSeedInliers) {
    return 0;
  }
  std::vector<cv::Point2d> cv1, cv2;
  for (const Match &m : matches) {
    cv1.push_back(m.p1);
    cv2.push_back(m.p2);
  }
  const Eigen::Matrix3d Keig = intrinsicsMatrix(m_K);
  cv::Mat Kcv, inliers;
  cv::eigen2cv(Keig, Kcv);
  const cv::Mat Es =
      cv::findEssentialMat(cv1, cv2, Kcv, cv::RANSAC, m_params.ransacConfidence, m_params.ransacThresholdPx, inliers);
  const int agreeing = inliers.empty() ? 0 : cv::countNonZero(inliers);
  if (Es.rows < 3 || agreeing < kMinSeedInliers || 2 * agreeing < static_cast<int>(matches.size())) {
    return 0;
  }
  Eigen::Matrix3d E;
  cv::cv2eigen(Es.rowRange(0, 3), E); // the first of the 5-point solver's solutions: RANSAC's best
  const Eigen::Matrix3d Kinv = Keig.inverse();
  const Eigen::Matrix3d F = Kinv.transpose() * E * Kinv;
  std::vector<bool> firstUsed(m_firstKeypoints.size(), false), currentUsed(keypoints.size(), false);
  for (const Match &m : matches) {
    firstUsed[static_cast<size_t>(m.firstIndex)] = true;
    currentUsed[static_cast<size_t>(m.currentIndex)] = true;
  }
  std::vector<Match> added;
  for (const auto &pair : matchAlongEpipolarLines(F, m_firstKeypoints, m_firstDescriptors, keypoints, descriptors,
                                                  firstUsed, currentUsed)) {
    added.push_back(matchOf(pair.first, pair.second, keypoints));
  }
  refineMatches(I, added);
  matches.insert(matches.end(), added.begin(), added.end());
  return static_cast<int>(added.size());
}

void TwoViewInitializer::forgetTemplates()
{
  // Released, not only emptied: about 3 KB per keypoint, 3 MB for 1000, of no use once the map has started.
  std::vector<LucasKanadeTemplate>().swap(m_templates);
  std::vector<signed char>().swap(m_templateState);
}

void TwoViewInitializer::refineMatches(const vpImage<unsigned char> &I, std::vector<Match> &matches)
{
  if (m_templateState.size() != m_firstKeypoints.size()) {
    m_templates.assign(m_firstKeypoints.size(), LucasKanadeTemplate());
    m_templateState.assign(m_firstKeypoints.size(), 0);
  }
  for (Match &m : matches) {
    const size_t j = static_cast<size_t>(m.firstIndex);
    if (m_templateState[j] == 0) {
      m_templateState[j] = makeLucasKanadeTemplate(m_firstImage, m.p1.x, m.p1.y, m_templates[j]) ? 1 : -1;
    }
    m.refined =
        m_templateState[j] > 0 && refineMatchLucasKanade(m_templates[j], I, m.p2.x, m.p2.y, kMaxRefinementShiftPx);
  }
}

namespace
{
//! The two models of the first and current views, each scored over the matches (ORB-SLAM2 model selection).
struct TwoViewModels {
  double scoreF = 0.; //!< fundamentalScore() of the best essential matrix
  Eigen::Matrix3d E = Eigen::Matrix3d::Zero();
  std::vector<unsigned char> inliersF;
  double scoreH = 0.; //!< homographyScore()
  Eigen::Matrix3d H = Eigen::Matrix3d::Zero();
  cv::Mat Hcv; //!< empty when no homography was found
  std::vector<unsigned char> inliersH;
};

//! RANSAC essential matrix (the best scored of the 5-point solver's stacked solutions) and homography, scored.
TwoViewModels fitModels(const std::vector<cv::Point2d> &cv1, const std::vector<cv::Point2d> &cv2, const PixelVector &p1,
                        const PixelVector &p2, const cv::Mat &Kcv, const Eigen::Matrix3d &Kinv, double sigma,
                        double confidence)
{
  TwoViewModels models;
  cv::Mat Es = cv::findEssentialMat(cv1, cv2, Kcv, cv::RANSAC, confidence, sigma);
  std::vector<unsigned char> tmpInliers;
  for (int k = 0; k + 3 <= Es.rows; k += 3) {
    Eigen::Matrix3d E;
    cv::cv2eigen(Es.rowRange(k, k + 3), E);
    const double s = fundamentalScore(Kinv.transpose() * E * Kinv, p1, p2, sigma, tmpInliers);
    if (s > models.scoreF) {
      models.scoreF = s;
      models.E = E;
      models.inliersF = tmpInliers;
    }
  }
  models.Hcv = cv::findHomography(cv1, cv2, cv::RANSAC, sigma, cv::noArray(), kHomographyMaxIters, confidence);
  if (!models.Hcv.empty()) {
    cv::cv2eigen(models.Hcv, models.H);
    models.scoreH = homographyScore(models.H, p1, p2, sigma, models.inliersH);
  }
  return models;
}

//! Candidate motions of the chosen model: the homography's decompositions or the essential matrix's four.
std::vector<Hypothesis> motionHypotheses(const TwoViewModels &models, bool useHomography, const cv::Mat &Kcv)
{
  std::vector<Hypothesis> hypotheses;
  if (useHomography) {
    std::vector<cv::Mat> Rs, ts, normals;
    cv::decomposeHomographyMat(models.Hcv, Kcv, Rs, ts, normals);
    for (size_t k = 0; k < Rs.size(); ++k) {
      Hypothesis h;
      cv::cv2eigen(Rs[k], h.R);
      cv::cv2eigen(ts[k], h.t);
      // t is known up to the plane distance; a null t (pure rotation) is kept: it fails the parallax test.
      if (h.t.norm() > 0.) {
        h.t.normalize();
      }
      hypotheses.push_back(h);
    }
  } else if (models.scoreF > 0.) {
    cv::Mat Ecv, R1, R2, t;
    cv::eigen2cv(models.E, Ecv);
    cv::decomposeEssentialMat(Ecv, R1, R2, t);
    for (const cv::Mat &Rcv : {R1, R2}) {
      for (const double sign : {1., -1.}) {
        Hypothesis h;
        cv::cv2eigen(Rcv, h.R);
        cv::cv2eigen(t, h.t);
        h.t *= sign;
        hypotheses.push_back(h);
      }
    }
  }
  return hypotheses;
}

/*!
  The hypothesis with the most points in front of both cameras (checkMotion), if it is clearly better than the
  others and has enough points and parallax; then polished on all its points (the minimal RANSAC sample used 5)
  and triangulated again into \e check.
*/
TwoViewAttempt::Outcome selectMotion(const std::vector<Hypothesis> &hypotheses, const PinholeIntrinsics &K,
                                     const PixelVector &p1, const PixelVector &p2,
                                     const std::vector<unsigned char> &inliers, int numModelInliers, double sigma,
                                     const vpHSlamParameters::Initializer &params, TwoViewAttempt &attempt,
                                     Hypothesis &motion, MotionCheck &check)
{
  const double maxReprojErrSq = kReprojErrFactorSq * sigma * sigma;
  std::vector<MotionCheck> checks;
  int best = -1, bestGood = 0, secondGood = 0;
  for (size_t k = 0; k < hypotheses.size(); ++k) {
    checks.push_back(checkMotion(hypotheses[k].R, hypotheses[k].t, K, p1, p2, inliers, maxReprojErrSq));
    const int good = checks.back().numGood;
    if (good > bestGood) {
      secondGood = bestGood;
      bestGood = good;
      best = static_cast<int>(k);
    } else if (good > secondGood) {
      secondGood = good;
    }
  }
  attempt.numInliers = bestGood;
  if (best < 0) {
    return TwoViewAttempt::modelFailed;
  }
  attempt.parallaxDeg = checks[static_cast<size_t>(best)].medianParallaxDeg;
  if (bestGood < params.minMatches || bestGood < kMinGoodFractionOfInliers * numModelInliers) {
    return TwoViewAttempt::tooFewInliers;
  }
  if (attempt.parallaxDeg < params.minParallaxDeg) {
    return TwoViewAttempt::lowParallax;
  }
  if (secondGood > kMaxSecondBestRatio * bestGood) {
    return TwoViewAttempt::ambiguousMotion;
  }

  motion = hypotheses[static_cast<size_t>(best)];
  if (refineRelativePose(motion.R, motion.t, K, p1, p2, checks[static_cast<size_t>(best)].good,
                         kRefineHuberFactor * sigma, &attempt.translationDirSigmaDeg)) {
    checks[static_cast<size_t>(best)] = checkMotion(motion.R, motion.t, K, p1, p2, inliers, maxReprojErrSq);
  }
  check = checks[static_cast<size_t>(best)];
  attempt.numInliers = check.numGood;
  attempt.parallaxDeg = check.medianParallaxDeg;
  // The refined motion may trade translation for rotation (small-baseline ambiguity): check again.
  if (check.numGood < params.minMatches) {
    return TwoViewAttempt::tooFewInliers;
  }
  if (check.medianParallaxDeg < params.minParallaxDeg) {
    return TwoViewAttempt::lowParallax;
  }
  return TwoViewAttempt::initialized;
}

/*!
  The triangulated points with enough parallax, and the motion, scaled so that the median inverse depth is
  \e initialIdepth (with |t| = 1 the depths are in baselines). False when fewer than \e minMatches points remain.
*/
bool scaledInitialization(const MotionCheck &check, const Hypothesis &motion, const PixelVector &p1,
                          const PixelVector &p2, const vpHSlamParameters::Initializer &params,
                          TwoViewInitialization &result)
{
  std::vector<double> idepths;
  for (size_t i = 0; i < p1.size(); ++i) {
    if (!check.good[i] || check.parallaxDeg[i] < kMinPointParallaxDeg || check.X1[i].z() <= 0.) {
      continue;
    }
    InitialPoint pt;
    pt.u = p1[i].x();
    pt.v = p1[i].y();
    pt.uCur = p2[i].x();
    pt.vCur = p2[i].y();
    pt.idepth = 1. / check.X1[i].z();
    pt.parallaxDeg = check.parallaxDeg[i];
    result.points.push_back(pt);
    idepths.push_back(pt.idepth);
  }
  if (static_cast<int>(idepths.size()) < params.minMatches) {
    return false;
  }
  std::nth_element(idepths.begin(), idepths.begin() + static_cast<std::ptrdiff_t>(idepths.size() / 2), idepths.end());
  const double scale = idepths[idepths.size() / 2] / params.initialIdepth;
  for (InitialPoint &pt : result.points) {
    pt.idepth /= scale;
  }
  result.c2Mc1 = SE3d(Eigen::Matrix3d(motion.R), Eigen::Vector3d(motion.t * scale));
  return true;
}
} // namespace

TwoViewAttempt::Outcome TwoViewInitializer::solve(const std::vector<Match> &matches, TwoViewAttempt &attempt)
{
  const int n = static_cast<int>(matches.size());
  if (n < m_params.minMatches) {
    return TwoViewAttempt::tooFewMatches;
  }
  std::vector<cv::Point2d> cv1, cv2;
  PixelVector p1, p2;
  std::vector<double> flow;
  for (const Match &m : matches) {
    cv1.push_back(m.p1);
    cv2.push_back(m.p2);
    p1.emplace_back(m.p1.x, m.p1.y);
    p2.emplace_back(m.p2.x, m.p2.y);
    flow.push_back(std::hypot(m.p2.x - m.p1.x, m.p2.y - m.p1.y));
  }
  std::nth_element(flow.begin(), flow.begin() + n / 2, flow.end());
  attempt.medianFlowPx = flow[static_cast<size_t>(n / 2)];
  if (attempt.medianFlowPx < kMinMedianFlowPx) {
    return TwoViewAttempt::tooLittleMotion;
  }

  const Eigen::Matrix3d Keig = intrinsicsMatrix(m_K);
  const Eigen::Matrix3d Kinv = Keig.inverse();
  cv::Mat Kcv;
  cv::eigen2cv(Keig, Kcv);
  const double sigma = m_params.ransacThresholdPx;
  const TwoViewModels models = fitModels(cv1, cv2, p1, p2, Kcv, Kinv, sigma, m_params.ransacConfidence);
  if (models.scoreF + models.scoreH <= 0.) {
    return TwoViewAttempt::modelFailed;
  }
  attempt.scoreRatioH = models.scoreH / (models.scoreH + models.scoreF);
  const bool useHomography = attempt.scoreRatioH > kHomographyScoreRatio;

  const std::vector<Hypothesis> hypotheses = motionHypotheses(models, useHomography, Kcv);
  const std::vector<unsigned char> &inliers = useHomography ? models.inliersH : models.inliersF;
  const int numModelInliers = static_cast<int>(std::count(inliers.begin(), inliers.end(), 1));
  if (hypotheses.empty() || numModelInliers < m_params.minMatches) {
    attempt.numInliers = numModelInliers;
    return hypotheses.empty() ? TwoViewAttempt::modelFailed : TwoViewAttempt::tooFewInliers;
  }
  Hypothesis motion;
  MotionCheck check;
  const TwoViewAttempt::Outcome outcome =
      selectMotion(hypotheses, m_K, p1, p2, inliers, numModelInliers, sigma, m_params, attempt, motion, check);
  if (outcome != TwoViewAttempt::initialized) {
    return outcome;
  }

  TwoViewInitialization result;
  if (!scaledInitialization(check, motion, p1, p2, m_params, result)) {
    return TwoViewAttempt::tooFewInliers;
  }
  result.numInliers = check.numGood;
  result.parallaxDeg = check.medianParallaxDeg;
  result.fromHomography = useHomography;
  result.translationDirSigmaDeg = attempt.translationDirSigmaDeg;
  m_result = result;
  return TwoViewAttempt::initialized;
}
} // namespace hslam
