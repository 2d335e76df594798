/*
 * H-SLAM for ViSP.
 */
/*!
  \file SparseIdepthInterpolator.h
  \brief Inverse-depth prior for any pixel of a frame from a sparse set of triangulated points (the two-view
  initializer's), by the median of the k nearest points in the image.

  What it is for: after two-view initialisation the first keyframe gets DSO-style immature points wherever the
  gradient is high, not only at the ORB corners that were triangulated. Each needs a starting inverse depth and
  an uncertainty for its photometric refinement; this gives both. The median of the k nearest neighbours (not
  their mean) keeps a depth discontinuity sharp and ignores a single wrong triangulation; the spread of those
  neighbours around it (mean absolute deviation, which a minority on the other side of an edge still widens) is the
  uncertainty, so a pixel between a near and a far object gets a wide prior.

  Threading: immutable after construction; query() is const and may run concurrently. No allocation per query.
*/
#ifndef HSLAM_MAPPING_SPARSE_IDEPTH_INTERPOLATOR_H
#define HSLAM_MAPPING_SPARSE_IDEPTH_INTERPOLATOR_H

#include <visp3/core/vpConfig.h>

#include <vector>

namespace hslam
{
//! A sample: pixel and inverse depth.
struct IdepthSample {
  double u = 0., v = 0.; //!< pixel
  double idepth = 0.;    //!< inverse depth (any consistent scale)
};

//! An interpolated prior.
struct IdepthPrior {
  double idepth = 0.;     //!< median inverse depth of the neighbours
  double idepthVar = 0.;  //!< variance: (1.4826 MAD)^2 of the neighbours plus a floor relative to idepth^2
  double farthestPx = 0.; //!< image distance of the farthest neighbour used, pixels
  int neighbours = 0;     //!< neighbours used
};

//! k-nearest-neighbour median interpolation of inverse depth on an image grid.
class VISP_EXPORT SparseIdepthInterpolator
{
public:
  //! Largest k supported (fixed-size buffers in query()).
  static constexpr int kMaxNeighbours = 32;

  /*!
    \param samples : triangulated points (copied); samples outside the image are kept (they still inform nearby
    pixels).
    \param width, height : image size, pixels.
    \param neighbours : k, in [1, kMaxNeighbours].
    \param minRelativeSigma : floor of the standard deviation as a fraction of the idepth (the neighbours may
    agree by chance; a pixel between them is still only interpolated).
    \exception vpHSlamException::invalidArgument for an empty sample set or out-of-range values.
  */
  SparseIdepthInterpolator(const std::vector<IdepthSample> &samples, int width, int height, int neighbours = 8,
                           double minRelativeSigma = 0.1);

  //! Prior at pixel (u, v). Always succeeds (uses min(k, sample count) neighbours).
  IdepthPrior query(double u, double v) const;

  int sampleCount() const { return static_cast<int>(m_samples.size()); }

private:
  std::vector<IdepthSample> m_samples;
  int m_neighbours;
  double m_minRelativeSigma;
  double m_cellSize;
  int m_cols, m_rows;
  std::vector<int> m_cellStart; //!< CSR: samples of cell c are m_cellIndex[m_cellStart[c] .. m_cellStart[c+1])
  std::vector<int> m_cellIndex;
};
} // namespace hslam

#endif
