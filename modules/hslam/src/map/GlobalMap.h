/*
 * H-SLAM for ViSP.
 */
/*!
  \file GlobalMap.h
  \brief The global map: marginalised keyframes kept lean, their points in the window's inverse-depth form, and
  the hybrid connectivity graph (co-visibility + pose-pose edges) with keyframe culling.

  What it is for: H-SLAM paper sec. 3.3 and ARCHITECTURE.md "Global map" / "Hybrid connectivity graph". When a
  keyframe leaves the photometric window, the mapper hands it here: pose, affine brightness, exposure and its
  points (host pixel, inverse depth and variance, ORB descriptor, kind, observers); pyramids, images and patches
  are released with the window's Keyframe. Re-use (map/GlobalPointReuse.h) reads the points back into the window.

  Co-visibility: a point is seen by its host and by its observers (keyframes where it had an inlier photometric
  residual); two keyframes share the point when both are in that set. An edge joins keyframes sharing at least
  covisibilityMinShared points (weight = count). Pose-pose edges join consecutive keyframes and keyframes that
  shared residuals in the window, with relative pose and information (WindowOptimizer::pairInformation).

  Culling (ORB-SLAM's redundancy rule on this graph): a stored keyframe whose points are observed, for more than
  cullObservedShare of them, by at least cullMinObservers other keyframes from outside its own window (ids more
  than windowSize apart: keyframes that came back to the place) is culled. The window's own observers do not
  count: in a sliding window every point is seen by the window's keyframes, so with them ORB-SLAM's rule culled
  53-78 % of all keyframes on sequences that never come back, and loop detection lost its database. Culled: it leaves
  the co-visibility graph and the keyframe database (the caller removes it there; observers already culled do not
  count), but keeps its pose node and pose-pose edges (a control point for the pose graph) and the points it hosts (the
  map loses no point: the host only defines the parametrisation).

  Threading: not thread-safe; the mapping thread owns it.
*/
#ifndef HSLAM_MAP_GLOBAL_MAP_H
#define HSLAM_MAP_GLOBAL_MAP_H

#include "features/BinaryDescriptor.h"
#include "map/AffineBrightness.h"
#include "math/SE3.h"
#include "math/Sim3.h"

#include <visp3/core/vpConfig.h>

#include <Eigen/Core>

#include <algorithm>
#include <array>
#include <cstdint>
#include <limits>
#include <map>
#include <utility>
#include <vector>

namespace hslam
{
//! What became of a stored point.
enum class GlobalPointState : uint8_t {
  stored,      //!< in the global map, fixed
  reactivated, //!< early adoption: back in the window, hosted by a new keyframe (this copy is kept for history)
  fused        //!< late fusion: absorbed by an active point
};

//! A marginalised point: no patch, everything else of MapPoint.
struct GlobalPoint {
  float u = 0.f, v = 0.f;  //!< host pixel, level 0
  float idepth = 0.f;      //!< inverse depth in the host camera
  float idepthVar = 0.f;   //!< its variance (from the window Hessian at marginalisation)
  OrbDescriptor orb;       //!< ORB at the host pixel
  float orbAngleDeg = 0.f; //!< orientation of the descriptor
  bool isCorner = false;
  bool hasOrb = false;
  GlobalPointState state = GlobalPointState::stored;
  std::vector<int> observers; //!< other keyframes with an inlier residual (sorted ids)
  //! Where the point was seen in each observer (same order as observers; NaN: not known, e.g. a version-1 map
  //! file). Measured when the host left the window: the projection through the window's optimised poses and
  //! inverse depth, i.e. where the photometric residuals put it; re-used points keep their older measurements.
  //! The global bundle adjustment's observations.
  std::vector<std::array<float, 2>> observedAt;
};

//! Drops the observers (and their pixels) of \e p for which \e drop(id) is true.
template <typename Drop> void dropObservers(GlobalPoint &p, Drop drop)
{
  size_t out = 0;
  for (size_t i = 0; i < p.observers.size(); ++i) {
    if (!drop(p.observers[i])) {
      p.observers[out] = p.observers[i];
      if (i < p.observedAt.size()) {
        p.observedAt[out] = p.observedAt[i];
      }
      ++out;
    }
  }
  p.observers.resize(out);
  p.observedAt.resize(std::min(out, p.observedAt.size()));
}

//! A marginalised keyframe.
struct GlobalKeyframe {
  int id = -1;
  int frameId = -1;
  int segment = 0;
  double timestamp = 0.;
  double exposure = 1.;
  SE3d cMw;
  AffineBrightness affine;
  std::vector<GlobalPoint> points;
  bool culled = false;
  //! Set by GlobalMap whenever the keyframe may have changed (stored, restored, or reached through
  //! findForChange()): caches of its points (ReuseKeyframeSelector) compare it. Never saved; never repeated in a map.
  uint64_t revision = 0;
};

//! Relative pose constraint between two keyframes.
struct PosePoseEdge {
  int from = -1, to = -1;
  SE3d toMfrom;
  Eigen::Matrix<double, 6, 6> information = Eigen::Matrix<double, 6, 6>::Zero();
  bool consecutive = false; //!< consecutive keyframes (else: shared residuals in the window)
};

/*!
  Pose-pose link between two window keyframes from the photometric residuals they share (both directions), for the
  hybrid connectivity graph: the relative pose and its information (6x6, left perturbation of otherMthis, twist
  order translation, rotation) = the pose block of the residuals' J^T W J at the current state. Inverse depths are
  held fixed in it (not Schur-complemented), so it is optimistic; the pose graph weighs edges relative to each
  other, which this keeps.
*/
struct PairInformation {
  int otherKeyframeId = -1;
  SE3d otherMthis;                         //!< relative pose at marginalisation
  Eigen::Matrix<double, 6, 6> information; //!< see above
  int residuals = 0;                       //!< inlier residuals between the two (both directions)
};

//! Co-visibility edge (a < b).
struct CovisibilityEdge {
  int a = -1, b = -1;
  int weight = 0; //!< points seen by both
};

//! Graph and culling settings (vpHSlamParameters::GlobalMap).
struct GlobalMapOptions {
  int covisibilityMinShared = 15; //!< points two keyframes share to be co-visible (ORB-SLAM)
  double cullObservedShare = 0.9; //!< culling: share of points observed by enough other keyframes (ORB-SLAM)
  int cullMinObservers = 3;       //!< ... and how many other keyframes (ORB-SLAM)
  int windowSize = 7;             //!< observers within this many keyframe ids of the host do not count for culling
};

class VISP_EXPORT GlobalMap
{
public:
  using Options = GlobalMapOptions;

  explicit GlobalMap(const Options &options = Options()) : m_options(options) {}

  void clear();

  /*!
    Store a marginalised keyframe and count its points' co-visibility. Returns true when the culling rule removed
    it at once (its id must then leave the keyframe database).
  */
  bool add(GlobalKeyframe keyframe);
  void addPosePoseEdge(const PosePoseEdge &edge);
  /*!
    Replace the whole map by keyframes and edges read back from a map file: co-visibility is counted again from the
    points' observers, culled flags are kept as they are (the culling rule is not applied again, so a saved and
    reloaded map is the same map).
  */
  void restore(std::vector<GlobalKeyframe> keyframes, std::vector<PosePoseEdge> edges);

  /*!
    A stored point leaves the global map into the window (early adoption or late fusion): its co-visibility
    counts are withdrawn (the active point carries its observers on) and its state set.
  */
  void absorb(int keyframeId, size_t pointIndex, GlobalPointState state);

  /*!
    Keyframe \e observerId saw stored point \e pointIndex of keyframe \e keyframeId at pixel (u, v) (loop fusion): it
    becomes an observer (co-visibility counted) with that measurement. No effect for a point that is not stored, its
    own host, or an observer it already has.
  */
  void addObservation(int keyframeId, size_t pointIndex, int observerId, float u, float v);

  /*!
    A loop correction moved stored keyframe \e id to the similarity \e Siw: its pose becomes the rigid part and its
    points follow their host (inverse depths multiplied by the scale: X_camera' = X_camera / s). False when absent.
  */
  bool applySimilarity(int id, const Sim3d &Siw);
  /*!
    The map without its points: keyframe poses, segments and culled flags, co-visibility counts and pose-pose edges.
    What loop detection and the pose graph read, copied so that another thread can read it while this map changes.
  */
  GlobalMap graphCopy() const;
  //! The stored keyframe \e id to change (nullptr when absent); it gets a new GlobalKeyframe::revision.
  GlobalKeyframe *findForChange(int id);
  const GlobalKeyframe *find(int id) const;
  const std::map<int, GlobalKeyframe> &keyframes() const { return m_keyframes; }
  const std::vector<PosePoseEdge> &posePoseEdges() const { return m_posePose; }

  //! Co-visibility edges of weight >= covisibilityMinShared, culled keyframes left out.
  std::vector<CovisibilityEdge> covisibilityEdges() const;
  //! Keyframes co-visible with \e id (any keyframe id, stored or still in the window), culled ones left out; in
  //! increasing id, at most \e maxCount of them.
  std::vector<int> covisibleWith(int id, size_t maxCount = std::numeric_limits<size_t>::max()) const;

  /*!
    Culling rule of the file comment applied to a stored keyframe (again: later observations may make it
    redundant). Returns true when it is culled now.
  */
  bool applyCulling(int id);

  int culledCount() const { return m_culled; }
  //! Points hosted by the stored keyframes, whatever their state (kept as keyframes are stored, not counted).
  size_t pointCount() const { return m_pointCount; }
  //! Bytes held: keyframes, points (with their observer lists), counts and edges.
  double memoryBytes() const;

private:
  //! For changes the revision does not guard (observers, the culled flag): the points' positions and states stay.
  GlobalKeyframe *findKeepingRevision(int id);
  //! \e keyframe into the map (replacing one of its id): a new revision, its points and co-visibility counted.
  GlobalKeyframe &store(GlobalKeyframe keyframe);
  void countShared(const GlobalPoint &p, int host, int sign);
  bool isCulled(int id) const;

  Options m_options;
  std::map<int, GlobalKeyframe> m_keyframes;
  //! Symmetric adjacency: m_shared[a][b] = m_shared[b][a] = points seen by both (co-visibility queries per keyframe
  //! read one row instead of every pair).
  std::map<int, std::map<int, int>> m_shared;
  std::vector<PosePoseEdge> m_posePose;
  int m_culled = 0;
  uint64_t m_nextRevision = 1; //!< not reset by clear(): a revision is never given twice by one map
  size_t m_pointCount = 0;
};
} // namespace hslam

#endif
