/*
 * H-SLAM for ViSP.
 */
/*!
  \file GlobalMapKeeper.h
  \brief Upkeep of the global map: what leaves the window is kept lean, and stored points come back into the window
  (early adoption, late fusion). H-SLAM paper sec. 3.3; the matching itself is GlobalPointReuse.h.
*/
#ifndef HSLAM_MAP_GLOBAL_MAP_KEEPER_H
#define HSLAM_MAP_GLOBAL_MAP_KEEPER_H

#include "features/ImagePyramid.h"
#include "map/GlobalMap.h"
#include "map/GlobalPointReuse.h"
#include "map/Keyframe.h"

#include <visp3/core/vpConfig.h>
#include <visp3/hslam/vpHSlamParameters.h>

#include <functional>
#include <vector>

namespace hslam
{
/*!
  What re-use asks of the window (the window optimises; this component does not): the photometric refinement of a
  stored point's inverse depth as a new point of keyframe \e hostId (prior: the stored estimate), and an immature
  point turned into an active map point.
*/
struct ReuseRefinement {
  struct Result {
    bool accepted = false;
    double idepth = 0.;
    double idepthHessian = 0.;
  };
  std::function<Result(int hostId, const ImmaturePoint &pt, double idepth, double priorWeight)> refine;
  std::function<MapPoint(const ImmaturePoint &pt)> activate;
};

/*!
  The global map and its upkeep (system.mode vo-reuse and slam).

  What it owns: the GlobalMap (stored keyframes in the window's inverse-depth form, pose-pose and co-visibility
  graph, culling), the segment the keyframes being made belong to (re-use and loops stay within a segment), and the
  re-use counters.

  What it is given: each keyframe that leaves the window with the window around it and its pose-pose information
  (store()); each new keyframe with the window, to bring stored points back (reuse()); loaded maps (restore()).

  What it hands back: the map itself (globalMap(): read by the loop closer and relocalisation, moved by loop
  corrections), whether a keyframe stored was culled at once (its indexes elsewhere must forget it), the re-used
  points placed in the window's keyframes, the map as a file holds it (snapshot()).

  Threading: not thread-safe; owned by the mapper (mapping thread, or the caller in deterministic mode).
*/
class VISP_EXPORT GlobalMapKeeper
{
public:
  //! Counters of global-map re-use since the start.
  struct Statistics {
    int keyframes = 0;        //!< keyframes made while re-use was on
    int reactivated = 0;      //!< global points re-activated by early adoption
    int fused = 0;            //!< global points absorbed by late fusion
    int windowActive = 0;     //!< active points in the window now
    int windowFromGlobal = 0; //!< of which came from the global map
    int storedKeyframes = 0;  //!< keyframes in the global map
    int culledKeyframes = 0;  //!< of which culled (pose node only)
    size_t storedPoints = 0;  //!< points held by the global map (any state)
  };

  GlobalMapKeeper(const vpHSlamParameters &params, const PinholeIntrinsics &K0, int width, int height);

  /*!
    Store \e kf, leaving \e window now (it is still in it), with its pose-pose links \e pairs. True when the global
    map culled it at once (it keeps only its pose node).
  */
  bool store(const Keyframe &kf, const std::vector<KeyframePtr> &window, const std::vector<PairInformation> &pairs);
  /*!
    Early adoption into \e newest (the window's newest keyframe), then late fusion in \e window; returns the points
    re-activated. \e seedKeyframe: a stored keyframe a relocalisation placed the frame against (-1: none); its
    neighbourhood is searched whatever the overlap test says.
  */
  int reuse(Keyframe &newest, const std::vector<KeyframePtr> &window, int seedKeyframe,
            const ReuseRefinement &refinement);
  //! A stored keyframe, its co-visible keyframes and its neighbours in time that the global map holds (not culled).
  std::vector<int> storedNeighbourhood(int id) const;
  //! Of \e keyframeIds, the stored keyframe whose camera is closest to \e cMw (centre distance; -1 when none).
  int closestKeyframe(const SE3d &cMw, const std::vector<int> &keyframeIds) const;
  //! Re-use counters, with the window's share of re-used points.
  Statistics statistics(const std::vector<KeyframePtr> &window) const;
  //! Points of the stored keyframes in world coordinates (appended).
  void pointsWorld(std::vector<Eigen::Vector3d> &points, std::vector<int> &status) const;

  /*!
    The map as a file holds it: the stored keyframes and edges, and \e window's keyframes as if marginalised now
    (marginalised and active points, converged immature ones, pose-pose edges from \e pairsOf). Observers and edges
    naming keyframes that are not held are left out.
  */
  void snapshot(const std::vector<KeyframePtr> &window, const std::function<std::vector<PairInformation>(int)> &pairsOf,
                std::vector<GlobalKeyframe> &keyframes, std::vector<PosePoseEdge> &edges) const;
  //! A loaded map becomes the global map; the next segment comes after its segments.
  void restore(std::vector<GlobalKeyframe> keyframes, std::vector<PosePoseEdge> edges);

  GlobalMap &globalMap() { return m_map; }
  const GlobalMap &globalMap() const { return m_map; }
  //! Bytes held: the map and what the keyframe selection keeps of it.
  double memoryBytes() const { return m_map.memoryBytes() + m_selector.memoryBytes(); }
  int segment() const { return m_segment; }
  //! A new segment starts (tracking was lost); the stored keyframes stay.
  void newSegment() { ++m_segment; }
  //! Everything dropped, counters included.
  void reset();

private:
  //! A window keyframe as the global map keeps it: marginalised points, and active ones too when asked (snapshot).
  GlobalKeyframe leanKeyframe(const Keyframe &kf, const std::vector<KeyframePtr> &window, bool withActivePoints) const;
  //! Pose-pose edges of a keyframe from its pair information, plus temporal links to window neighbours it shared no
  //! residual with.
  std::vector<PosePoseEdge> posePoseEdges(const Keyframe &kf, const std::vector<KeyframePtr> &window,
                                          const std::vector<PairInformation> &pairs) const;
  /*!
    Early adoption: \e newest's corner candidates (\e target, its keypoint k being immature point
    keypointToImmature[k]) matched to the points of \e searched; returns the adopted. \e alone: the keyframe is
    alone in the window (nothing to refine against).
  */
  int adopt(Keyframe &newest, bool alone, const std::vector<int> &searched, const ReuseTarget &target,
            const std::vector<size_t> &keypointToImmature, const ReuseRefinement &refinement);
  //! Late fusion: active corners of the window matching a stored point of \e searched absorb it.
  int fuse(const std::vector<KeyframePtr> &window, const std::vector<int> &searched);

  vpHSlamParameters m_params;
  PinholeIntrinsics m_K0;
  int m_width, m_height;
  GlobalMap m_map;
  ReuseKeyframeSelector m_selector; //!< the stored keyframes searched at each keyframe (keeps their samples)
  int m_segment = 0;                //!< segment of the keyframes being made
  Statistics m_stats;
};
} // namespace hslam

#endif
