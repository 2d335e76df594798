/*
 * H-SLAM for ViSP.
 */
// Region-adaptive gradient pixel selection after DSO's PixelSelector2 (Engel et al., "Direct Sparse Odometry"):
// see PixelSelector.h for the algorithm and the differences (any image size, exact count, seeded randomness).
#include "features/PixelSelector.h"
#include "common/TextParsing.h"

#include <visp3/hslam/vpHSlamException.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <sstream>

namespace hslam
{
namespace
{
//! Block size d of the first call (DSO: currentPotential = 3).
constexpr int kInitialPotential = 3;
//! Re-runs with a corrected d after the first selection (DSO makeMaps recursion; 2 converges on every test image).
constexpr int kMaxReruns = 2;
//! Re-run with a smaller d when wanted / found exceeds this (DSO: 1.25).
constexpr float kTooFewRatio = 1.25f;
//! Re-run with a larger d when wanted / found is below this (DSO: 0.25).
constexpr float kTooManyRatio = 0.25f;
//! Pixels this close to the border are never selected (DSO: 4; leaves room for the pattern and coarse lookups).
constexpr int kSelectionBorder = 4;
//! |grad| histogram: integer bins 0..kHistCap, larger values in the last bin (DSO: 48).
constexpr int kHistCap = 48;
constexpr int kHistBins = kHistCap + 1;
//! Squared gradients from this value on fall in the last bin: (kHistCap + 1)^2 - 1.
constexpr float kLastSquare = static_cast<float>(kHistBins * kHistBins - 1);
//! The block threshold is this quantile of |grad| (DSO setting_minGradHistCut = 0.5, the median).
constexpr double kHistQuantile = 0.5;
//! Number of random projection directions, spread over a half circle (DSO: 16).
constexpr int kNumDirections = 16;
constexpr int kMaxSelectionLevels = 3;
constexpr double kPi = 3.14159265358979323846;

[[noreturn]] void throwInvalid(int line, const std::string &what)
{
  throwAt(vpHSlamException::invalidArgument, __FILE__, static_cast<std::size_t>(line), "PixelSelector: " + what);
}

//! Integer hash (murmur3 finaliser style) of the seed, the level and a block: the block's random direction.
uint32_t hashBlock(uint32_t seed, uint32_t level, uint32_t bx, uint32_t by)
{
  uint32_t h =
      (seed * 0x9E3779B9u) ^ ((level + 1u) * 0x85EBCA6Bu) ^ ((bx + 1u) * 0xC2B2AE35u) ^ ((by + 1u) * 0x27D4EB2Fu);
  h ^= h >> 16;
  h *= 0x7FEB352Du;
  h ^= h >> 15;
  h *= 0x846CA68Bu;
  h ^= h >> 16;
  return h;
}

//! splitmix64: a small, platform-independent generator for the subsampling (std distributions are not portable).
uint64_t nextRandom(uint64_t &state)
{
  uint64_t z = (state += 0x9E3779B97F4A7C15ull);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}
} // namespace

PixelSelector::PixelSelector(const vpHSlamParameters::Features &params) : m_params(params), m_potential(0)
{
  if (params.selectionBlockSize < 1) {
    throwInvalid(__LINE__, "selectionBlockSize = " + std::to_string(params.selectionBlockSize) + ", must be >= 1");
  }
  if (params.selectionLevels < 1 || params.selectionLevels > kMaxSelectionLevels) {
    throwInvalid(__LINE__, "selectionLevels = " + std::to_string(params.selectionLevels) + ", must be in 1..3");
  }
  // DSO: level-1 threshold = f * level-0, level-2 threshold = f^2 * level-1 (squared-gradient units).
  const float f = static_cast<float>(params.gradientThresholdLevelFactor);
  m_levelFactor[0] = 1.f;
  m_levelFactor[1] = f;
  m_levelFactor[2] = f * f * f;
  for (int k = 0; k < kNumDirections; ++k) {
    const double angle = kPi * k / kNumDirections;
    m_dirU[k] = static_cast<float>(std::cos(angle));
    m_dirV[k] = static_cast<float>(std::sin(angle));
  }
  m_sqrtBin.resize(static_cast<size_t>(kHistBins * kHistBins));
  for (int i = 0; i < kHistBins * kHistBins; ++i) {
    m_sqrtBin[static_cast<size_t>(i)] =
        static_cast<unsigned char>(std::min(static_cast<int>(std::sqrt(static_cast<double>(i))), kHistCap));
  }
  reset();
}

void PixelSelector::reset()
{
  m_potential = kInitialPotential;
}

float PixelSelector::levelThresholdFactor(int level) const
{
  return (level >= 0 && level < kMaxSelectionLevels) ? m_levelFactor[level] : 0.f;
}

float PixelSelector::squaredThresholdAt(int u, int v) const
{
  if (m_thSmoothSq.empty() || u < 0 || v < 0 || u >= m_thWidth || v >= m_thHeight) {
    return 0.f;
  }
  const int bs = m_params.selectionBlockSize;
  const int bx = std::min(u / bs, m_thCols - 1);
  const int by = std::min(v / bs, m_thRows - 1);
  return m_thSmoothSq[static_cast<size_t>(by * m_thCols + bx)];
}

void PixelSelector::computeThresholds(const PyramidLevel &level0)
{
  const int w = level0.width;
  const int h = level0.height;
  const int bs = m_params.selectionBlockSize;
  if (w != m_thWidth || h != m_thHeight) {
    m_thWidth = w;
    m_thHeight = h;
    // A remainder narrower than a block joins the last block (DSO drops it and reads past the row instead).
    m_thCols = std::max(1, w / bs);
    m_thRows = std::max(1, h / bs);
    m_thColOf.resize(static_cast<size_t>(w));
    for (int x = 0; x < w; ++x) {
      m_thColOf[static_cast<size_t>(x)] = std::min(x / bs, m_thCols - 1);
    }
    m_hist.resize(static_cast<size_t>(m_thCols) * kHistBins);
    m_thRaw.resize(static_cast<size_t>(m_thCols) * static_cast<size_t>(m_thRows));
    m_thSmoothSq.resize(m_thRaw.size());
  }
  const float add = static_cast<float>(m_params.gradientThresholdAdd);
  for (int by = 0; by < m_thRows; ++by) {
    std::fill(m_hist.begin(), m_hist.end(), 0);
    const int y0 = by * bs;
    const int y1 = (by == m_thRows - 1) ? h : y0 + bs;
    for (int y = y0; y < y1; ++y) {
      // Bin floor(|grad|) = floor(sqrt(floor(gradSq))) through a table: no square root per pixel.
      const float *g = level0.gradSq.data() + static_cast<size_t>(y) * w;
      for (int bx = 0; bx < m_thCols; ++bx) {
        int *hist = &m_hist[static_cast<size_t>(bx * kHistBins)];
        const int x1 = (bx == m_thCols - 1) ? w : (bx + 1) * bs;
        for (int x = bx * bs; x < x1; ++x) {
          ++hist[m_sqrtBin[static_cast<size_t>(std::min(g[x], kLastSquare))]];
        }
      }
    }
    for (int bx = 0; bx < m_thCols; ++bx) {
      const int *hist = &m_hist[static_cast<size_t>(bx * kHistBins)];
      int total = 0;
      for (int b = 0; b < kHistBins; ++b) {
        total += hist[b];
      }
      const int rank = static_cast<int>(total * kHistQuantile);
      int cumulative = 0;
      int median = kHistCap;
      for (int b = 0; b < kHistBins; ++b) {
        cumulative += hist[b];
        if (cumulative > rank) {
          median = b;
          break;
        }
      }
      m_thRaw[static_cast<size_t>(by * m_thCols + bx)] = static_cast<float>(median) + add;
    }
  }
  // DSO: mean over the (up to) 3x3 neighbouring blocks, then squared to compare with squared gradients.
  for (int by = 0; by < m_thRows; ++by) {
    for (int bx = 0; bx < m_thCols; ++bx) {
      float sum = 0.f;
      int num = 0;
      for (int ny = std::max(0, by - 1); ny <= std::min(m_thRows - 1, by + 1); ++ny) {
        for (int nx = std::max(0, bx - 1); nx <= std::min(m_thCols - 1, bx + 1); ++nx) {
          sum += m_thRaw[static_cast<size_t>(ny * m_thCols + nx)];
          ++num;
        }
      }
      const float mean = sum / static_cast<float>(num);
      m_thSmoothSq[static_cast<size_t>(by * m_thCols + bx)] = mean * mean;
    }
  }
}

void PixelSelector::inheritTakenBlocks(int level, int blockSize, int w, int h, int nbx)
{
  std::vector<unsigned char> &taken = m_taken[level];
  const int childSize = blockSize / 2;
  const int ncx = (w + childSize - 1) / childSize;
  const int ncy = (h + childSize - 1) / childSize;
  const std::vector<unsigned char> &child = m_taken[level - 1];
  for (int cy = 0; cy < ncy; ++cy) {
    for (int cx = 0; cx < ncx; ++cx) {
      if (child[static_cast<size_t>(cy * ncx + cx)]) {
        taken[static_cast<size_t>((cy / 2) * nbx + cx / 2)] = 1;
      }
    }
  }
}

void PixelSelector::resetBlockRow(unsigned int seed, int level, int by, int nbx)
{
  for (int bx = 0; bx < nbx; ++bx) {
    m_bestScore[static_cast<size_t>(bx)] = -1.f;
    m_bestIndex[static_cast<size_t>(bx)] = -1;
    m_blockDir[static_cast<size_t>(bx)] = static_cast<int>(
        hashBlock(seed, static_cast<uint32_t>(level), static_cast<uint32_t>(bx), static_cast<uint32_t>(by)) %
        kNumDirections);
  }
}

void PixelSelector::fillRowThreshold(int thRowIndex, int cellRowIndex, float factor, const OccupancyGrid *occupied,
                                     int w)
{
  float *rowTh = m_rowThreshold.data();
  const float *thRow = m_thSmoothSq.data() + static_cast<size_t>(thRowIndex) * m_thCols;
  for (int x = 0; x < w; ++x) {
    rowTh[x] = factor * thRow[m_thColOf[static_cast<size_t>(x)]];
  }
  if (occupied) {
    const unsigned char *occRow = occupied->cellRow(cellRowIndex);
    for (int x = 0; x < w; ++x) {
      if (occRow[m_occColOf[static_cast<size_t>(x)]]) {
        rowTh[x] = std::numeric_limits<float>::infinity();
      }
    }
  }
}

void PixelSelector::collectBlockRow(int level, int w, int nbx, unsigned char *takenRow)
{
  for (int bx = 0; bx < nbx; ++bx) {
    const int index = m_bestIndex[static_cast<size_t>(bx)];
    if (index >= 0) {
      SelectedPixel p;
      p.u = index % w;
      p.v = index / w;
      p.level = level;
      m_candidates.push_back(p);
      takenRow[bx] = 1;
    }
  }
}

void PixelSelector::scanRow(const Eigen::Vector3f *colorRow, const float *gradRow, int level, int rowBase, int w,
                            int blockSize, int nbx, const unsigned char *takenRow)
{
  const int xMin = kSelectionBorder;
  const int xEnd = w - kSelectionBorder; // exclusive
  const float *rowTh = m_rowThreshold.data();
  for (int bx = 0; bx < nbx; ++bx) {
    if (takenRow[bx]) {
      continue;
    }
    const int x0 = std::max(bx * blockSize, xMin);
    const int x1 = std::min(bx * blockSize + blockSize, xEnd);
    const float du = m_dirU[m_blockDir[static_cast<size_t>(bx)]];
    const float dv = m_dirV[m_blockDir[static_cast<size_t>(bx)]];
    float best = m_bestScore[static_cast<size_t>(bx)];
    int bestIndex = m_bestIndex[static_cast<size_t>(bx)];
    for (int x = x0; x < x1; ++x) {
      // DSO: among pixels above the threshold, rank by the level-0 gradient projected on the block's random
      // direction (a branch-free variant measured 6 % slower: it reads every pixel's gradient vector).
      if (gradRow[x >> level] > rowTh[x]) {
        const float score = std::fabs(colorRow[x][1] * du + colorRow[x][2] * dv);
        if (score > best) {
          best = score;
          bestIndex = rowBase + x;
        }
      }
    }
    m_bestScore[static_cast<size_t>(bx)] = best;
    m_bestIndex[static_cast<size_t>(bx)] = bestIndex;
  }
}

void PixelSelector::selectLevel(const ImagePyramid &pyramid, int level, int blockSize, unsigned int seed,
                                const OccupancyGrid *occupied)
{
  const PyramidLevel &l0 = pyramid.level(0);
  const PyramidLevel &ll = pyramid.level(level);
  const int w = l0.width;
  const int h = l0.height;
  const int nbx = (w + blockSize - 1) / blockSize;
  const int nby = (h + blockSize - 1) / blockSize;
  std::vector<unsigned char> &taken = m_taken[level];
  taken.assign(static_cast<size_t>(nbx) * static_cast<size_t>(nby), 0);
  if (level > 0) {
    inheritTakenBlocks(level, blockSize, w, h, nbx);
  }
  m_bestScore.resize(static_cast<size_t>(nbx));
  m_bestIndex.resize(static_cast<size_t>(nbx));
  m_blockDir.resize(static_cast<size_t>(nbx));

  const float factor = m_levelFactor[level];
  const int yMin = kSelectionBorder;
  const int yEnd = h - kSelectionBorder;
  const int bs = m_params.selectionBlockSize;
  const int wl = ll.width;
  const int cellSize = occupied ? occupied->cellSize() : 1;
  // Per-pixel threshold of the current row, level factor applied and +inf in occupied cells. It changes only
  // with the threshold-block row and the occupancy-cell row, so it is refilled rarely and the pixel loop reads
  // it linearly with a single comparison.
  m_rowThreshold.resize(static_cast<size_t>(w));
  int filledThRow = -1, filledCellRow = -1;

  for (int by = 0; by < nby; ++by) {
    const int y0 = std::max(by * blockSize, yMin);
    const int y1 = std::min(by * blockSize + blockSize, yEnd);
    if (y0 >= y1) {
      continue;
    }
    unsigned char *takenRow = &taken[static_cast<size_t>(by) * nbx];
    resetBlockRow(seed, level, by, nbx);
    for (int y = y0; y < y1; ++y) {
      const int thRowIndex = std::min(y / bs, m_thRows - 1);
      const int cellRowIndex = occupied ? y / cellSize : 0;
      if (thRowIndex != filledThRow || cellRowIndex != filledCellRow) {
        filledThRow = thRowIndex;
        filledCellRow = cellRowIndex;
        fillRowThreshold(thRowIndex, cellRowIndex, factor, occupied, w);
      }
      const Eigen::Vector3f *colorRow = l0.color.data() + static_cast<size_t>(y) * w;
      // No clamping: with the border of 4 px, x >> l < floor(w / 2^l) (resp. y) for the levels l <= 2 used here.
      const float *gradRow = ll.gradSq.data() + static_cast<size_t>(y >> level) * wl;
      scanRow(colorRow, gradRow, level, y * w, w, blockSize, nbx, takenRow);
    }
    collectBlockRow(level, w, nbx, takenRow);
  }
}

int PixelSelector::selectOnce(const ImagePyramid &pyramid, int potential, unsigned int seed,
                              const OccupancyGrid *occupied)
{
  m_candidates.clear();
  const int levels = std::min(m_params.selectionLevels, pyramid.numLevels());
  for (int l = 0; l < levels; ++l) {
    selectLevel(pyramid, l, potential << l, seed, occupied);
  }
  return static_cast<int>(m_candidates.size());
}

void PixelSelector::subsample(int count, unsigned int seed)
{
  // Partial Fisher-Yates on indices: exactly `count` candidates, uniformly, from the seed only.
  const int n = static_cast<int>(m_candidates.size());
  m_order.resize(static_cast<size_t>(n));
  for (int i = 0; i < n; ++i) {
    m_order[static_cast<size_t>(i)] = i;
  }
  uint64_t state = 0x5EEDull ^ (static_cast<uint64_t>(seed) << 32);
  for (int i = 0; i < count; ++i) {
    const int j = i + static_cast<int>(nextRandom(state) % static_cast<uint64_t>(n - i));
    std::swap(m_order[static_cast<size_t>(i)], m_order[static_cast<size_t>(j)]);
  }
  // Keep the chosen ones in their (row-major) order: mark them in place.
  for (int i = count; i < n; ++i) {
    m_candidates[static_cast<size_t>(m_order[static_cast<size_t>(i)])].level = -1;
  }
  m_candidates.erase(
      std::remove_if(m_candidates.begin(), m_candidates.end(), [](const SelectedPixel &p) { return p.level < 0; }),
      m_candidates.end());
}

int PixelSelector::select(const ImagePyramid &pyramid, int desiredCount, unsigned int seed,
                          std::vector<SelectedPixel> &selected, const OccupancyGrid *occupied)
{
  if (pyramid.numLevels() < 1) {
    throwInvalid(__LINE__, "the pyramid is empty (build it first)");
  }
  const PyramidLevel &l0 = pyramid.level(0);
  if (occupied && (occupied->width() != l0.width || occupied->height() != l0.height)) {
    std::ostringstream os;
    os << "occupancy grid of " << occupied->width() << "x" << occupied->height() << " pixels for an image of "
       << l0.width << "x" << l0.height;
    throwInvalid(__LINE__, os.str());
  }
  selected.clear();
  computeThresholds(l0);
  m_lastCandidates = 0;
  m_lastRuns = 0;
  const int wanted = desiredCount - (occupied ? occupied->markedPoints() : 0);
  if (wanted <= 0) {
    return 0;
  }
  if (occupied) {
    m_occColOf.resize(static_cast<size_t>(l0.width));
    for (int x = 0; x < l0.width; ++x) {
      m_occColOf[static_cast<size_t>(x)] = x / occupied->cellSize();
    }
  }

  int potential = m_potential;
  int ideal = potential;
  int found = 0;
  for (int run = 0;; ++run) {
    found = selectOnce(pyramid, potential, seed, occupied);
    m_lastRuns = run + 1;
    if (found == 0) {
      ideal = potential;
      break;
    }
    // DSO: found ~ K / (d + 1)^2, so the d giving `wanted` is sqrt(K / wanted) - 1 (rounded down).
    const float quotient = static_cast<float>(wanted) / static_cast<float>(found);
    const float K = static_cast<float>(found) * static_cast<float>((potential + 1) * (potential + 1));
    ideal = std::max(1, static_cast<int>(std::sqrt(K / static_cast<float>(wanted)) - 1.f));
    if (run < kMaxReruns && quotient > kTooFewRatio && potential > 1) {
      potential = std::min(ideal, potential - 1);
      continue;
    }
    if (run < kMaxReruns && quotient < kTooManyRatio) {
      potential = std::max(ideal, potential + 1);
      continue;
    }
    break;
  }
  m_potential = ideal;
  m_lastCandidates = found;

  std::sort(m_candidates.begin(), m_candidates.end(),
            [](const SelectedPixel &a, const SelectedPixel &b) { return a.v != b.v ? a.v < b.v : a.u < b.u; });
  if (found > wanted) {
    subsample(wanted, seed);
  }
  selected.assign(m_candidates.begin(), m_candidates.end());
  return static_cast<int>(selected.size());
}
} // namespace hslam
