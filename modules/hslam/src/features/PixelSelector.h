/*
 * H-SLAM for ViSP.
 */
/*!
  \file PixelSelector.h
  \brief DSO-style selection of well-textured pixels on a new keyframe (region-adaptive gradient threshold, three
  block levels, adaptive block size), leaving out cells already taken by FAST corners.
*/
#ifndef HSLAM_FEATURES_PIXEL_SELECTOR_H
#define HSLAM_FEATURES_PIXEL_SELECTOR_H

#include "features/ImagePyramid.h"

#include <visp3/core/vpConfig.h>
#include <visp3/hslam/vpHSlamParameters.h>

#include <vector>

namespace hslam
{
//! A selected pixel: level-0 integer pixel (u right, v down) and the selection level that picked it.
struct SelectedPixel {
  int u = 0;     //!< column at level 0, pixels
  int v = 0;     //!< row at level 0, pixels
  int level = 0; //!< 0: picked in a d-block at level 0; 1: 2d-block, level-1 gradient; 2: 4d-block, level 2 (DSO type)
};

/*!
  Cells of a level-0 image already taken by other features (FAST corners): the selector skips every pixel of an
  occupied cell and asks for markedPoints() fewer pixels.

  Ownership: a plain value filled by the caller (the features code) before PixelSelector::select().
*/
class OccupancyGrid
{
public:
  //! All cells free, no point marked. \e cellSize in pixels (>= 1), cells cover width x height pixels.
  void reset(int width, int height, int cellSize)
  {
    m_cellSize = cellSize < 1 ? 1 : cellSize;
    m_width = width;
    m_height = height;
    m_cols = (width + m_cellSize - 1) / m_cellSize;
    m_rows = (height + m_cellSize - 1) / m_cellSize;
    m_cells.assign(static_cast<size_t>(m_cols) * static_cast<size_t>(m_rows), 0);
    m_markedPoints = 0;
  }
  //! Marks the cell holding level-0 pixel (u, v) (rounded to nearest) and counts one point; ignored outside.
  void markPoint(float u, float v)
  {
    const int x = static_cast<int>(u + 0.5f);
    const int y = static_cast<int>(v + 0.5f);
    if (u < -0.5f || v < -0.5f || x >= m_width || y >= m_height) {
      return;
    }
    m_cells[static_cast<size_t>((y / m_cellSize) * m_cols + x / m_cellSize)] = 1;
    ++m_markedPoints;
  }
  //! True when the cell of level-0 pixel (x, y) is taken (false outside the grid).
  bool isOccupied(int x, int y) const
  {
    if (x < 0 || y < 0 || x >= m_width || y >= m_height) {
      return false;
    }
    return m_cells[static_cast<size_t>((y / m_cellSize) * m_cols + x / m_cellSize)] != 0;
  }
  int width() const { return m_width; }               //!< pixels
  int height() const { return m_height; }             //!< pixels
  int cellSize() const { return m_cellSize; }         //!< pixels
  int cols() const { return m_cols; }                 //!< cells per row
  int markedPoints() const { return m_markedPoints; } //!< points marked since reset()
  //! Row \e cellY of the cell flags (cols() bytes, non-zero = taken).
  const unsigned char *cellRow(int cellY) const { return m_cells.data() + static_cast<size_t>(cellY) * m_cols; }

private:
  int m_width = 0, m_height = 0, m_cellSize = 1, m_cols = 0, m_rows = 0, m_markedPoints = 0;
  std::vector<unsigned char> m_cells;
};

/*!
  Region-adaptive gradient pixel selection (DSO PixelSelector2, re-implemented).

  1. Threshold map: the level-0 image is cut into blocks of Features::selectionBlockSize pixels (a remainder
     narrower than a block joins the last block, so any image size works); per block the median of |grad I|
     (integer histogram capped at 48, DSO) plus Features::gradientThresholdAdd; the value is averaged over the
     3x3 neighbouring blocks and squared (it is compared with squared gradients).
  2. Selection: blocks of d, 2d and 4d pixels (d = the "potential"). In each d-block, the level-0 pixel whose
     gradient is above the threshold and whose gradient projected on a random direction (16 directions, one per
     block, from the seed) is largest. A 2d-block where no d-block found a pixel takes the best pixel whose
     level-1 gradient passes the threshold times f; a 4d-block without any pick takes one from level 2 with
     threshold times f^3 (f = Features::gradientThresholdLevelFactor; DSO applies it once, then squared again).
     Random directions spread the picks over edges of all orientations.
  3. Count: the number picked behaves as K / (d + 1)^2 (DSO). When it is more than 1.25 times too few (and d > 1)
     or 4 times too many, d is corrected from that model and the selection re-run (at most twice); the surplus is
     then removed by a seeded random subsampling, so the result has exactly the target when enough texture exists.
     The final d is kept as the start for the next frame (DSO).

  Determinism: no global random state; the output depends only on the pyramid, the target, the seed, the mask
  and the potential left by the previous call (two selectors fed the same calls give identical output).

  Threading: one selector per thread (it holds scratch buffers reused between calls, so no allocation once
  sizes are stable).

  \code
  PixelSelector selector(params.features);
  std::vector<SelectedPixel> pixels;
  selector.select(frame.pyramid, params.features.desiredImmatureDensity, frameId, pixels, &cornerCells);
  \endcode
*/
class VISP_EXPORT PixelSelector
{
public:
  /*!
    \param params : selection settings (block size, threshold add, level factor, selection levels).
    \exception vpHSlamException::invalidArgument when selectionBlockSize < 1 or selectionLevels is not in 1..3.
  */
  explicit PixelSelector(const vpHSlamParameters::Features &params);

  /*!
    Select about \e desiredCount pixels (minus occupied->markedPoints()).
    \param pyramid : the frame's pyramid (level 0 at least; coarser selection levels need those levels).
    \param desiredCount : target count, corners included (e.g. Features::desiredImmatureDensity).
    \param seed : seeds the block directions and the subsampling (e.g. the frame id).
    \param selected : output, sorted row-major; previous content replaced.
    \param occupied : optional cells taken by corners, same size as level 0, or nullptr.
    \return selected.size().
    \exception vpHSlamException::invalidArgument when the pyramid is empty or the grid size differs.
  */
  int select(const ImagePyramid &pyramid, int desiredCount, unsigned int seed, std::vector<SelectedPixel> &selected,
             const OccupancyGrid *occupied = nullptr);

  //! Squared level-0 gradient threshold at level-0 pixel (u, v) from the last select() (compare with gradSq).
  float squaredThresholdAt(int u, int v) const;
  //! Multiplier of the squared threshold for a pick at selection level \e level (1, f, f^3).
  float levelThresholdFactor(int level) const;
  //! Block size d to be used by the next select(), pixels.
  int potential() const { return m_potential; }
  //! Candidates found by the last selection run, before subsampling.
  int lastCandidateCount() const { return m_lastCandidates; }
  //! Selection runs of the last select() (1 + re-runs).
  int lastRunCount() const { return m_lastRuns; }
  //! Back to the initial block size (DSO: 3).
  void reset();

private:
  void computeThresholds(const PyramidLevel &level0);
  int selectOnce(const ImagePyramid &pyramid, int potential, unsigned int seed, const OccupancyGrid *occupied);
  void selectLevel(const ImagePyramid &pyramid, int level, int blockSize, unsigned int seed,
                   const OccupancyGrid *occupied);
  //! Marks the blocks of \e level (nbx per row; image w x h) in which a finer level already picked a pixel (DSO).
  void inheritTakenBlocks(int level, int blockSize, int w, int h, int nbx);
  //! Blocks of row \e by: no best pixel yet, and the pseudo-random direction their gradients are ranked along.
  void resetBlockRow(unsigned int seed, int level, int by, int nbx);
  //! m_rowThreshold for one pixel row of width \e w: level factor times the block threshold, +inf in occupied cells.
  void fillRowThreshold(int thRowIndex, int cellRowIndex, float factor, const OccupancyGrid *occupied, int w);
  //! One pixel row (offset \e rowBase): in each free block, the pixel above the threshold with the largest gradient
  //! along the block's direction so far (DSO).
  void scanRow(const Eigen::Vector3f *colorRow, const float *gradRow, int level, int rowBase, int w, int blockSize,
               int nbx, const unsigned char *takenRow);
  //! The best pixel of each block of a row (image width \e w) becomes a candidate and takes its block.
  void collectBlockRow(int level, int w, int nbx, unsigned char *takenRow);
  void subsample(int count, unsigned int seed);

  vpHSlamParameters::Features m_params;
  int m_potential;
  int m_lastCandidates = 0;
  int m_lastRuns = 0;
  float m_levelFactor[3];
  float m_dirU[16], m_dirV[16];

  // Threshold blocks (reused buffers).
  int m_thWidth = 0, m_thHeight = 0, m_thCols = 0, m_thRows = 0;
  std::vector<int> m_thColOf;           //!< threshold block column of each level-0 column
  std::vector<int> m_hist;              //!< per block of one block row: |grad| histogram
  std::vector<float> m_thRaw;           //!< median + add per block
  std::vector<float> m_thSmoothSq;      //!< smoothed, squared, per block
  std::vector<unsigned char> m_sqrtBin; //!< floor(sqrt(i)) capped, for the |grad| histogram
  std::vector<float> m_rowThreshold;    //!< squared threshold of each pixel of the current row (+inf: occupied)
  std::vector<int> m_occColOf;          //!< occupancy cell column of each level-0 column
  // Selection scratch (reused buffers).
  std::vector<unsigned char> m_taken[3]; //!< per selection level: block already holds a pick
  std::vector<float> m_bestScore;
  std::vector<int> m_bestIndex;
  std::vector<int> m_blockDir;
  std::vector<SelectedPixel> m_candidates;
  std::vector<int> m_order;
};
} // namespace hslam

#endif
