/*
 * H-SLAM for ViSP.
 */
/*!
  \file WindowRelocalization.h
  \brief Relocalisation against the photometric window's keyframes with ORB points triangulated between them.

  Why: after a lost stretch (a covered lens, a blur), the camera is usually still near the place the window maps,
  but the window's described points with a depth are few (its active corners: 54-138 for a keyframe and its four
  neighbours on 7-Scenes), and a view 10 degrees and 0.26 m away matches too few of them for PnP. The window's
  keyframes still hold their rectified 8-bit images, and their poses are fixed while the camera is lost, so here
  each of them gets scale-invariant ORB features (OrbExtractor, as the two-view initializer), matched to the other
  window keyframes' along the epipolar line their poses give and triangulated (ORB-SLAM2's
  SearchForTriangulation + CreateNewMapPoints, done once per loss instead of at every keyframe). The lost frame is
  described the same way and matched to all of them; Relocalizer's PnP RANSAC and pose-only refinement follow.
  Nothing is added to the map: the points live as long as the loss.

  Threading: not thread-safe; owned by the tracking side and used while the mapper is idle (a lost camera feeds
  no mapping job).
*/
#ifndef HSLAM_TRACKING_WINDOW_RELOCALIZATION_H
#define HSLAM_TRACKING_WINDOW_RELOCALIZATION_H

#include "features/ImagePyramid.h"
#include "features/OrbExtractor.h"
#include "map/Frame.h"
#include "tracking/Relocalizer.h"

#include <visp3/core/vpConfig.h>

#include <map>
#include <vector>

namespace hslam
{
//! A window keyframe as seen by WindowRelocalization: its id, pose and frame (the raw image is read).
struct WindowView {
  int id = -1;
  SE3d cMw;
  std::shared_ptr<const Frame> frame;
};

//! ORB features of one view with the pose they were taken at.
struct DescribedView {
  int id = -1;
  SE3d cMw;
  std::vector<Eigen::Vector2d> uv;        //!< level-0 pixels
  std::vector<float> scale;               //!< scale factor of the pyramid level each was detected at (1, 1.2, ...)
  std::vector<OrbDescriptor> descriptors; //!< one per keypoint
};

//! Settings of the triangulation between window keyframes (defaults: ORB-SLAM2's where it has one).
struct ViewTriangulationOptions {
  int maxDistance = 50;            //!< Hamming distance accepted at most (ORB-SLAM2 TH_LOW)
  float ratio = 0.8f;              //!< best below ratio x second best among the keypoints near the epipolar line
  double epipolarSigmaPx = 1.;     //!< keypoint noise at level 0; the line test is chi2(1 dof, 95 %) x (sigma scale)^2
  double reprojectionSigmaPx = 1.; //!< reprojection test chi2(2 dof, 95 %) x (sigma scale)^2 in both views
  double minParallaxDeg = 1.;      //!< rays closer than this give no depth (ORB-SLAM2: cos < 0.9998, 1.15 deg)
};

//! Settings of WindowRelocalization.
struct WindowRelocalizationOptions {
  /*!
    Features per image: the extractor's 2000. Decision, measured on 7-Scenes 0-299 with frames 120-160 black over 11
    point budgets (490-510): with 1000 (ORB-SLAM2's at 640x480) the camera was found again in 7 of 11 runs, with 1500
    or 2000 in all 11, each at the first frame after the cover. They cost only while the camera is lost.
  */
  OrbExtractorOptions orb;
  ViewTriangulationOptions triangulation; //!< matching and checks between the window's keyframes
};

/*!
  Points of view \e a triangulated from ORB matches with view \e b (world coordinates, a's descriptors). A keypoint of
  a flagged in \e done (resized to a's keypoints) is skipped, and flagged once triangulated, so a view can be paired
  with several others without repeating its points. A match in b must lie within the epipolar band, be the best by
  Hamming distance and pass the ratio test among the keypoints in that band, and take a keypoint of b no better
  match took; the point must be in front of both cameras, with enough parallax and a small reprojection error in
  both.
  \return the number of points appended to \e wX and \e descriptors.
*/
VISP_EXPORT int triangulateViews(const DescribedView &a, const DescribedView &b, const PinholeIntrinsics &K,
                                 const ViewTriangulationOptions &options, std::vector<unsigned char> &done,
                                 std::vector<Eigen::Vector3d> &wX, std::vector<OrbDescriptor> &descriptors);

//! See the file comment.
class VISP_EXPORT WindowRelocalization
{
public:
  explicit WindowRelocalization(const PinholeIntrinsics &K,
                                const WindowRelocalizationOptions &options = WindowRelocalizationOptions());

  //! Scale-invariant ORB features of an image (the lost frame), in the form Relocalizer matches.
  RelocalizationFrame describe(const vpImage<unsigned char> &raw);
  /*!
    The window's triangulated points as one relocalisation candidate (id: the newest keyframe's). Each view is
    paired with every other, widest baseline first, so a point seen by several views comes once per view with that
    view's descriptor (a lost frame seen from nearer one of them matches that one). Views are described once and kept
    by id (an image never changes); the points are triangulated again when a view's pose or the set of views changed.
  */
  RelocalizationKeyframe windowPoints(const std::vector<WindowView> &views);
  //! Forget the described views and points (tracking resumed: the window will move).
  void clear();

  /*!
    How the lost frame is matched to the window's points: ratio 0.9 and Hamming 64 instead of relocalisation's
    0.75 and 50, AP3P hypotheses from 4 matches and up to 2000 RANSAC iterations instead of EPnP from 5 and 300.
    Decision, measured on 7-Scenes 0-299 with frames 120-160 black: the frame 0.26 m and 10 degrees away from the
    window matches 35 of its 1738 points at 0.75 / 50, too few to agree on a pose, and about 210 at 0.9 / 64, of
    which 20-40 are right (about 15 %): EPnP samples of 5 then rarely hold only right ones. Over six covers (7-Scenes
    120-125, 120-135, 120-160, 60-100, 200-240, Tsukuba 60-80; 1000 features per image) one map segment was kept in 6
    with these values, 3 with ORB-SLAM2's (0.75 / 50, EPnP, 300), 3 with 0.8 / 50 and AP3P, 5 with 0.9 / 64 and EPnP.
    A rotation-consistency histogram on these matches (OrbMatcher's) lowered 7 of 11 point budgets to 5 of 11.
    A wrong place is still refused: 30 inliers after refinement (tracking.relocalizationMinInliers), then the
    photometric alignment and 15 of those matches agreeing with it.
  */
  static RelocalizerOptions matchingOptions();

private:
  DescribedView describeView(const WindowView &view);
  //! ORB features of an image: level-0 pixels, level scale factors and descriptors.
  void extract(const vpImage<unsigned char> &raw, std::vector<Eigen::Vector2d> &uv, std::vector<float> &scale,
               std::vector<OrbDescriptor> &descriptors);

  PinholeIntrinsics m_K;
  WindowRelocalizationOptions m_options;
  OrbExtractor m_extractor;
  std::map<int, DescribedView> m_views;
  //! The last triangulation and the (id, pose) of the views it came from: a lost camera queries the same window.
  RelocalizationKeyframe m_points;
  std::vector<std::pair<int, SE3d>> m_pointsFrom;
};
} // namespace hslam

#endif
