/*
 * H-SLAM for ViSP.
 */
/*!
  \file GlobalBundleAdjustment.h
  \brief Global bundle adjustment in the map's own inverse-depth form (loop correction, paper sec. 3.4).

  What it is for: after the pose graph has bent the old side of a loop into place, keyframe poses and the global
  points' inverse depths are refined together against where the points were seen. The unknowns are the keyframes'
  camera-from-world poses (SE(3): quaternion + translation, updated on the manifold) and one inverse depth per point;
  a point's host pixel is its parametrisation and stays as it is (the window's convention, MapPoint.h). A point
  hosted in keyframe h at pixel p with inverse depth rho, seen in keyframe o at pixel z, gives the residual

    r = pi(R_o R_h^T (K^-1 p - rho t_h) + rho t_o) - z

  (the point rho-scaled, which leaves its projection unchanged and keeps rho -> 0, a point at infinity, regular),
  under a Huber loss of huberPx pixels. Solved by Levenberg-Marquardt in Ceres with the sparse Schur complement:
  the inverse depths are eliminated first (paper: "Ceres, sparse Schur, robust loss").

  Gauge: monocular bundle adjustment is free in pose and scale (7 degrees of freedom). Fixed keyframes hold it; the
  caller fixes the active window (its priors must stay valid), which also holds the scale through the points they
  observe. With fewer than two fixed keyframes the two lowest ids are held.

  Threading: an object is used from one thread; it copies everything it needs, so it can run beside the mapper.
*/
#ifndef HSLAM_LOOP_GLOBAL_BUNDLE_ADJUSTMENT_H
#define HSLAM_LOOP_GLOBAL_BUNDLE_ADJUSTMENT_H

#include "features/ImagePyramid.h"
#include "math/SE3.h"

#include <visp3/core/vpConfig.h>

#include <array>
#include <atomic>
#include <map>
#include <vector>

namespace ceres
{
class LossFunction;
class Manifold;
class Problem;
} // namespace ceres

namespace hslam
{
//! A point as the adjustment sees it.
struct BundlePoint {
  int hostId = -1;
  double u = 0., v = 0.; //!< host pixel (fixed: the parametrisation)
  double idepth = 0.;    //!< initial inverse depth (> 0)
  struct Observation {
    int keyframeId = -1;
    double u = 0., v = 0.; //!< measured pixel
  };
  std::vector<Observation> observations;
};

//! Settings (vpHSlamParameters::Loop::globalBa*).
struct GlobalBundleOptions {
  int maxIterations = 10; //!< Levenberg-Marquardt iterations
  double huberPx = 2.;    //!< Huber threshold on the reprojection error, pixels
  int threads = 1;        //!< Ceres threads
  //! When set and true, the solver stops at its next iteration (the result is then not usable: nothing changes).
  const std::atomic<bool> *cancel = nullptr;
};

//! What optimize() did.
struct GlobalBundleSummary {
  bool usable = false; //!< Ceres returned a usable solution (estimates written)
  int keyframes = 0;   //!< keyframes in the problem (fixed included)
  int points = 0;      //!< points with at least one usable observation
  int observations = 0;
  int iterations = 0;
  double rmsBeforePx = 0.; //!< root mean square reprojection error before and after (all observations)
  double rmsAfterPx = 0.;
  double seconds = 0.; //!< wall time
};

class VISP_EXPORT GlobalBundleAdjustment
{
public:
  explicit GlobalBundleAdjustment(const PinholeIntrinsics &K) : m_K(K) {}

  //! Add (or replace) keyframe \e id at \e cMw; \e fixed holds it (gauge).
  void addKeyframe(int id, const SE3d &cMw, bool fixed);
  /*!
    Add a point; observations in keyframes not added, in the host itself, with non-finite pixels or in front of
    which the point does not lie are left out. Returns the index of the point, or -1 when its host is unknown,
    its inverse depth is not positive or no observation is left.
  */
  int addPoint(const BundlePoint &point);

  GlobalBundleSummary optimize(const GlobalBundleOptions &options);

  //! Current estimate of keyframe \e id. \exception vpHSlamException::invalidArgument for an unknown id.
  SE3d keyframe(int id) const;
  //! Current inverse depth of the point with index \e i (returned by addPoint()).
  double idepth(int i) const { return m_points.at(static_cast<size_t>(i)).idepth; }
  size_t keyframeCount() const { return m_keyframes.size(); }
  size_t pointCount() const { return m_points.size(); }

private:
  //! [qx, qy, qz, qw, tx, ty, tz] of cMw.
  struct Pose {
    std::array<double, 7> x;
    bool fixed = false;
  };
  struct Point {
    int host = -1;
    double u = 0., v = 0.;
    double idepth = 0.;
    std::vector<BundlePoint::Observation> observations;
  };
  double rmsReprojection(int &count) const;
  //! Holds keyframes, first ids first, until at least two are held (the gauge of a monocular map).
  void holdGauge();
  //! The poses copied into \e poses (keyframe-id order), and each keyframe's block in it.
  std::map<int, double *> poseBlocks(std::vector<std::array<double, 7>> &poses) const;
  //! One reprojection residual per observation (robust \e loss); inverse depths bounded below.
  void addPointResiduals(ceres::Problem &problem, ceres::LossFunction *loss, const std::map<int, double *> &block);
  //! Manifold of the pose blocks that have a residual, held ones constant; those blocks, in keyframe-id order.
  std::vector<double *> setPoseBlocks(ceres::Problem &problem, ceres::Manifold *manifold,
                                      const std::map<int, double *> &block) const;
  //! A usable, finite solution is kept (poses copied back) and true; otherwise the inverse depths are restored.
  bool keepOrRestore(bool solverUsable, const std::vector<std::array<double, 7>> &poses,
                     const std::map<int, double *> &block, const std::vector<double> &idepthBackup);

  PinholeIntrinsics m_K;
  std::map<int, Pose> m_keyframes;
  std::vector<Point> m_points;
};
} // namespace hslam

#endif
