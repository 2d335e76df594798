/*
 * H-SLAM for ViSP.
 */
/*!
  \file PointActivation.h
  \brief Which immature points become active map points: distance map over the newest keyframe and DSO's adaptive
  minimum distance (DSO FullSystem::activatePointsMT and CoarseDistanceMap).

  Each new keyframe: the active points of the other window keyframes are projected into the newest keyframe at a
  coarse pyramid level (DSO: level 1) and a breadth-first search gives every pixel its distance to the nearest
  projection (steps alternate 8- and 4-neighbourhoods, an octagonal approximation of the Euclidean distance,
  capped at 40 steps as in DSO). An immature point of any window keyframe is activated when its inverse-depth
  interval is ready (small on the image, distinctive match, traced without outlier) and its projection falls on a
  pixel at least minDistance * 2^selectionLevel away from every active point; each activation adds itself to the
  map, so candidates keep apart from each other too. minDistance is adapted once per keyframe so that the number
  of active points approaches the desired density (DSO's currentMinActDist rule).

  Threading: a PointActivation belongs to the mapping thread; it keeps its buffers between keyframes (no
  allocation once the image size is known). Keyframes are read only; the caller applies the returned plan.
*/
#ifndef HSLAM_MAPPING_POINT_ACTIVATION_H
#define HSLAM_MAPPING_POINT_ACTIVATION_H

#include "features/ImagePyramid.h"
#include "map/Keyframe.h"
#include "map/MapPoint.h"

#include <visp3/core/vpConfig.h>
#include <visp3/hslam/vpHSlamParameters.h>

#include <utility>
#include <vector>

namespace hslam
{
//! Address of an immature point: index of its host in the window vector, index in the host's immature list.
struct ImmaturePointRef {
  int windowIndex = -1;
  int pointIndex = -1;
};

//! An immature point selected for activation, with its initial inverse depth.
struct ActivationCandidate {
  ImmaturePointRef ref;
  int hostKeyframeId = -1;
  float idepth = 0.f;    //!< initial inverse depth: centre of the interval, 1/m (DSO, before its GN refinement)
  float idepthMin = 0.f; //!< interval, 1/m
  float idepthMax = 0.f; //!< interval, 1/m
  float uNewest = 0.f;   //!< projection of the centre into the newest keyframe, level-0 pixels
  float vNewest = 0.f;
};

//! Outcome of one activation pass; the caller creates map points for \e activate and removes \e drop.
struct ActivationPlan {
  std::vector<ActivationCandidate> activate; //!< in window order, then point order
  std::vector<ImmaturePointRef> drop;        //!< hopeless: never traced, outlier, or left the newest keyframe's view
};

/*!
  Distance map and activation decisions (see the file comment). Parameters: Mapper::activationMinDistance (initial
  minimum distance), maxTraceInterval, minTraceQuality; the desired number of active points comes from
  Features::desiredPointDensity through adaptMinDistance().
*/
class VISP_EXPORT PointActivation
{
public:
  explicit PointActivation(const vpHSlamParameters::Mapper &mapper);

  //! Pyramid level of the distance map (DSO: 1, i.e. half resolution).
  static constexpr int kDistanceMapLevel = 1;
  //! Value of pixels the search did not reach (no active point within its step limit).
  static constexpr float kFarDistance = 1000.f;
  //! The search stops after this many steps (DSO: 40); farther pixels keep kFarDistance.
  static constexpr int kMaxSearchSteps = 40;

  /*!
    Distance map from seed pixels given directly at the map's resolution (width x height); seeds outside
    (0, width) x (0, height) (DSO: the first row and column excluded too) are ignored.
  */
  void buildDistanceMap(int width, int height, const std::vector<std::pair<int, int>> &seeds);

  /*!
    Distance map over \e newest at kDistanceMapLevel from the ACTIVE points of every other keyframe of
    \e window (projected with their current inverse depth and the keyframes' poses cMw).
  */
  void buildDistanceMap(const std::vector<KeyframePtr> &window, const Keyframe &newest);

  int width() const { return m_width; }   //!< distance map width, pixels at kDistanceMapLevel
  int height() const { return m_height; } //!< distance map height
  //! Distance (in search steps, about pixels at kDistanceMapLevel) of map pixel (u, v) to the nearest seed.
  float distanceAt(int u, int v) const { return m_distance[static_cast<size_t>(v * m_width + u)]; }

  /*!
    True when a point of \e selectionLevel projecting to (u, v) (continuous pixel at the map's level) is far enough
    from active points: distance + frac(u) >= minDistance * 2^selectionLevel. The fractional part breaks ties
    between integer distances so a fractional minimum distance thins points gradually (DSO).
  */
  bool canActivate(float u, float v, int selectionLevel) const;

  //! Record an activation at map pixel (u, v): it becomes a seed (DSO addIntoDistFinal).
  void addActivated(int u, int v);

  /*!
    DSO's rule: lower the minimum distance when there are too few active points, raise it when too many,
    in steps that grow with the mismatch, clamped to [0, 4].
  */
  void adaptMinDistance(int activeCount, int desiredCount);
  float minDistance() const { return m_minDistance; }
  void setMinDistance(float distance) { m_minDistance = distance; }

  /*!
    Whether the interval of \e pt is ready for activation (DSO): last trace good, skipped (already certain),
    bad condition or out of bounds; \e pixelInterval (length of the interval projected in the newest keyframe)
    below maxTraceInterval; quality above minTraceQuality; positive interval centre.
  */
  bool isReady(const ImmaturePoint &pt, float pixelInterval) const;

  /*!
    One activation pass (DSO activatePointsMT, without the GN refinement that the window optimisation does): with
    the current distance map (call buildDistanceMap() first) and minimum distance (adaptMinDistance() is the
    caller's, once per keyframe, before), visit the immature points of every window keyframe but \e newest.
    Selected points are added to the distance map as they are chosen. Nothing is modified in the window.

    Per keyframe, the mapper does (DSO order):
    \code
    activation.adaptMinDistance(activePointCount, params.features.desiredPointDensity);
    activation.buildDistanceMap(window, *newest);
    ActivationPlan plan = activation.selectPoints(window, *newest);
    for (const ActivationCandidate &c : plan.activate) { ... PointActivation::makeMapPoint(immature) + GN ... }
    PointActivation::eraseImmaturePoints(window, refsOfActivatedAndDropped);
    \endcode
  */
  ActivationPlan selectPoints(const std::vector<KeyframePtr> &window, const Keyframe &newest);

  //! Initial inverse depth of an activated point: the centre of its interval (DSO), 1/m.
  static float initialIdepth(const ImmaturePoint &pt) { return 0.5f * (pt.idepthMin + pt.idepthMax); }

  /*!
    An active MapPoint from an immature one: same host, pixel, patch and weights, inverse depth at the interval
    centre and, as a first variance, that of a uniform distribution over the interval (width^2 / 12); the window
    optimisation refines both.
  */
  static MapPoint makeMapPoint(const ImmaturePoint &pt);

  /*!
    Remove the referenced immature points from their hosts (any order, duplicates allowed); the others keep their
    order, their indices shift.
  */
  static void eraseImmaturePoints(const std::vector<KeyframePtr> &window, const std::vector<ImmaturePointRef> &refs);

private:
  void resize(int width, int height);
  void growFromSeeds(int seedCount);

  float m_maxTraceInterval;
  float m_minTraceQuality;
  float m_minDistance;
  int m_width = 0;
  int m_height = 0;
  std::vector<float> m_distance;                    //!< row-major, m_width x m_height
  std::vector<std::pair<int, int>> m_front, m_next; //!< BFS fronts (reused)
};
} // namespace hslam

#endif
