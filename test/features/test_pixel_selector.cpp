// PixelSelector on a rendered synthetic frame and on a real 7-Scenes frame: count near the target, every pick
// above its block threshold, spatial coverage, determinism, occupancy mask, flat and tiny images.
#include "HSlamTestData.h"

#include "features/ImagePyramid.h"
#include "features/PixelSelector.h"

#include <visp3/hslam/vpHSlamException.h>
#include <visp3/hslam/vpHSlamSyntheticScene.h>
#include <visp3/io/vpImageIo.h>

#include <cstdlib>
#include <set>
#include <utility>

namespace
{
constexpr int kMaxLevels = 6;
constexpr int kMinCoarsestPixels = 5000;
constexpr double kCountTolerance = 0.15;   // |found - target| / target
constexpr double kMinCoverage = 0.95;      // textured 32x32 blocks that get at least one point (target 1500)
constexpr double kTexturedFraction = 0.02; // a block is "textured" when this fraction of it passes the threshold
const int kTargets[] = {500, 1500, 2000};

const char *const kRealFrame = "7scenes_redkitchen_000-299/rgb/000000.jpg";

hslam::ImagePyramid pyramidOf(const vpImage<unsigned char> &I)
{
  hslam::ImagePyramid pyr;
  const double w = I.getWidth(), h = I.getHeight();
  pyr.build(I, hslam::PinholeIntrinsics{0.8 * w, 0.8 * w, 0.5 * w - 0.5, 0.5 * h - 0.5}, kMaxLevels,
            kMinCoarsestPixels);
  return pyr;
}

// One rendered frame of the synthetic room, shared by the tests (rendering costs about a second).
const hslam::ImagePyramid *syntheticPyramid()
{
  static const hslam::ImagePyramid *pyr = []() -> const hslam::ImagePyramid * {
    if (hslam_test::vispImagesDir().empty()) {
      return nullptr;
    }
    vpHSlamSyntheticScene scene;
    scene.configure(640, 480, 30, 30.0, 7);
    vpImage<unsigned char> I;
    scene.render(3, I);
    return new hslam::ImagePyramid(pyramidOf(I));
  }();
  return pyr;
}

const hslam::ImagePyramid *realPyramid()
{
  static const hslam::ImagePyramid *pyr = []() -> const hslam::ImagePyramid * {
    const std::string path = hslam_test::sharedData(kRealFrame);
    if (path.empty()) {
      return nullptr;
    }
    vpImage<unsigned char> I;
    vpImageIo::read(I, path);
    return new hslam::ImagePyramid(pyramidOf(I));
  }();
  return pyr;
}

#define REQUIRE_SYNTHETIC(var)                                                                                         \
  const hslam::ImagePyramid *var = syntheticPyramid();                                                                 \
  if (!var) {                                                                                                          \
    GTEST_SKIP() << "ViSP image data (visp-images-data) not found: no synthetic textures";                             \
  }

void expectCountsNearTargets(const hslam::ImagePyramid &pyr, const char *what)
{
  const vpHSlamParameters::Features params;
  for (int target : kTargets) {
    hslam::PixelSelector selector(params);
    std::vector<hslam::SelectedPixel> pixels;
    const int n = selector.select(pyr, target, 1, pixels);
    EXPECT_EQ(n, static_cast<int>(pixels.size()));
    EXPECT_LE(std::abs(n - target), kCountTolerance * target)
        << what << ": target " << target << ", found " << n << " (candidates " << selector.lastCandidateCount()
        << ", runs " << selector.lastRunCount() << ", d " << selector.potential() << ")";
  }
  // A selector kept across frames (its block size carried over) also meets the targets, in any order.
  hslam::PixelSelector selector(params);
  std::vector<hslam::SelectedPixel> pixels;
  for (int target : {2000, 500, 1500, 500, 2000}) {
    const int n = selector.select(pyr, target, 2, pixels);
    EXPECT_LE(std::abs(n - target), kCountTolerance * target) << what << ": sequence, target " << target;
  }
}

void expectAboveThresholds(const hslam::ImagePyramid &pyr, const char *what)
{
  const vpHSlamParameters::Features params;
  hslam::PixelSelector selector(params);
  std::vector<hslam::SelectedPixel> pixels;
  selector.select(pyr, 1500, 3, pixels);
  ASSERT_FALSE(pixels.empty());
  const hslam::PyramidLevel &l0 = pyr.level(0);
  int below = 0, outside = 0, perLevel[3] = {0, 0, 0};
  std::set<std::pair<int, int>> unique;
  for (const hslam::SelectedPixel &p : pixels) {
    ASSERT_GE(p.level, 0);
    ASSERT_LE(p.level, 2);
    ++perLevel[p.level];
    unique.insert({p.u, p.v});
    if (p.u < 4 || p.v < 4 || p.u >= l0.width - 4 || p.v >= l0.height - 4) {
      ++outside;
      continue;
    }
    const hslam::PyramidLevel &L = pyr.level(p.level);
    const float g = L.gradSq[static_cast<size_t>((p.v >> p.level) * L.width + (p.u >> p.level))];
    const float th = selector.squaredThresholdAt(p.u, p.v) * selector.levelThresholdFactor(p.level);
    // The threshold is at least (0 + gradientThresholdAdd)^2 * factor: never trivially zero.
    EXPECT_GE(selector.squaredThresholdAt(p.u, p.v), params.gradientThresholdAdd * params.gradientThresholdAdd);
    if (!(g > th)) {
      ++below;
    }
  }
  EXPECT_EQ(below, 0) << what;
  EXPECT_EQ(outside, 0) << what;
  EXPECT_EQ(unique.size(), pixels.size()) << what << ": a pixel selected twice";
  EXPECT_GT(perLevel[0], 0) << what;
}

void expectCoverage(const hslam::ImagePyramid &pyr, const char *what)
{
  const vpHSlamParameters::Features params;
  hslam::PixelSelector selector(params);
  std::vector<hslam::SelectedPixel> pixels;
  selector.select(pyr, 1500, 4, pixels);
  const hslam::PyramidLevel &l0 = pyr.level(0);
  const int bs = params.selectionBlockSize;
  const int cols = l0.width / bs, rows = l0.height / bs;
  std::vector<int> points(static_cast<size_t>(cols * rows), 0);
  for (const hslam::SelectedPixel &p : pixels) {
    if (p.u / bs < cols && p.v / bs < rows) {
      ++points[static_cast<size_t>((p.v / bs) * cols + p.u / bs)];
    }
  }
  int textured = 0, covered = 0;
  for (int by = 0; by < rows; ++by) {
    for (int bx = 0; bx < cols; ++bx) {
      int above = 0;
      for (int y = std::max(4, by * bs); y < std::min(l0.height - 4, (by + 1) * bs); ++y) {
        for (int x = std::max(4, bx * bs); x < std::min(l0.width - 4, (bx + 1) * bs); ++x) {
          above += l0.gradSq[static_cast<size_t>(y * l0.width + x)] > selector.squaredThresholdAt(x, y);
        }
      }
      if (above >= kTexturedFraction * bs * bs) {
        ++textured;
        covered += points[static_cast<size_t>(by * cols + bx)] > 0;
      }
    }
  }
  ASSERT_GT(textured, 0) << what;
  EXPECT_GE(static_cast<double>(covered) / textured, kMinCoverage)
      << what << ": " << covered << " of " << textured << " textured blocks have a point";
}
} // namespace

TEST(PixelSelector, CountNearTargetSynthetic)
{
  REQUIRE_SYNTHETIC(pyr);
  expectCountsNearTargets(*pyr, "synthetic");
}

TEST(PixelSelector, CountNearTargetReal)
{
  HSLAM_REQUIRE_SHARED_DATA(path, kRealFrame);
  expectCountsNearTargets(*realPyramid(), path.c_str());
}

TEST(PixelSelector, SelectedPixelsAboveBlockThreshold)
{
  REQUIRE_SYNTHETIC(pyr);
  expectAboveThresholds(*pyr, "synthetic");
  if (realPyramid()) {
    expectAboveThresholds(*realPyramid(), "7scenes");
  }
}

TEST(PixelSelector, SpatialCoverage)
{
  REQUIRE_SYNTHETIC(pyr);
  expectCoverage(*pyr, "synthetic");
  if (realPyramid()) {
    expectCoverage(*realPyramid(), "7scenes");
  }
}

TEST(PixelSelector, Deterministic)
{
  REQUIRE_SYNTHETIC(pyr);
  const vpHSlamParameters::Features params;
  hslam::PixelSelector a(params), b(params);
  std::vector<hslam::SelectedPixel> pa, pb, pc;
  for (int frame = 0; frame < 3; ++frame) {
    a.select(*pyr, 1500, static_cast<unsigned int>(frame), pa);
    b.select(*pyr, 1500, static_cast<unsigned int>(frame), pb);
    ASSERT_EQ(pa.size(), pb.size());
    int differ = 0;
    for (size_t i = 0; i < pa.size(); ++i) {
      differ += pa[i].u != pb[i].u || pa[i].v != pb[i].v || pa[i].level != pb[i].level;
    }
    EXPECT_EQ(differ, 0) << "frame " << frame;
  }
  // Another seed picks (partly) other pixels.
  hslam::PixelSelector c(params);
  c.select(*pyr, 1500, 12345u, pc);
  std::set<std::pair<int, int>> sa;
  for (const auto &p : pa) {
    sa.insert({p.u, p.v});
  }
  int shared = 0;
  for (const auto &p : pc) {
    shared += static_cast<int>(sa.count({p.u, p.v}));
  }
  EXPECT_LT(shared, static_cast<int>(pc.size()));
}

TEST(PixelSelector, OccupancyMaskRespected)
{
  REQUIRE_SYNTHETIC(pyr);
  const vpHSlamParameters::Features params;
  const hslam::PyramidLevel &l0 = pyr->level(0);
  const int cell = 16, corners = 300, target = 1500;
  hslam::OccupancyGrid grid;
  grid.reset(l0.width, l0.height, cell);
  // Corners on a coarse lattice, two per marked cell (cells in every third column and row).
  int marked = 0;
  for (int y = 8; y < l0.height && marked < corners; y += 3 * cell) {
    for (int x = 8; x < l0.width && marked < corners; x += 3 * cell) {
      grid.markPoint(static_cast<float>(x), static_cast<float>(y));
      grid.markPoint(static_cast<float>(x + 2), static_cast<float>(y + 1));
      marked += 2;
    }
  }
  ASSERT_EQ(grid.markedPoints(), marked);
  hslam::PixelSelector selector(params);
  std::vector<hslam::SelectedPixel> pixels;
  const int n = selector.select(*pyr, target, 5, pixels, &grid);
  int inOccupied = 0;
  for (const auto &p : pixels) {
    inOccupied += grid.isOccupied(p.u, p.v);
  }
  EXPECT_EQ(inOccupied, 0);
  const int wanted = target - marked;
  EXPECT_LE(std::abs(n - wanted), kCountTolerance * wanted) << "found " << n << " for " << wanted;
  // Corners fill the whole target: nothing selected.
  hslam::OccupancyGrid full;
  full.reset(l0.width, l0.height, cell);
  for (int i = 0; i < 100; ++i) {
    full.markPoint(static_cast<float>(i), 10.f);
  }
  EXPECT_EQ(selector.select(*pyr, 100, 5, pixels, &full), 0);
  EXPECT_TRUE(pixels.empty());
  // A grid of the wrong size is refused.
  hslam::OccupancyGrid wrong;
  wrong.reset(320, 240, cell);
  EXPECT_THROW(selector.select(*pyr, target, 5, pixels, &wrong), vpHSlamException);
}

TEST(PixelSelector, FlatAndTinyImages)
{
  const vpHSlamParameters::Features params;
  hslam::PixelSelector selector(params);
  std::vector<hslam::SelectedPixel> pixels;
  vpImage<unsigned char> flat(480, 640, 128);
  EXPECT_EQ(selector.select(pyramidOf(flat), 1500, 0, pixels), 0);
  EXPECT_TRUE(pixels.empty());
  // Smaller than a threshold block and than the border: no crash, nothing selected inside the border.
  vpImage<unsigned char> tiny(6, 7);
  for (unsigned int i = 0; i < tiny.getSize(); ++i) {
    tiny.bitmap[i] = static_cast<unsigned char>((i * 97u) % 256u);
  }
  EXPECT_EQ(selector.select(pyramidOf(tiny), 1500, 0, pixels), 0);
  // Odd size (KITTI), random texture: finds points, all inside the image.
  vpImage<unsigned char> kitti(370, 1226);
  for (unsigned int i = 0; i < kitti.getSize(); ++i) {
    kitti.bitmap[i] = static_cast<unsigned char>((i * 2654435761u) >> 24);
  }
  const int n = selector.select(pyramidOf(kitti), 2000, 0, pixels);
  EXPECT_LE(std::abs(n - 2000), kCountTolerance * 2000);
  for (const auto &p : pixels) {
    ASSERT_LT(p.u, 1226 - 4);
    ASSERT_LT(p.v, 370 - 4);
  }
  vpHSlamParameters::Features bad;
  bad.selectionBlockSize = 0;
  EXPECT_THROW(hslam::PixelSelector{bad}, vpHSlamException);
  bad = vpHSlamParameters::Features();
  bad.selectionLevels = 4;
  EXPECT_THROW(hslam::PixelSelector{bad}, vpHSlamException);
}
