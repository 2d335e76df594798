/*
 * H-SLAM for ViSP.
 */
/*!
  \file LoopFeatures.h
  \brief What a stored keyframe keeps for loop closure: multi-scale ORB keypoints of its image with a depth taken
  from the window's inverse-depth estimates, and the bag-of-words vector of their descriptors (paper sec. 3.4).

  What it is for: place recognition and Sim(3) verification need many well-spread, described points with a depth
  on both ends of a loop. The window's photometric points are too few for that once marginalised (about 90
  described, converged ones per keyframe at the default point budget: loops were found on real images but every
  one was rejected), and their number follows the photometric budget. So each keyframe that leaves the window gets
  its own set, sized for the job (loop.featuresPerKeyframe ORB keypoints over the pyramid the vocabulary was trained
  on, bucketed over the image), as ORB-SLAM keeps its keypoints and LDSO its corners.

  Depth: when the keyframe leaves the window its inverse depths are final. The samples are the window's points
  (its own and the other keyframes' active points, expressed in it); each keypoint takes the median inverse depth
  of its nearest samples (SparseIdepthInterpolator) when they are close in the image and agree with each other
  (kMaxSampleDistanceFraction, kMaxRelativeSpread), so a keypoint across a depth edge or in an empty area has none.
  Only keypoints with a depth are kept (a loop's 3D-3D match needs one on both sides), which also bounds memory.

  Threading: LoopFeatureExtractor holds an OrbExtractor (not thread-safe): one per thread. LoopKeyframe is a value.
*/
#ifndef HSLAM_LOOP_LOOP_FEATURES_H
#define HSLAM_LOOP_LOOP_FEATURES_H

#include "features/BinaryDescriptor.h"
#include "features/ImagePyramid.h"
#include "features/OrbExtractor.h"
#include "mapping/SparseIdepthInterpolator.h"

#include <visp3/core/vpConfig.h>
#include <visp3/core/vpImage.h>

#include <Eigen/Core>

#include <cstdint>
#include <vector>

namespace hslam
{
//! A keyframe's loop features: points in its camera frame with their descriptors (its BoW vector, of every
//! keypoint's descriptor, is kept by the keyframe database).
struct LoopKeyframe {
  int id = -1;
  std::vector<Eigen::Vector3f> X;   //!< keypoint with its depth, in the keyframe's camera frame
  std::vector<OrbDescriptor> orb;   //!< one per point
  std::vector<std::uint8_t> octave; //!< pyramid level the keypoint was detected at
  //! Bytes held on the heap (vectors' capacity).
  double memoryBytes() const;
  //! A loop correction scaled the keyframe's map: X_camera' = X_camera / scale.
  void rescale(double scale);
};

//! Extraction settings.
struct LoopFeatureOptions {
  int maxFeatures = 500;    //!< ORB keypoints detected per keyframe (loop.featuresPerKeyframe)
  int sampleNeighbours = 6; //!< window points whose median gives a keypoint its inverse depth
};

class VISP_EXPORT LoopFeatureExtractor
{
public:
  //! A keypoint's nearest depth samples must lie within this fraction of the image width (32 px at 640).
  static constexpr double kMaxSampleDistanceFraction = 0.05;
  //! ... and agree: robust standard deviation of their inverse depths at most this fraction of the median.
  static constexpr double kMaxRelativeSpread = 0.15;

  explicit LoopFeatureExtractor(const LoopFeatureOptions &options = LoopFeatureOptions());

  /*!
    Keypoints of \e image (rectified, raw 8-bit), each given an inverse depth from \e samples (the window's points
    in this keyframe's camera: pixel and inverse depth), only those with one kept. \e allDescriptors receives the
    descriptors of every keypoint, with or without a depth (for the BoW vector). No sample: no point.
  */
  LoopKeyframe extract(int id, const vpImage<unsigned char> &image, const std::vector<IdepthSample> &samples,
                       const PinholeIntrinsics &K, std::vector<OrbDescriptor> &allDescriptors);

  const LoopFeatureOptions &options() const { return m_options; }

private:
  LoopFeatureOptions m_options;
  OrbExtractor m_extractor;
};
} // namespace hslam

#endif
